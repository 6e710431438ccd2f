"""Where to release a fleet of drifters (``bounce_gym/MultiDrifter-v0``; Alam 2018, thesis ch. 5,
problem 1): surface coverage over time by Alg. 5.2's deployment against random and greedy
deployments of the same number of drifters (`baselines.drifters.DeploymentPolicy`); every
drifter drifts.

Policy kinds: ``planner`` — Alg. 5.2 and the greedy deployment for the experiment's horizon
(both plan on the env's cell model); ``random`` — random surface cells from the episode's seed.
Alg. 5.2 fixes the fleet size: the experiment's ``env_kwargs.n_drifters`` must be the number
of cells it deploys (an error says which), and the other deployments release as many drifters.

Per episode: ``drifters`` (the fleet size, a label), ``coverage`` (the fraction of surface water
cells visited at the end), ``full`` (all of them visited; the env then ends the episode) and
``steps_to_full`` (full episodes only), and ``predicted_coverage``: the cell model's expected
coverage of the episode's deployment within the horizon, for independent drifters
(`baselines.drifters.expected_coverage`) — what the cell backend's coverage estimates. Plots:
coverage against steps (the mean over the episodes with its 95% band, `bounce_gym_experiments.stats.mean_band`,
and the predictions), and the first seed's deployment cells over the persistent groups.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from baselines.drifters import (
    DeploymentPolicy,
    expected_coverage,
    persistent_behavior,
    visit_probabilities,
)
from bounce_gym.errors import ConfigError
from bounce_gym_experiments import stats
from bounce_gym_experiments.families.drifters import DrifterEpisode, DrifterFamily

#: At most this many points of the coverage curves get an interval in the plot.
BAND_POINTS = 101


class DeploymentSetup:
    """Per experiment: the surface's Alg. 5.1 analysis, the visit probabilities within the
    horizon (for the predictions), and every episode's coverage curve per policy."""

    def __init__(self, env, horizon: int) -> None:
        model = env.unwrapped.cell_model()
        self.horizon = horizon
        self.behavior = persistent_behavior(model, 0)
        self.hit = visit_probabilities(self.behavior, horizon)
        self.curves: dict[str, list[np.ndarray]] = {}
        self.predicted: dict[str, list[float]] = {}


class DeploymentEpisode(DrifterEpisode):
    """Follows the coverage of one episode; its metrics also file the curve with the setup."""

    def __init__(self, env, policy: DeploymentPolicy, setup: DeploymentSetup) -> None:
        self.n = len(env.unwrapped.possible_agents)
        self.policy, self.setup = policy, setup
        self.curve: list[float] = []

    def start(self, info):
        self.curve = [float(info["coverage"])]
        return False

    def step(self, info):
        self.curve.append(float(info["coverage"]))
        return False

    def metrics(self, info):
        coverage = float(info["coverage"])
        out = {"drifters": self.n, "coverage": coverage, "full": coverage >= 1.0}
        if out["full"]:
            out["steps_to_full"] = len(self.curve) - 1
        predicted = expected_coverage(self.setup.behavior, self.policy.deployment.states,
                                      self.setup.hit)
        out["predicted_coverage"] = predicted
        # after full coverage the env stops; the curve stays at 1 to the horizon
        curve = np.full(self.setup.horizon + 1, self.curve[-1])
        curve[:len(self.curve)] = self.curve
        self.setup.curves.setdefault(self.policy.name, []).append(curve)
        self.setup.predicted.setdefault(self.policy.name, []).append(predicted)
        return out


class DrifterDeployment(DrifterFamily):
    name = "drifter-deployment"
    task = "cover"
    parallel = True
    table = "drifter deployment: surface coverage (Alg. 5.2)"
    columns = ("experiment", "policy", "drifters", "episodes", "seeds", "coverage",
               "predicted_coverage", "full", "steps_to_full")
    labels = frozenset({"drifters"})
    score = "coverage"
    policy_kinds = ("planner", "random")
    takes_planner_kwargs = True

    def prepare(self, env, experiment: Mapping):
        setup = DeploymentSetup(env, experiment["max_steps"])
        n, needed = len(env.unwrapped.possible_agents), DeploymentPolicy.size(setup.behavior)
        if "planner" in experiment["policies"] and n != needed:
            raise ConfigError(f"env_kwargs.n_drifters: Alg. 5.2 deploys {needed} drifters on "
                              f"the surface of this field and the baselines as many; the env "
                              f"has {n}: set n_drifters: {needed}")
        return setup

    def policies(self, kind, env, experiment, setup):
        if kind == "planner":
            return [DeploymentPolicy("alg5.2"),
                    DeploymentPolicy("greedy", horizon=experiment["max_steps"])]
        return [DeploymentPolicy("random")]

    def episode(self, env, policy, setup):
        return DeploymentEpisode(env, policy, setup)

    def drain(self, setup):
        drained = (setup.curves, setup.predicted)
        setup.curves, setup.predicted = {}, {}
        return drained

    def absorb(self, setup, drained):
        for filed, more in zip((setup.curves, setup.predicted), drained, strict=True):
            for policy, values in more.items():
                filed.setdefault(policy, []).extend(values)

    def collect(self, data, env, policy, setup):
        super().collect(data, env, policy, setup)
        data["setup"] = setup
        data.setdefault("deployments", {})[policy.name] = policy.deployment

    def plots(self, folder, name, data):
        from bounce_gym_experiments.plots.drifters import plot_coverage_curves, plot_deployment

        setup: DeploymentSetup | None = data.get("setup")
        if setup is None or not setup.curves:
            return []
        points = np.unique(np.linspace(0, setup.horizon, BAND_POINTS).round().astype(int))
        bands = {policy: stats.mean_band(np.array(curves)[:, points])
                 for policy, curves in setup.curves.items()}
        predicted = {policy: float(np.mean(values))
                     for policy, values in setup.predicted.items()}
        return [
            plot_coverage_curves(points, bands, folder / f"{name}-coverage.png", predicted,
                                 title=f"{name}: surface coverage\nmean and 95% CI over "
                                       "the episodes; triangles: the model's expectation"),
            plot_deployment(data["model"], setup.behavior, data["deployments"],
                            folder / f"{name}-deployment.png",
                            title=f"{name}: deployment cells (first seed)"),
        ]


FAMILY = DrifterDeployment()
