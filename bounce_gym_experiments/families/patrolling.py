"""Stochastic patrolling with an adversary (``bounce_gym/Patrol-v0``; Alam 2018, thesis ch. 4):
patrol strategies against adversaries, one row per pair.

Patrollers (the experiment's ``policies``): ``planner`` — MAECT over all vertices (§4.4.1,
`baselines.patrolling.maect.solve_maect`) and the Stackelberg equilibrium mixture (§4.4.2,
`baselines.patrolling.equilibrium`); ``random`` — the uniform random walk on the cell graph;
``perimeter`` — the perimeter patrols after Agmon et al. (p = 1 and p = 1/2; approximations of
the thesis's BMP/DCP/DNCP, `baselines.patrolling.policies.PerimeterPatrolPolicy`); ``rl`` —
parameter-shared PPO trained with ``role: patrollers`` (`baselines.rl.patrol`). Adversaries
(the experiment's ``adversaries``): ``best_response`` — the Stackelberg follower told the
strategy, ``best_response_positions`` — told the patrollers' positions at step 0 too
(`baselines.patrolling.policies.BestResponseAdversary`); ``rl`` — PPO trained with ``role:
adversary``, sampling its actions, and the same model greedy (``... (greedy)``). Trained
patrollers sample. Every patroller meets every adversary, one row each (``<patrollers> vs
<adversary>``). ``planner_kwargs`` set the equilibrium's strategy set (`PatrolSetup`). The
choices are in docs/choices/patrolling.md, "The patrol evaluation".

Per episode: ``captured`` (the attack was caught, thesis §4.3.5), ``deterred`` (the adversary
never attacked), ``outcome``, ``attack_target`` (vertex, -1 for none), ``detection_time`` (steps
from the attack's start to the capture; captured episodes only, so the table's mean is
conditional and its ``n`` the number of captures), ``t_a`` (a label) and, against a best
response, ``predicted_capture``: the capture probability the env computes for the adversary's
target from what it was told — its mean is what ``captured`` estimates when the strategy is a
Markov chain or a mixture of them (for the perimeter walk the adversary is told an induced chain,
and the prediction is only that chain's). Plots: MAECT's edge weights, the Alg. 4.3 covers and
p_d(t_a) per Markov strategy at its best-response target.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from baselines.patrolling.equilibrium import EquilibriumStrategy, equilibrium_strategy
from baselines.patrolling.maect import solve_maect
from baselines.patrolling.markov import transition_matrix
from baselines.patrolling.policies import (
    BestResponseAdversary,
    JointPatrolPolicy,
    LearnedAdversary,
    LearnedPatrollers,
    MarkovPatrolPolicy,
    PerimeterPatrolPolicy,
)
from baselines.patrolling.subset import DEFAULT_CYCLE_SHARE
from baselines.patrolling.towards import DEFAULT_PATHS
from baselines.patrolling.visibility_policies import distributed_subsets
from baselines.patrolling.vulnerability import (
    GLD,
    DetectionCurve,
    detection_curve,
    detection_times,
    fit_gld,
)
from bounce_gym import validate
from bounce_gym.envs.patrol import capture
from bounce_gym.envs.registration import PATROL_PETTINGZOO_ENVS
from bounce_gym.errors import ConfigError, config_errors
from bounce_gym_experiments import stats
from bounce_gym_experiments.families.base import Episode, Family

#: the patrollers' policy kinds (module docstring)
PATROL_POLICY_KINDS = ("planner", "random", "perimeter", "rl")
#: the adversaries: the Stackelberg best response told the strategy, or also the patrollers'
#: positions, and trained models (default: the first two)
ADVERSARY_KINDS = ("best_response", "best_response_positions", "rl")

#: the best-response modes of the adversary kinds
_MODES = {"best_response": "strategy", "best_response_positions": "positions"}
#: simulated detection times per strategy for the p_d(t_a) curves
DETECTION_RUNS = 1000
#: a placeholder distribution for a curve with nothing to fit (its fitted values are not used)
_NO_FIT = GLD(0.0, 1.0, 0.0, 0.0)


class PatrolSetup:
    """Per experiment: the env's graph and visibility, the MAECT strategy and the equilibrium
    mixture (when the planner runs).

    The equilibrium's strategy set (`baselines.patrolling.equilibrium`): MAECT over all
    vertices, MAECT over the subset of robot 1's viewing cells of the distributed visibility
    policy (§4.3.3, `visibility_policies.distributed_subsets`), and the Alg. 4.1 chains towards
    the ``exposed`` targets of least capture probability under MAECT (``planner_kwargs``:
    ``exposed`` (5), ``h`` (0.8), ``k`` (3), ``tol`` (1e-8) of the subset problem).
    """

    def __init__(self, env, experiment: Mapping) -> None:
        inner = env.unwrapped
        self.name = experiment["name"]
        self.graph = inner.graph
        self.visibility = inner.visibility
        self.t_a = int(inner.attack_time)
        self.m = inner.n_patrollers
        self.maect = self.equilibrium = None
        #: per patroller policy, whether each episode against the best response (strategy)
        #: ended in a capture (the measured points of the p_d(t_a) plot)
        self.captured: dict[str, list[bool]] = {}
        #: the trained patrollers and adversaries loaded so far, with their groups
        self.learned_patrollers: list = []
        self.learned_adversaries: list = []
        if "planner" in experiment["policies"]:
            self.maect = solve_maect(self.graph)
            self.equilibrium = self._equilibrium(inner, **experiment["planner_kwargs"])

    def _equilibrium(self, inner, exposed: int = 5, h: float = DEFAULT_CYCLE_SHARE,
                     k: int = DEFAULT_PATHS, tol: float = 1e-8) -> EquilibriumStrategy:
        exposed = validate.integer("planner_kwargs.exposed", exposed, 1, inner.n_vertices)
        maect = self.maect.transition.toarray()
        S = capture.survival(maect, inner.board.seen, self.t_a)
        risk = capture.capture_from_distinct_uniform(S, self.m)
        targets = np.argsort(risk, kind="stable")[:exposed]
        subset = distributed_subsets(self.visibility, 1)[0]
        with config_errors("planner_kwargs"):
            return equilibrium_strategy(self.graph, maect, subset, targets, h=h, k=k, tol=tol)


class PatrolEpisode(Episode):
    """Follows the patrollers' vertices to tell a capture at the attack's start (detection time
    0) from one after its first step (1); the metrics come from the last ``info``; the clock is
    the env's steps."""

    def __init__(self, env, t_a: int, captures: list[bool] | None = None) -> None:
        self.inner = env.unwrapped
        self.t_a = t_a
        self.captures = captures
        self.before: np.ndarray | None = None
        self.at_start: np.ndarray | None = None

    def start(self, info):
        self.before, self.at_start = self.inner.positions(), None
        return False

    def step(self, info):
        if self.at_start is None and info["attack_started"] >= 0:
            self.at_start = self.before
        self.before = self.inner.positions()
        return False

    def metrics(self, info):
        outcome = info["outcome"]
        target = int(info["attack_target"])
        out = {"captured": outcome == "capture", "deterred": outcome == "deterred",
               "outcome": outcome, "attack_target": target, "t_a": self.t_a}
        if self.captures is not None:
            self.captures.append(out["captured"])
        if outcome == "capture":
            seen_at_start = self.inner.board.seen[target, self.at_start].any()
            out["detection_time"] = 0 if seen_at_start else int(info["attack_elapsed"])
        return out

    def ticks(self, info, steps):
        return steps


class Patrolling(Family):
    name = "patrolling"
    parallel = True
    table = "patrolling: capture of the adversary (thesis ch. 4)"
    columns = ("experiment", "policy", "episodes", "seeds", "t_a", "captured",
               "predicted_capture", "detection_time", "deterred")
    labels = frozenset({"t_a"})
    descriptors = frozenset({"attack_target"})
    score = "captured"
    planner_attributes = ("predicted_capture",)
    policy_kinds = PATROL_POLICY_KINDS
    adversary_kinds = ADVERSARY_KINDS
    takes_planner_kwargs = True
    record_paths = False

    def claims(self, experiment):
        return experiment["env"] in PATROL_PETTINGZOO_ENVS

    def world(self, env):
        return env.unwrapped.board.world

    def prepare(self, env, experiment):
        try:
            return PatrolSetup(env, experiment)
        except TypeError as exc:
            raise ConfigError(f"planner_kwargs: {exc}") from None

    def patrollers(self, kind: str, env, setup: PatrolSetup) -> list:
        """The patroller policies of one kind (not ``rl``)."""
        if kind == "planner":
            eq = setup.equilibrium
            return [MarkovPatrolPolicy([setup.maect.transition], name="MAECT"),
                    MarkovPatrolPolicy(eq.chains, eq.mixture, name="equilibrium mixture")]
        if kind == "random":
            walk, _ = transition_matrix(setup.graph, nodes=sorted(setup.graph))
            return [MarkovPatrolPolicy([walk], name="random walk")]
        return [PerimeterPatrolPolicy("deterministic"), PerimeterPatrolPolicy("random_walk")]

    def policies(self, kind, env, experiment, setup):
        return [JointPatrolPolicy(patrollers, BestResponseAdversary(_MODES[adversary]))
                for patrollers in self.patrollers(kind, env, setup)
                for adversary in experiment["adversaries"] if adversary in _MODES]

    def trained_policies(self, folder, env, label, experiment, setup):
        """The trained patrollers of ``folder`` against every adversary of the experiment, and
        its trained adversaries against every patroller (`baselines.rl.policies.patrol_policy`
        tells which side a model learned). Models of both sides may come from different folders
        of ``rl_models``: each folder's models also meet those loaded before them (kept in the
        setup). A trained adversary plays twice, sampling and greedy (its names and group with
        `baselines.rl.policies.GREEDY_SUFFIX`; the experiment's ``greedy: false``: sampling
        only); trained patrollers always sample."""
        from baselines.rl.model_files import MODEL_NAME, model_files, run_name
        from baselines.rl.policies import GREEDY_SUFFIX, PatrollerSB3Policy, patrol_policy

        patrollers, adversaries = [], []
        for path in model_files(folder):
            model = patrol_policy(path, env)
            model.name = f"rl {label}{path.stem}"
            name = MODEL_NAME.fullmatch(path.name)
            group = f"rl {label}{run_name(name['algo'], name['variant'])}"
            if isinstance(model, PatrollerSB3Policy):
                patrollers.append((LearnedPatrollers(model), group))
                continue
            adversaries.append((LearnedAdversary(model), group))
            if experiment["greedy"]:
                greedy = patrol_policy(path, env, deterministic=True)
                greedy.name = model.name + GREEDY_SUFFIX
                adversaries.append((LearnedAdversary(greedy), group + GREEDY_SUFFIX))
        if "rl" not in experiment["policies"]:
            patrollers = []
        if "rl" not in experiment["adversaries"]:
            adversaries = []
        out = []
        for learned, group in patrollers:
            for kind in experiment["adversaries"]:
                if kind in _MODES:
                    adversary = BestResponseAdversary(_MODES[kind])
                    out.append((JointPatrolPolicy(learned, adversary),
                                f"{group} vs {adversary.name}"))
            out += [(JointPatrolPolicy(learned, a), f"{group} vs {g}")
                    for a, g in setup.learned_adversaries]
        fixed = [p for kind in experiment["policies"] if kind != "rl"
                 for p in self.patrollers(kind, env, setup)]
        for learned, group in adversaries:
            out += [(JointPatrolPolicy(p, learned), f"{p.name} vs {group}") for p in fixed]
            out += [(JointPatrolPolicy(p, learned), f"{g} vs {group}")
                    for p, g in setup.learned_patrollers + patrollers]
        setup.learned_patrollers += patrollers
        setup.learned_adversaries += adversaries
        return out

    def episode(self, env, policy, setup):
        adversary = policy.adversary
        told = isinstance(adversary, BestResponseAdversary) and adversary.mode == "strategy"
        captures = setup.captured.setdefault(policy.patrollers.name, []) if told else None
        return PatrolEpisode(env, setup.t_a, captures)

    def drain(self, setup):
        drained, setup.captured = setup.captured, {}
        return drained

    def absorb(self, setup, drained):
        for patrollers, captures in drained.items():
            setup.captured.setdefault(patrollers, []).extend(captures)

    def collect(self, data, env, policy, setup):
        """The setup and each Markov strategy's best-response target for the plots; a note
        with the equilibrium mixture's weights."""
        if "setup" not in data and setup.equilibrium is not None:
            eq = setup.equilibrium
            weights = ", ".join(f"{name} {w:.3f}" for name, w in zip(eq.names, eq.mixture,
                                                                      strict=True) if w >= 5e-4)
            data["notes"].append(f"{setup.name}: the equilibrium mixture is {weights} (the "
                                 f"game's attack: vertex {eq.attack})")
        data["setup"] = setup
        patrollers = policy.patrollers
        adversary = policy.adversary
        if isinstance(patrollers, MarkovPatrolPolicy) and isinstance(adversary,
                                                                     BestResponseAdversary) \
                and adversary.mode == "strategy":
            data.setdefault("targets", {})[patrollers.name] = (patrollers, adversary.target)

    def trajectory_plots(self, folder, name, data):
        return []

    def plots(self, folder, name, data):
        from bounce_gym_experiments.plots.patrolling import (
            plot_covers,
            plot_detection_curves,
            plot_edge_weights,
        )

        setup: PatrolSetup | None = data.get("setup")
        if setup is None:
            return []
        written = []
        if setup.maect is not None:
            written.append(plot_edge_weights(setup.graph, setup.maect.weights,
                                             folder / f"{name}-maect-weights.png",
                                             title=f"{name}: MAECT edge weights"))
        covers = distributed_subsets(setup.visibility, setup.m)
        written.append(plot_covers(setup.graph, setup.visibility.seen, covers,
                                   folder / f"{name}-covers.png",
                                   title=f"{name}: Alg. 4.3 covers, l = {setup.visibility.l:g}"))
        curves = self.detection_curves(setup, data.get("targets", {}))
        if curves:
            measured = {}
            for policy, captures in setup.captured.items():
                rate = stats.rate(captures)
                measured[policy] = (setup.t_a, rate.value, rate.lo, rate.hi)
            written.append(plot_detection_curves(
                curves, folder / f"{name}-pd.png", measured,
                title=f"{name}: p_d(t_a) at each strategy's best-response target\n"
                      "GλD fit (line), empirical CDF (dashed), measured with 95% CI (point)"))
        return written

    @staticmethod
    def detection_curves(setup: PatrolSetup, targets: Mapping) -> dict:
        """p_d(t_a) for t_a = 0 .. 5 t_a of every Markov strategy at its best-response target:
        `detection_times` of the m patrollers (each chain of a mixture with its share of the
        runs) from uniformly random distinct starts, as the env places them. Runs not detected
        within 20 t_a steps (a chain of Alg. 4.1 may never reach the target) count as never
        detected: the GλD is fitted to the detected ones and both curves are scaled by their
        share. Without two distinct detection times there is nothing to fit and the empirical
        curve stands alone (with no detection at all it is 0)."""
        from bounce_gym.cells.visibility import watch_region

        curves = {}
        t_a = np.arange(0, 5 * setup.t_a + 1)
        for name, (policy, target) in targets.items():
            watched = watch_region(setup.visibility, target).inside
            runs = np.maximum(np.round(policy.weights * DETECTION_RUNS).astype(int), 0)
            times = np.concatenate([
                detection_times([chain] * setup.m, watched, n_runs=int(k), seed=i,
                                distinct_starts=True, max_steps=20 * setup.t_a)
                for i, (chain, k) in enumerate(zip(policy.chains, runs, strict=True)) if k > 0])
            detected = times[np.isfinite(times)]
            share = len(detected) / len(times)
            if len(np.unique(detected)) >= 2 and len(detected) >= 5:
                curve = detection_curve(detected, t_a, fit_gld(detected, bin_width=1.0,
                                                               restarts=1))
                fitted = share * curve.fitted
            else:  # nothing to fit (e.g. every detection at the start): the ECDF alone
                curve = detection_curve(np.zeros(1) if len(detected) == 0 else detected, t_a,
                                        _NO_FIT)
                fitted = np.full(len(t_a), np.nan)
            curves[name] = DetectionCurve(curve.t_a, fitted, share * curve.empirical, curve.gld)
        return curves


FAMILY = Patrolling()
