"""Combinatorial localization filters for a bouncing robot with a bump sensor and a clock.

Alam, Bobadilla & Shell, "Space-efficient filters for mobile robot localization from discrete
limit cycles", IEEE RA-L 3(1), 2018 (thesis Ch. 2): Sec. III-B (cell mapping, Defs. 1–4), Sec. IV
(Algorithm 1 and Defs. 5–9). Where the paper is open, the choices are those of docs/choices/localization.md,
cited below by heading.

The pipeline after the simple cell mapping (SCM) ``C`` (successor array) and its observation labels
(``bump``; 1 = bump tick, 0 = forward tick):

* **I-state graphs** (Def. 5): the functional graph ``z -> C(z)`` with edge label
  ``ℓ(z, C(z)) = bump[z]`` (label 1 iff the orientation bin changes, i.e. the robot bumped and
  rotated in place: docs/choices/cell_model.md, "Observation 1 means the orientation bin changed").
  `istate_graph` builds one networkx graph for all cells or for one periodic group, `istate_graphs`
  one per group (the "octopus" graphs of Algorithm 1).
* **Nondeterministic I-state automaton** (Def. 6): ``N + 1`` states, ``q0`` with ε-moves to every
  cell and exactly one labelled out-edge per cell. It is kept implicit in the two arrays;
  `IStateNFA` spells out δ and the ε-closure for checking, and ``nfa_size == N + 1``.
* **DFA by lazy subset construction** (Def. 7, Sec. IV-C): `build_dfa`. A state is the set
  of cells consistent with everything observed (stored as a sorted int array); the start state is
  all ``N`` cells (``q0`` itself is omitted); a missing transition goes to the implicit trap,
  which is not counted in `DFA.n_states` (`DFA.n_states_with_trap` counts it; docs/choices/localization.md,
  "DFA size: the start state is all cells, the trap is not counted").
  Prop. 1: ``|Q'| = O(N²)``; out-degree ≤ 2.
* **Knowledge cycles**: the strongly connected components of the DFA graph with more than one
  state or a self-loop (a rotation pocket emits 1, 1, 1, …). Each is a simple cycle, every state in
  it has the same ``|S|`` (the cycle's *uncertainty*) and is a subset of the periodic cells.
* **Colours** (Def. 8/9; docs/choices/localization.md, "Knowledge-cycle colours and numbering"): colour 1 for
  every state outside a knowledge cycle; cycles numbered 2 … m + 1 in order of their smallest cell
  id; the trap (open world) m + 2.
* **Filters**: `LocalizationFilter` — closed world (Def. 8, Problem 1: an impossible observation
  raises `ImpossibleObservationError`) or open world (Def. 9, Problem 2: it goes to the absorbing
  trap, "not in E"). One DFA table lookup per observation (Table III: O(1) per update).
* **Identification among worlds** (Sec. IV-D): `WorldIdentifier` runs one open-world filter per
  candidate world; a world is ruled out once its filter is trapped.

Beyond the paper (its Sec. VI future work: switching φ to shrink the uncertainty):

* `ActiveLocalizationFilter` — the robot may change its bounce angle at every bump; the filter keeps
  the candidate set ``S`` and applies ``S' = {c_φ(z) : z ∈ S, obs(z) = symbol}`` with the
  successor array of the angle φ used (O(|S|) per update).
* `AngleSwitchPlanner` — a reference policy choosing the angle at a bump that minimises the
  worst-case candidate-set size after the next segment(s) (minimax over the observation outcomes,
  a segment = rotate, then drive until the next bump; the outcome is the number of 0s).
* `BeliefLocalizationPolicy` — on the sampled GCM of a continuous env (issue 24): a histogram
  filter over decision states (`bounce_gym.markov.belief`) and, at every bump, the angle of least
  expected posterior entropy; the claim is the task's ("belief" filter).
* `ParticleLocalizationPolicy` — on a particle belief moved by the env's own dynamics
  (`bounce_gym.dynamics.particles`, Monte Carlo localization): the angle of least expected
  posterior entropy; the claim is the task's ("particles" filter).
* `build_policy_dfa` — the closed-loop subset automaton of a planner, so the planner's localization
  limits can be compared exactly with the fixed-angle DFAs (`final_uncertainties`).

The SCM arrays come from `bounce_gym.cells.CellModel.successor`, which implements the choices of
docs/choices/cell_model.md (a bump rotates in place and emits 1, reset to the cell centre every step, free
target cell, king step with the symmetric tie rule, bins centred at k·360°/N_S); here nothing
depends on the cell iteration order ("Algorithm 1's index errors and order independence"). Cell
numbering is the model's (0-based ``z = k·N_pos + p``; the papers' ids are ``z + 1``). Angles are in
radians, as everywhere inside the package.
"""


from baselines.localization.belief_policy import BeliefLocalizationPolicy
from baselines.localization.particle_policy import ParticleLocalizationPolicy
from baselines.localization.planner import (
    AngleSwitchPlanner,
    build_policy_dfa,
    final_uncertainties,
)
from baselines.localization.policy import AngleSwitchPolicy

__all__ = ["AngleSwitchPlanner", "BeliefLocalizationPolicy", "AngleSwitchPolicy",
           "ParticleLocalizationPolicy", "build_policy_dfa", "final_uncertainties"]
