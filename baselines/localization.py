"""Combinatorial localization filters for a bouncing robot with a bump sensor and a clock.

Alam, Bobadilla & Shell, "Space-efficient filters for mobile robot localization from discrete
limit cycles", IEEE RA-L 3(1), 2018 (thesis Ch. 2); spec ``001_localization_filters.md`` and
``003a_thesis_ch1-3.md`` §2–3 give the definitions and the resolutions (G1–G13) cited below.

The pipeline after the simple cell mapping (SCM) ``C`` (successor array) and its observation labels
(``bump``; 1 = bump tick, 0 = forward tick):

* **I-state graphs** (Def. 5): the functional graph ``z -> C(z)`` with edge label
  ``ℓ(z, C(z)) = bump[z]`` (G7: label 1 iff the orientation bin changes, i.e. the robot bumped and
  rotated in place, G1). `istate_graph` builds one networkx graph for all cells or for one periodic
  group, `istate_graphs` one per group (the "octopus" graphs of Algorithm 1).
* **Nondeterministic I-state automaton** (Def. 6): ``N + 1`` states, ``q0`` with ε-moves to every
  cell and exactly one labelled out-edge per cell. It is kept implicit in the two arrays;
  `IStateNFA` spells out δ and the ε-closure for checking, and ``nfa_size == N + 1``.
* **DFA by lazy subset construction** (Def. 7, spec §4 pseudo-code): `build_dfa`. A state is the set
  of cells consistent with everything observed (stored as a sorted int array); the start state is
  all ``N`` cells (G8: ``q0`` itself is omitted); a missing transition goes to the implicit trap,
  which is not counted in `DFA.n_states` (G8; `DFA.n_states_with_trap` counts it).
  Prop. 1: ``|Q'| = O(N²)``; out-degree ≤ 2.
* **Knowledge cycles**: the strongly connected components of the DFA graph with more than one
  state or a self-loop (a rotation pocket emits 1, 1, 1, …). Each is a simple cycle, every state in
  it has the same ``|S|`` (the cycle's *uncertainty*) and is a subset of the periodic cells.
* **Colours** (Def. 8/9, G9): colour 1 for every state outside a knowledge cycle; cycles numbered
  2 … m + 1 in order of their smallest cell id; the trap (open world) m + 2.
* **Filters**: `LocalizationFilter` — closed world (Def. 8, Problem 1: an impossible observation
  raises `ImpossibleObservationError`) or open world (Def. 9, Problem 2: it goes to the absorbing
  trap, "not in E"). One DFA table lookup per observation (Table III: O(1) per update).
* **Identification among worlds** (Sec. IV-D): `WorldIdentifier` runs one open-world filter per
  candidate world; a world is ruled out once its filter is trapped.

Beyond the paper (its future work, spec §6 "switching φ to shrink the uncertainty"):

* `ActiveLocalizationFilter` — the robot may change its bounce angle at every bump; the filter keeps
  the candidate set ``S`` and applies ``S' = {c_φ(z) : z ∈ S, obs(z) = symbol}`` with the
  successor array of the angle φ used (O(|S|) per update).
* `AngleSwitchPlanner` — a reference policy choosing the angle at a bump that minimises the
  worst-case candidate-set size after the next segment(s) (minimax over the observation outcomes,
  a segment = rotate, then drive until the next bump; the outcome is the number of 0s).
* `build_policy_dfa` — the closed-loop subset automaton of a planner, so the planner's localization
  limits can be compared exactly with the fixed-angle DFAs (`final_uncertainties`).

The SCM arrays come from `bounce_gym.cells.CellModel.successor`, which implements the resolutions
G1 (a bump rotates in place and emits 1), G2 (reset to the cell centre every step), G4–G6 (free
target cell, king step with the symmetric tie rule, bins centred at k·360°/N_S); here nothing
depends on the cell iteration order (G3). Cell numbering is the model's (0-based
``z = k·N_pos + p``; the papers' ids are ``z + 1``). Angles are in radians, as everywhere inside
the package.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import networkx as nx
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from baselines.policy import Policy
from bounce_gym.cells import CellModel
from bounce_gym.errors import BounceGymError, ConfigError
from bounce_gym.worlds import World
from bounce_gym.worlds import get as get_world

__all__ = [
    "DFA",
    "TRAP",
    "ActiveLocalizationFilter",
    "AngleSwitchPlanner",
    "IStateNFA",
    "ImpossibleObservationError",
    "LocalizationFilter",
    "ObservationError",
    "WorldIdentifier",
    "build_dfa",
    "build_policy_dfa",
    "final_uncertainties",
    "future_classes",
    "istate_graph",
    "istate_graphs",
    "periodic_cells",
    "periodic_groups",
]

TRAP = -1
"""State index of the implicit trap state (Def. 9); `DFA.delta` holds it for missing transitions."""

_SYMBOLS = {0: 0, 1: 1}  # also matches False/True and numpy integers/bools (equal hash and value)


class ObservationError(BounceGymError):
    """An observation symbol is not 0 (forward tick) or 1 (bump tick)."""


class ImpossibleObservationError(ObservationError):
    """A closed-world filter received an observation string no cell of its world can produce.

    Problem 1 assumes the robot is inside E, so this cannot happen with noise-free observations
    from that world; use ``open_world=True`` (Def. 9) to detect "not in E" instead.
    """


def _symbol(symbol) -> int:
    try:
        return _SYMBOLS[symbol]
    except (KeyError, TypeError):
        raise ObservationError(
            f"symbol: expected 0 (forward tick) or 1 (bump tick), got {symbol!r}") from None


# -- the SCM as arrays ---------------------------------------------------------------------------

def _check_scm(successor, bump) -> tuple[np.ndarray, np.ndarray]:
    succ = np.asarray(successor)
    obs = np.asarray(bump)
    if succ.ndim != 1 or succ.size == 0 or not np.issubdtype(succ.dtype, np.integer):
        raise ConfigError(f"successor: expected a non-empty 1-D integer array, got shape "
                          f"{succ.shape} and dtype {succ.dtype}")
    if obs.shape != succ.shape:
        raise ConfigError(f"bump: expected shape {succ.shape} like successor, got {obs.shape}")
    if obs.dtype != bool:
        if not np.isin(obs, (0, 1)).all():
            raise ConfigError("bump: expected booleans or 0/1 (1 = bump tick)")
        obs = obs.astype(bool)
    n = succ.size
    if succ.min() < 0 or succ.max() >= n:
        raise ConfigError(f"successor: every entry must be a cell id in [0, {n})")
    return succ.astype(np.int64, copy=False), obs


def _graph_matrix(succ: np.ndarray) -> coo_matrix:
    n = succ.size
    return coo_matrix((np.ones(n, dtype=np.int8), (np.arange(n), succ)), shape=(n, n))


def periodic_cells(successor) -> np.ndarray:
    """Boolean mask of the periodic cells (Def. 1: ``z = C^m(z)`` for some m ≥ 1).

    The SCM graph is functional, so the periodic cells are exactly the cells on its cycles: the
    strongly connected components with more than one cell, plus fixed points.
    """
    succ = np.asarray(successor, dtype=np.int64)
    _, labels = connected_components(_graph_matrix(succ), directed=True, connection="strong")
    counts = np.bincount(labels)
    return (counts[labels] > 1) | (succ == np.arange(succ.size))


def periodic_groups(successor) -> tuple[np.ndarray, int]:
    """Group number of every cell and the number r of periodic groups (Def. 3, Def. 4).

    Each weakly connected component of the functional graph holds exactly one periodic group (its
    cycle) and that group's transient trajectories. Groups are numbered 0 … r − 1 in order of
    their smallest cell id, which is the order Algorithm 1 discovers them in (spec G3).
    """
    succ = np.asarray(successor, dtype=np.int64)
    r, labels = connected_components(_graph_matrix(succ), directed=True, connection="weak")
    _, first = np.unique(labels, return_index=True)
    rank = np.empty(r, dtype=np.int64)
    rank[np.argsort(first)] = np.arange(r)
    return rank[labels], int(r)


def future_classes(successor, bump) -> np.ndarray:
    """Coarsest partition of the cells into classes with identical future observation strings.

    Moore's partition refinement on the labelled functional graph: start from the label classes
    and split by the class of the successor until stable. Two cells of one class can never be told
    apart by any further observation (the cell-level counterpart of a knowledge cycle).
    """
    succ, obs = _check_scm(successor, bump)
    cls = obs.astype(np.int64)
    count = int(np.unique(cls).size)
    while True:
        _, new = np.unique(cls * (count + 1) + cls[succ], return_inverse=True)
        new = new.reshape(-1).astype(np.int64)
        new_count = int(new.max()) + 1
        if new_count == count:
            return new
        cls, count = new, new_count


# -- I-state graphs (Def. 5) and the nondeterministic automaton (Def. 6) -------------------------

def istate_graph(successor, bump, group: int | None = None) -> nx.DiGraph:
    """The I-state graph with 0/1 edge labels (Def. 5; BUILD-STATEGRAPH of Algorithm 1).

    Vertices are cells (node attributes ``periodic`` and ``group``), edges ``(z, C(z))`` with the
    attribute ``label`` = 1 for a bump tick, 0 for a forward tick (G7). Without ``group`` the graph
    holds all N cells (the disjoint union of the groups' graphs, ``|G.V| = N``); with ``group = j``
    only periodic group j (numbered as in `periodic_groups`) and its transient trajectories.
    """
    succ, obs = _check_scm(successor, bump)
    periodic = periodic_cells(succ)
    groups, r = periodic_groups(succ)
    cells = np.arange(succ.size)
    if group is not None:
        if isinstance(group, bool) or not isinstance(group, int | np.integer) \
                or not 0 <= group < r:
            raise ConfigError(f"group: expected an integer in [0, {r}), got {group!r}")
        cells = cells[groups == group]
    graph = nx.DiGraph(group=group, n_groups=r)
    graph.add_nodes_from((int(z), {"periodic": bool(periodic[z]), "group": int(groups[z])})
                         for z in cells)
    graph.add_edges_from((int(z), int(succ[z]), {"label": int(obs[z])}) for z in cells)
    if group is not None:
        graph.graph["period"] = int(periodic[cells].sum())
    return graph


def istate_graphs(successor, bump) -> list[nx.DiGraph]:
    """One I-state graph per periodic group, G = {G_1 … G_r} as returned by Algorithm 1."""
    _, r = periodic_groups(np.asarray(successor, dtype=np.int64))
    return [istate_graph(successor, bump, group=j) for j in range(r)]


@dataclass(frozen=True)
class IStateNFA:
    """The nondeterministic I-state automaton A = (Q, Σ_ε, δ, q0, F) of Def. 6, kept implicit.

    Q = {q0} ∪ cells (``size == N + 1``); q0 (`START`) has ε-moves to every cell and no labelled
    move; every cell q has exactly one labelled move, to C(q) on ℓ(q, C(q)) (so
    ``|δ(q, 0)| + |δ(q, 1)| = 1``); F = the periodic cells. Nothing returns to q0.
    """

    successor: np.ndarray
    bump: np.ndarray

    START = -1

    @classmethod
    def from_arrays(cls, successor, bump) -> IStateNFA:
        succ, obs = _check_scm(successor, bump)
        return cls(succ, obs)

    @property
    def n_cells(self) -> int:
        return int(self.successor.size)

    @property
    def size(self) -> int:
        """|Q| = N + 1 (Table I, "NFA states")."""
        return self.n_cells + 1

    nfa_size = size

    @property
    def final(self) -> np.ndarray:
        """F = G.V_P, the periodic cells (boolean mask)."""
        return periodic_cells(self.successor)

    def delta(self, q: int, symbol) -> frozenset[int]:
        """δ(q, a) for a labelled symbol a ∈ {0, 1} (the empty set where undefined)."""
        a = _symbol(symbol)
        if q == self.START:
            return frozenset()
        if not 0 <= q < self.n_cells:
            raise ConfigError(f"q: expected START or a cell id in [0, {self.n_cells}), got {q!r}")
        return frozenset({int(self.successor[q])}) if int(self.bump[q]) == a else frozenset()

    def epsilon_closure(self, states: Iterable[int]) -> frozenset[int]:
        """ε-Closure: q0 adds every cell (and itself); cells have no ε-moves."""
        states = frozenset(int(q) for q in states)
        if self.START in states:
            return states | frozenset(range(self.n_cells))
        return states


# -- the DFA (Def. 7) ----------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class DFA:
    """The deterministic I-state automaton A' of Def. 7 with its knowledge cycles and colours.

    Attributes:
        states: the states as sorted cell-id arrays; state 0 is the start state (all N cells, G8).
        delta: (n_states, 2) next state on 0 and on 1; `TRAP` (−1) where the transition is missing.
        n_cells: N.
        periodic: periodic cells of the SCM (None for a closed-loop `build_policy_dfa`).
        cycles: the knowledge cycles, each the state indices in transition order starting at the
            state holding the cycle's smallest cell id; numbered by (smallest cell id, first state).
        cycle_of: knowledge cycle index of every state, −1 outside the cycles.
        colour: colour of every state (G9): 1 outside the cycles, 2 + cycle index inside.
        bump_angle: for `build_policy_dfa`, the angle (radians) used on a 1 in every state
            (NaN where a 1 is impossible); None for a fixed-angle DFA.
        bump_angle_index: the same as an index into the planner's angles (−1 where impossible).
    """

    states: tuple[np.ndarray, ...]
    delta: np.ndarray
    n_cells: int
    periodic: np.ndarray | None
    cycles: tuple[np.ndarray, ...]
    cycle_of: np.ndarray
    colour: np.ndarray
    bump_angle: np.ndarray | None = None
    bump_angle_index: np.ndarray | None = None
    _index: dict = field(default_factory=dict, repr=False)

    start = 0

    # -- sizes and bookkeeping (G8) --
    @property
    def n_states(self) -> int:
        """|Q'| without the implicit trap (the count reported next to Table I)."""
        return len(self.states)

    @property
    def has_trap(self) -> bool:
        """Whether some transition is missing, i.e. the open-world trap q_t is reachable."""
        return bool((self.delta == TRAP).any())

    @property
    def n_states_with_trap(self) -> int:
        """|Q'| counting the trap state q_t when some transition leads to it (G8)."""
        return self.n_states + int(self.has_trap)

    @property
    def nfa_size(self) -> int:
        """|Q| = N + 1 of the nondeterministic automaton it was built from (Def. 6)."""
        return self.n_cells + 1

    @property
    def sizes(self) -> np.ndarray:
        """|S| of every state."""
        return np.array([s.size for s in self.states], dtype=np.int64)

    @property
    def final(self) -> np.ndarray | None:
        """F' = {S : S ∩ F ≠ ∅} as a boolean mask over states (kept for completeness, G10)."""
        if self.periodic is None:
            return None
        return np.array([bool(self.periodic[s].any()) for s in self.states])

    @property
    def out_degree(self) -> np.ndarray:
        return (self.delta != TRAP).sum(axis=1)

    # -- knowledge cycles and colours (G9) --
    @property
    def n_cycles(self) -> int:
        return len(self.cycles)

    @property
    def cycle_lengths(self) -> tuple[int, ...]:
        return tuple(len(c) for c in self.cycles)

    @property
    def uncertainties(self) -> tuple[int, ...]:
        """|S| of every knowledge cycle (the number of candidate configurations, Table II)."""
        return tuple(int(self.states[c[0]].size) for c in self.cycles)

    @property
    def min_uncertainty(self) -> int:
        """The "strongest possible localization" (Table II minimum)."""
        return min(self.uncertainties)

    @property
    def max_uncertainty(self) -> int:
        """The weakest localization a run can end with (Table II maximum)."""
        return max(self.uncertainties)

    @property
    def trap_colour(self) -> int:
        """Colour of the open-world trap q_t: #cycles + 2 (G9)."""
        return self.n_cycles + 2

    def n_colours(self, open_world: bool = False) -> int:
        """Colours the filter uses: white + one per cycle (+ the trap in the open world)."""
        return self.n_cycles + 1 + int(open_world)

    # -- use --
    def step(self, state: int, symbol) -> int:
        """δ'(state, symbol); `TRAP` is absorbing."""
        if state == TRAP:
            return TRAP
        return int(self.delta[state, _symbol(symbol)])

    def run(self, symbols: Iterable, state: int = 0) -> int:
        """The state after reading ``symbols`` from ``state`` (`TRAP` if impossible)."""
        for a in symbols:
            state = self.step(state, a)
        return state

    def state_of(self, cells) -> int | None:
        """Index of the state whose cell set is ``cells``, or None if it is not a state."""
        key = np.unique(np.asarray(cells, dtype=np.int64)).tobytes()
        return self._index.get(key)

    def graph(self, with_trap: bool = False) -> nx.DiGraph:
        """The DFA as a networkx graph: nodes carry ``size`` and ``colour``, edges ``label``.

        With ``with_trap`` the trap is node `TRAP` with a self-loop on 0 and 1 (Def. 9). A
        DiGraph keeps one edge per pair, so an edge taken on both symbols has ``label = (0, 1)``.
        """
        graph = nx.DiGraph()
        graph.add_nodes_from((i, {"size": int(s.size), "colour": int(self.colour[i])})
                             for i, s in enumerate(self.states))
        edges = [(int(i), int(self.delta[i, a]), a) for i in range(self.n_states) for a in (0, 1)
                 if self.delta[i, a] != TRAP or with_trap]
        for src, dst, a in edges:
            if graph.has_edge(src, dst):  # both symbols lead to the same state (e.g. the trap)
                graph.edges[src, dst]["label"] = (0, 1)
            else:
                graph.add_edge(src, dst, label=a)
        if with_trap and self.has_trap:
            graph.nodes[TRAP].update(size=0, colour=self.trap_colour)
            graph.add_edge(TRAP, TRAP, label=(0, 1))
        return graph

    def summary(self) -> dict:
        """Plain numbers for tables: NFA/DFA sizes, cycles, uncertainties and colours."""
        return {
            "nfa_states": self.nfa_size,
            "dfa_states": self.n_states,
            "dfa_states_with_trap": self.n_states_with_trap,
            "knowledge_cycles": self.n_cycles,
            "cycle_lengths": self.cycle_lengths,
            "uncertainties": self.uncertainties,
            "min_uncertainty": self.min_uncertainty,
            "max_uncertainty": self.max_uncertainty,
        }


def _subset_construction(n_cells: int, image: Callable[[np.ndarray, int], np.ndarray],
                         max_states: int | None):
    """Lazy (reachable-only) subset construction from the set of all cells (spec §4 pseudo-code).

    ``image(S, a)`` returns the sorted, duplicate-free successor set of S on symbol a.
    """
    start = np.arange(n_cells, dtype=np.int64)
    states = [start]
    index = {start.tobytes(): 0}
    delta: list[tuple[int, int]] = []
    i = 0
    while i < len(states):
        row = [TRAP, TRAP]
        for a in (0, 1):
            nxt = image(states[i], a)
            if nxt.size == 0:
                continue  # the implicit trap
            key = nxt.tobytes()
            j = index.get(key)
            if j is None:
                j = index[key] = len(states)
                states.append(nxt)
                if max_states is not None and len(states) > max_states:
                    raise ConfigError(f"max_states: the DFA exceeds {max_states} states")
            row[a] = j
        delta.append((row[0], row[1]))
        i += 1
    return tuple(states), np.array(delta, dtype=np.int64).reshape(-1, 2), index


def _read_only(arrays: Iterable[np.ndarray]) -> tuple[np.ndarray, ...]:
    out = tuple(arrays)
    for a in out:
        a.flags.writeable = False  # filters hand these out as `candidates`
    return out


def _knowledge_cycles(states: tuple[np.ndarray, ...], delta: np.ndarray):
    """Knowledge cycles = SCCs of the DFA graph with > 1 state or a self-loop (spec §4).

    Every such SCC is a simple cycle: sizes never grow along an edge, so they are constant in an
    SCC, and a state whose two transitions are both defined loses cells on each of them.
    """
    graph = nx.DiGraph()
    graph.add_nodes_from(range(len(states)))
    src, sym = np.nonzero(delta != TRAP)
    graph.add_edges_from(zip(src.tolist(), delta[src, sym].tolist(), strict=True))
    found = []
    for scc in nx.strongly_connected_components(graph):
        members = sorted(scc)
        if len(members) == 1 and not graph.has_edge(members[0], members[0]):
            continue
        smallest = [int(states[s][0]) for s in members]  # states are sorted arrays
        first = members[int(np.argmin(smallest))]  # ties: the lowest state index (argmin's first)
        order = [first]
        nxt = [t for t in graph.successors(first) if t in scc]
        while nxt[0] != first:
            order.append(nxt[0])
            nxt = [t for t in graph.successors(nxt[0]) if t in scc]
        if len(order) != len(members):  # pragma: no cover - excluded by the argument above
            raise AssertionError("a knowledge component is not a simple cycle")
        found.append((min(smallest), first, np.array(order, dtype=np.int64)))
    found.sort(key=lambda item: (item[0], item[1]))
    cycles = tuple(order for _, _, order in found)
    cycle_of = np.full(len(states), -1, dtype=np.int64)
    for k, order in enumerate(cycles):
        cycle_of[order] = k
    colour = np.where(cycle_of >= 0, cycle_of + 2, 1)
    return cycles, cycle_of, colour


def build_dfa(successor, bump, *, max_states: int | None = None) -> DFA:
    """The DFA A' of Def. 7 by lazy subset construction, with knowledge cycles and colours.

    Args:
        successor: the SCM C as an (N,) array of successor cell ids.
        bump: (N,) observation of every cell's tick (True/1 = bump, the label ℓ(z, C(z))).
        max_states: raise `ConfigError` if the DFA grows beyond this many states (Prop. 1 only
            bounds it by O(N²)).

    Per state the image on both symbols is one vectorised gather: S' = sort(C[S[ℓ[S] = a]]),
    de-duplicated (a cell-model SCM is injective on each label class, so nothing merges then).
    """
    succ, obs = _check_scm(successor, bump)
    dtype = np.int32 if succ.size < 2**31 else np.int64

    def image(cells: np.ndarray, a: int) -> np.ndarray:
        out = succ[cells[obs[cells] == bool(a)]]
        out.sort()
        if out.size > 1 and (out[1:] == out[:-1]).any():
            out = np.unique(out)
        return out

    states, delta, index = _subset_construction(succ.size, image, max_states)
    states = _read_only(s.astype(dtype) for s in states)
    cycles, cycle_of, colour = _knowledge_cycles(states, delta)
    return DFA(states=states, delta=delta, n_cells=int(succ.size),
               periodic=periodic_cells(succ), cycles=cycles, cycle_of=cycle_of, colour=colour,
               _index=index)


# -- the filters (Def. 8, Def. 9) ----------------------------------------------------------------

class LocalizationFilter:
    """The closed-world (Def. 8) or open-world (Def. 9) combinatorial localization filter.

    It runs the DFA of `build_dfa`: one table lookup per observation. Protocol (as used by the
    localization task): ``reset()``, ``update(symbol)`` with 1 = bump tick and 0 = forward tick,
    and the attributes ``size`` and ``localized``.

    Attributes (read-only properties):
        state: current DFA state index (`TRAP` once trapped).
        candidates: the cells consistent with every observation so far (sorted ids; empty when
            trapped); valid before convergence too (G9).
        size: ``len(candidates)``; once in a knowledge cycle, the uncertainty.
        colour: 1 outside knowledge cycles, 2 … m + 1 in cycle k, m + 2 in the trap (G9).
        localized: True once in a knowledge cycle (absorbing in the closed world).
        trapped: open world only — the observation string is impossible in this world ("not in
            E"). A closed-world filter raises `ImpossibleObservationError` instead and keeps its
            state.
        steps: the number of observations consumed since `reset`.
    """

    def __init__(self, dfa: DFA, open_world: bool = False, phi: float | None = None) -> None:
        if not isinstance(dfa, DFA):
            raise ConfigError(f"dfa: expected a DFA from build_dfa, got {type(dfa).__name__}")
        self.dfa = dfa
        self.open_world = bool(open_world)
        self.phi = phi  # the bounce angle the DFA was built for (radians), if known
        self._delta = dfa.delta.tolist()  # Python lists: the fastest O(1) lookup per symbol
        self._colour = dfa.colour.tolist()
        self._in_cycle = (dfa.cycle_of >= 0).tolist()
        self.reset()

    @classmethod
    def from_arrays(cls, successor, bump, open_world: bool = False) -> LocalizationFilter:
        return cls(build_dfa(successor, bump), open_world=open_world)

    @classmethod
    def from_model(cls, model: CellModel, phi: float, open_world: bool = False
                   ) -> LocalizationFilter:
        """The filter of a cell model for bounce angle ``phi`` (radians)."""
        return cls(build_dfa(*model.successor(phi)), open_world=open_world, phi=phi)

    @classmethod
    def for_world(cls, world: World | str, phi: float, n_bins: int = 8, cell_size: float = 1.0,
                  robot_radius: float = 0.0, open_world: bool = False,
                  corner_rule: str = "target_only") -> LocalizationFilter:
        """The filter of a world (or zoo name) discretised as in `bounce_gym.cells.CellModel`.

        ``phi`` is the bounce angle in radians (a multiple of 360° / ``n_bins``, G6).
        """
        if isinstance(world, str):
            world = get_world(world)
        model = CellModel(world, cell_size=cell_size, n_bins=n_bins, robot_radius=robot_radius,
                          corner_rule=corner_rule)
        return cls.from_model(model, phi, open_world=open_world)

    def reset(self) -> None:
        """Back to the start state: every cell is a candidate."""
        self._state = self.dfa.start
        self.steps = 0

    def update(self, symbol, angle: float | None = None) -> int:
        """Consume one observation (1 = bump tick, 0 = forward tick); returns the colour.

        ``angle`` (radians), the bounce angle of a bump, is optional; when given it must be the
        angle the filter was built for — a fixed-angle filter cannot follow another one.
        """
        a = _symbol(symbol)
        if angle is not None and self.phi is not None and not math.isclose(
                (angle - self.phi) % (2 * math.pi), 0.0, abs_tol=1e-9) and not math.isclose(
                (angle - self.phi) % (2 * math.pi), 2 * math.pi, abs_tol=1e-9):
            raise ObservationError(
                f"this filter was built for a bounce angle of {math.degrees(self.phi):g}°, "
                f"got {math.degrees(angle):g}°; use ActiveLocalizationFilter for several angles")
        if self._state != TRAP:
            nxt = self._delta[self._state][a]
            if nxt == TRAP and not self.open_world:
                raise ImpossibleObservationError(
                    f"closed-world filter: observation {a} after {self.steps} observations is "
                    f"impossible in this world (no candidate cell emits it); the robot cannot be "
                    f"in this world with these noise-free observations — use open_world=True to "
                    f"detect that")
            self._state = nxt
        self.steps += 1
        return self.colour

    def run(self, symbols: Iterable) -> int:
        """Consume a whole observation string; returns the final colour."""
        for a in symbols:
            self.update(a)
        return self.colour

    @property
    def state(self) -> int:
        return self._state

    @property
    def trapped(self) -> bool:
        return self._state == TRAP

    @property
    def candidates(self) -> np.ndarray:
        if self._state == TRAP:
            return np.empty(0, dtype=np.int64)
        return self.dfa.states[self._state]

    @property
    def size(self) -> int:
        return 0 if self._state == TRAP else int(self.dfa.states[self._state].size)

    @property
    def colour(self) -> int:
        return self.dfa.trap_colour if self._state == TRAP else self._colour[self._state]

    @property
    def localized(self) -> bool:
        return self._state != TRAP and self._in_cycle[self._state]

    @property
    def cycle(self) -> int | None:
        """Index of the current knowledge cycle (colour − 2), or None."""
        if self._state == TRAP or not self._in_cycle[self._state]:
            return None
        return int(self.dfa.cycle_of[self._state])


class WorldIdentifier:
    """Which of several candidate worlds can the robot be in? (Sec. IV-D, spec §3)

    One open-world filter (Def. 9) per world runs in parallel on the same observation stream; a
    world is ruled out as soon as its filter is trapped. `identified` names the world once it is
    the only one left; ``possible == ()`` means the robot is in none of them.
    """

    def __init__(self, filters: Mapping[str, LocalizationFilter]) -> None:
        if not filters:
            raise ConfigError("filters: expected at least one candidate world")
        for name, filt in filters.items():
            if not isinstance(filt, LocalizationFilter) or not filt.open_world:
                raise ConfigError(f"filters[{name!r}]: expected an open-world LocalizationFilter")
        self.filters = dict(filters)
        self.reset()

    @classmethod
    def for_worlds(cls, worlds: Mapping[str, World] | Iterable[World | str], phi: float,
                   n_bins: int = 8, cell_size: float = 1.0, robot_radius: float = 0.0,
                   corner_rule: str = "target_only") -> WorldIdentifier:
        """Build the filters for worlds given as a name → World mapping or as Worlds/zoo names."""
        if not isinstance(worlds, Mapping):
            items = {}
            for w in worlds:
                if isinstance(w, str):
                    w = get_world(w)
                if w.name in items:
                    raise ConfigError(f"worlds: duplicate world name {w.name!r}")
                items[w.name] = w
            worlds = items
        return cls({name: LocalizationFilter.for_world(
            w, phi, n_bins=n_bins, cell_size=cell_size, robot_radius=robot_radius,
            open_world=True, corner_rule=corner_rule) for name, w in worlds.items()})

    def reset(self) -> None:
        for filt in self.filters.values():
            filt.reset()

    def update(self, symbol) -> tuple[str, ...]:
        """Feed one observation to every filter; returns the worlds still possible."""
        _symbol(symbol)
        for filt in self.filters.values():
            filt.update(symbol)
        return self.possible

    def run(self, symbols: Iterable) -> tuple[str, ...]:
        for a in symbols:
            self.update(a)
        return self.possible

    @property
    def possible(self) -> tuple[str, ...]:
        return tuple(name for name, f in self.filters.items() if not f.trapped)

    @property
    def ruled_out(self) -> tuple[str, ...]:
        return tuple(name for name, f in self.filters.items() if f.trapped)

    @property
    def identified(self) -> str | None:
        """The only world still possible, else None (several left, or none: not in any)."""
        left = self.possible
        return left[0] if len(left) == 1 else None


# -- beyond the paper: switching the bounce angle -------------------------------------------------

class _AngleSet:
    """Successor arrays of one cell model for several bounce angles (shared bump labels)."""

    def __init__(self, model: CellModel, angles: Sequence[float]) -> None:
        if not isinstance(model, CellModel):
            raise ConfigError(f"model: expected a CellModel, got {type(model).__name__}")
        try:
            angles = [float(a) for a in angles]
        except TypeError:
            raise ConfigError(f"angles: expected a sequence of angles in radians, got "
                              f"{angles!r}") from None
        if not angles:
            raise ConfigError("angles: expected at least one bounce angle")
        self.model = model
        self.angles = tuple(angles)
        self.bins = [model.angle_bins(a, "angles") % model.n_bins for a in angles]
        if len(set(self.bins)) != len(self.bins):
            raise ConfigError(f"angles: the angles must be distinct modulo 360°, got "
                              f"{[round(math.degrees(a), 6) for a in angles]}")
        pairs = [model.successor(a) for a in angles]  # raises ConfigError for φ ≡ 0
        self.successors = np.stack([s for s, _ in pairs])
        self.bump = pairs[0][1]  # whether a tick bumps does not depend on φ, only where it goes
        self.n_cells = model.n_cells

    def index(self, angle: float) -> int:
        bins = self.model.angle_bins(float(angle), "angle") % self.model.n_bins
        try:
            return self.bins.index(bins)
        except ValueError:
            raise ConfigError(
                f"angle: {math.degrees(angle):g}° is not one of the angles "
                f"{[round(math.degrees(a), 6) for a in self.angles]}") from None


class ActiveLocalizationFilter:
    """A localization filter for a robot that may change its bounce angle at every bump.

    It keeps the candidate set S (the cells consistent with all observations and the angles used)
    and on an observation ``symbol`` with angle φ in use applies
    ``S' = {c_φ(z) : z ∈ S, obs(z) = symbol}`` — O(|S|) per update. With one angle throughout it
    is exactly the DFA filter (`LocalizationFilter`) of that angle.

    Args:
        model: the cell model of the world.
        angles: the bounce angles (radians) the robot can rotate by reliably (Φ of thesis Ch. 3).
        angle: the angle in use initially (default: the first).
        open_world: on an impossible observation become `trapped` instead of raising
            `ImpossibleObservationError`.

    Attributes:
        candidates, size, trapped, steps: as in `LocalizationFilter`.
        converged: no further observation can shrink S under the current angle (all its cells
            are in one class of `future_classes`).
        localized: no angle can shrink S any more and S holds periodic cells of the current
            angle — for a robot with one angle exactly "in a knowledge cycle" of its DFA.
    """

    def __init__(self, model: CellModel, angles: Sequence[float], angle: float | None = None,
                 open_world: bool = False) -> None:
        self._set = _AngleSet(model, angles)
        self.model = model
        self.angles = self._set.angles
        self.open_world = bool(open_world)
        self._initial = 0 if angle is None else self._set.index(angle)
        self._per_angle: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.reset()

    def reset(self) -> None:
        self._cells = _read_only([np.arange(self._set.n_cells, dtype=np.int64)])[0]
        self._angle = self._initial
        self._trapped = False
        self.steps = 0

    @property
    def angle(self) -> float:
        """The bounce angle in use (radians); it applies at the next bump."""
        return self.angles[self._angle]

    def set_angle(self, angle: float) -> None:
        """Switch the bounce angle (one of ``angles``)."""
        self._angle = self._set.index(angle)

    def update(self, symbol, angle: float | None = None) -> int:
        """Consume one observation; on a 1 the robot rotates by ``angle`` (default: the angle in
        use, which ``angle`` also replaces). Returns the new candidate count."""
        a = _symbol(symbol)
        if angle is not None:
            self.set_angle(angle)
        if not self._trapped:
            cells = self._cells
            keep = cells[self._set.bump[cells] == bool(a)]
            if keep.size == 0:
                if not self.open_world:
                    raise ImpossibleObservationError(
                        f"closed-world active filter: observation {a} after {self.steps} "
                        f"observations is impossible in this world")
                self._trapped = True
                self._cells = keep
            else:
                nxt = self._set.successors[self._angle][keep]
                nxt.sort()
                nxt.flags.writeable = False
                self._cells = nxt
        self.steps += 1
        return self.size

    @property
    def candidates(self) -> np.ndarray:
        return self._cells

    @property
    def size(self) -> int:
        return int(self._cells.size)

    @property
    def trapped(self) -> bool:
        return self._trapped

    def _classes(self, k: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Future classes and periodic mask of angle ``k`` (default: the one in use), computed
        once per angle."""
        k = self._angle if k is None else k
        if k not in self._per_angle:
            succ = self._set.successors[k]
            self._per_angle[k] = future_classes(succ, self._set.bump), periodic_cells(succ)
        return self._per_angle[k]

    @property
    def converged(self) -> bool:
        if self._trapped:
            return False
        cls = self._classes()[0][self._cells]
        return bool((cls == cls[0]).all())

    @property
    def localized(self) -> bool:
        """No angle can shrink S any more (S is converged under every angle) and S holds
        periodic cells of the angle in use; with one angle, "in a knowledge cycle"."""
        if self._trapped:
            return False
        for k in range(len(self.angles)):
            cls = self._classes(k)[0][self._cells]
            if not (cls == cls[0]).all():
                return False
        return bool(self._classes()[1][self._cells].all())


class AngleSwitchPlanner:
    """Reference policy: at a bump, pick the angle minimising the worst-case candidate count.

    A *segment* starts at a bump tick: the robot rotates by the chosen angle, then drives until
    the next bump; its observation is the number k of 0s before that 1 (a 1 right away gives
    k = 0). For a candidate set S at a bump (cells of S that do not bump are dropped — the 1 just
    observed rules them out) and an angle φ, the outcomes partition S into
    ``S'_k = {cells reached at the next bump from the z ∈ S with k zeros}``.

    ``choose(S)`` solves the depth-``depth`` minimax game: the robot picks φ, the world picks the
    outcome k (over the consistent cells), for ``depth`` segments; the value is the candidate
    count at the end (depth 1 = greedy: ``min_φ max_k |S'_k|``). Ties are broken by the expected
    count under a uniform prior over S, then by the order of ``angles``. Results are memoised per
    (set, depth).
    """

    def __init__(self, model: CellModel, angles: Sequence[float], depth: int = 1) -> None:
        if isinstance(depth, bool) or not isinstance(depth, int | np.integer) or depth < 1:
            raise ConfigError(f"depth: expected an integer >= 1, got {depth!r}")
        self._set = _AngleSet(model, angles)
        self.model = model
        self.angles = self._set.angles
        self.depth = int(depth)
        self._run_len, self._run_end = self._forward_runs()
        self._memo: dict[tuple[bytes, int], tuple[int, float, int]] = {}

    def _forward_runs(self) -> tuple[np.ndarray, np.ndarray]:
        """Per cell: 0s until the next bump tick and the cell where it bumps (angle-free)."""
        succ0, bump = self._set.successors[0], self._set.bump
        end = np.arange(self._set.n_cells, dtype=np.int64)
        length = np.zeros(self._set.n_cells, dtype=np.int64)
        for _ in range(self._set.n_cells + 1):
            moving = ~bump[end]
            if not moving.any():
                return length, end
            end[moving] = succ0[end[moving]]
            length[moving] += 1
        raise ConfigError("model: a forward run never bumps")  # pragma: no cover

    def outcomes(self, cells, angle: float) -> dict[int, np.ndarray]:
        """The next-segment outcomes of rotating by ``angle`` at a bump with candidates
        ``cells``: k (number of 0s) → sorted candidate set at the next bump."""
        return self._outcomes(self._bumping(cells), self._set.index(angle))

    def _bumping(self, cells) -> np.ndarray:
        cells = np.unique(np.asarray(cells, dtype=np.int64))
        if cells.size and (cells[0] < 0 or cells[-1] >= self._set.n_cells):
            raise ConfigError(f"cells: expected cell ids in [0, {self._set.n_cells})")
        out = cells[self._set.bump[cells]]
        if out.size == 0:
            raise ObservationError("cells: no candidate cell bumps, so this is not a bump tick")
        return out

    def _outcomes(self, cells: np.ndarray, k: int) -> dict[int, np.ndarray]:
        rotated = self._set.successors[k][cells]
        zeros, ends = self._run_len[rotated], self._run_end[rotated]
        result = {}
        for n in np.unique(zeros).tolist():
            nxt = ends[zeros == n]
            nxt.sort()
            result[int(n)] = nxt
        return result

    def _best(self, cells: np.ndarray, depth: int) -> tuple[int, float, int]:
        key = (cells.tobytes(), depth)
        hit = self._memo.get(key)
        if hit is not None:
            return hit
        best = None
        for k in range(len(self.angles)):
            worst, expected = self._score(cells, k, depth)
            if best is None or (worst, expected) < best[:2]:
                best = (worst, expected, k)
        if len(self._memo) > 200_000:
            self._memo.clear()
        self._memo[key] = best
        return best

    def _score(self, cells: np.ndarray, k: int, depth: int) -> tuple[int, float]:
        worst, expected = 0, 0.0
        for nxt in self._outcomes(cells, k).values():
            if depth == 1:
                w, e = nxt.size, float(nxt.size)
            else:
                w, e, _ = self._best(nxt, depth - 1)
            worst = max(worst, w)
            expected += nxt.size / cells.size * e
        return worst, expected

    def scores(self, cells) -> list[tuple[float, int, float]]:
        """(angle, worst-case count, expected count) of every angle at this planner's depth."""
        bumping = self._bumping(cells)
        return [(a, *self._score(bumping, k, self.depth)) for k, a in enumerate(self.angles)]

    def choose(self, cells) -> float:
        """The angle (radians) to rotate by at this bump, given the candidate set ``cells``."""
        return self.angles[self._best(self._bumping(cells), self.depth)[2]]

    def choose_index(self, cells) -> int:
        return self._best(self._bumping(cells), self.depth)[2]


def build_policy_dfa(planner: AngleSwitchPlanner, *, max_states: int | None = None) -> DFA:
    """The closed-loop subset automaton of a robot that rotates by ``planner.choose(S)`` at every
    bump — the active counterpart of `build_dfa` (same lazy construction, same knowledge cycles
    and colours), so its localization limits compare directly with the fixed-angle DFAs.
    """
    angle_set = planner._set
    bump, successors = angle_set.bump, angle_set.successors
    chosen: dict[bytes, int] = {}

    def image(cells: np.ndarray, a: int) -> np.ndarray:
        keep = cells[bump[cells] == bool(a)]
        if keep.size == 0:
            return keep
        k = 0
        if a == 1:
            k = chosen[cells.tobytes()] = planner._best(keep, planner.depth)[2]
        out = successors[k][keep]
        out.sort()
        return out

    states, delta, index = _subset_construction(angle_set.n_cells, image, max_states)
    states = _read_only(states)
    angle_index = np.array([chosen.get(s.tobytes(), -1) for s in states], dtype=np.int64)
    angles = np.array(angle_set.angles + (math.nan,))[angle_index]
    cycles, cycle_of, colour = _knowledge_cycles(states, delta)
    return DFA(states=states, delta=delta, n_cells=angle_set.n_cells, periodic=None,
               cycles=cycles, cycle_of=cycle_of, colour=colour, bump_angle=angles,
               bump_angle_index=angle_index, _index=index)


def final_uncertainties(dfa: DFA, successor, bump) -> np.ndarray:
    """The candidate count every start cell ends with: run the true cell and the DFA together
    (closed world) until the DFA is in a knowledge cycle (at most |Q'| steps).

    ``successor`` is the (N,) SCM of a fixed-angle DFA, or the (A, N) stack of the angles of a
    `build_policy_dfa` (the true cell follows the angle the policy picks, row
    ``dfa.bump_angle_index``). The maximum over start cells is the DFA's max uncertainty; the
    mean is the expected final uncertainty under a uniform prior.
    """
    succ = np.atleast_2d(np.asarray(successor, dtype=np.int64))
    obs = np.asarray(bump, dtype=bool)
    n = dfa.n_cells
    cells = np.arange(n, dtype=np.int64)
    states = np.zeros(n, dtype=np.int64)
    choice = dfa.bump_angle_index if dfa.bump_angle_index is not None \
        else np.zeros(dfa.n_states, dtype=np.int64)
    for _ in range(dfa.n_states):
        a = obs[cells]
        row = np.where(a, np.maximum(choice[states], 0), 0)
        cells = succ[row, cells]
        states = dfa.delta[states, a.astype(np.int64)]
    if (states == TRAP).any() or (dfa.cycle_of[states] < 0).any():  # pragma: no cover
        raise AssertionError("a true run left its own world's DFA")
    return dfa.sizes[states]


def task_filter(options) -> LocalizationFilter | ActiveLocalizationFilter:
    """The filter for the environments' localization task.

    Plug it in with ``task_kwargs={"filter_factory": "baselines.localization:task_filter"}`` (the
    registered ``bounce_gym/BounceLocalization-v0`` does). ``options`` are the env's validated
    `EnvOptions`: the world is discretised with cell size = ``step_length``, the cell backend's
    ``n_bins`` (8 otherwise) and the robot's radius. One bounce angle gives the O(1) DFA filter
    (Def. 8/9); several give the active filter. The filter is closed-world only on the noise-free
    ``cell`` backend, where the robot steps the model exactly; elsewhere it is open-world and
    reports ``trapped`` once the robot's observations leave the model.
    """
    if options.action_type != "discrete":
        raise ConfigError("localization filter: needs discrete actions (each bounce angle must "
                          "be a whole orientation bin of the cell model)")
    n_bins = options.backend_options.get("n_bins", 8)
    model = CellModel(options.world, cell_size=options.step_length, n_bins=n_bins,
                      robot_radius=options.robot_radius,
                      corner_rule=options.backend_options.get("corner_rule", "target_only"))
    exact = options.backend == "cell" and type(options.noise).__name__ == "Exact"
    angles = options.angles[0]
    if len(angles) == 1:
        return LocalizationFilter.from_model(model, float(angles[0]), open_world=not exact)
    return ActiveLocalizationFilter(model, angles, open_world=not exact)


class AngleSwitchPolicy(Policy):
    """Reference policy for the localization task: at every bump, the planner's angle.

    It runs its own `ActiveLocalizationFilter` on what the robot senses — rebuilt from the
    task's ``info`` (``observations``, ``clock``, ``step_ticks``), nothing privileged — and asks
    `AngleSwitchPlanner` for the angle minimising the worst-case candidate count.
    ``act(observation, info)`` returns the discrete action (the index of the angle).
    """

    name = "planner (angle switching)"

    def __init__(self, model: CellModel, angles: Sequence[float], depth: int = 1,
                 open_world: bool = True) -> None:
        self.planner = AngleSwitchPlanner(model, angles, depth=depth)
        self.filter = ActiveLocalizationFilter(model, angles, open_world=open_world)
        self.angles = self.planner.angles

    @classmethod
    def for_env(cls, env, depth: int = 1) -> AngleSwitchPolicy:
        """The policy for a `BounceEnv` (angles and discretisation taken from its options)."""
        options = env.unwrapped.options
        model = CellModel(options.world, cell_size=options.step_length,
                          n_bins=options.backend_options.get("n_bins", 8),
                          robot_radius=options.robot_radius,
                          corner_rule=options.backend_options.get("corner_rule", "target_only"))
        return cls(model, options.angles[0], depth=depth)

    def act(self, observation, info: dict) -> int:
        self.observe(info)
        if self.filter.trapped or self.filter.size == 0:
            return 0  # the observations left the model: no better choice than the first angle
        try:
            angle = self.planner.choose(self.filter.candidates)
        except ObservationError:
            return 0  # not at a bump (tick mode, driving): the action is not used
        return int(np.argmin(np.abs(np.asarray(self.angles) - angle)))

    def observe(self, info: dict) -> None:
        """Feed the filter the ticks the env reported since the previous call."""
        history = info["observations"]
        if not history:  # a new episode: the drive to the first contact, if any
            self.filter.reset()
            for _ in range(int(info["clock"])):
                self.filter.update(0)
        else:
            bumps, _, angle = history[-1]
            for _ in range(bumps):
                self.filter.update(1, angle)
            for _ in range(int(info["step_ticks"]) - bumps):
                self.filter.update(0)
