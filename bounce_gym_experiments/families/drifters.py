"""Profiling drifters reaching a goal (``bounce_gym/Drifter-v0``, task ``reach``; Alam 2018,
thesis ch. 5, problem 4): the value-iteration policy of Alg. 5.5
(`baselines.drifters.ValueIterationPolicy`) against always drifting, a random layer and trained
agents, on the cell and the continuous backend — and what every drifter family shares.

Policy kinds: ``planner`` Alg. 5.5 (planned on the env's cell model, acting on the drifter's
model state) and, with ``planner_kwargs: {models: [cell, sampled], samples: n, refine: r}``,
finite-horizon value iteration on the sampled GCM of the env's own dynamics
(`baselines.drifters.HorizonReachPolicy`, acting on the observed pose; the env needs
``observe_pose: true``), ``random`` a uniformly random legal action every step
(`baselines.drifters.RandomLayerPolicy`), ``fixed`` always drift
(`baselines.drifters.AlwaysDriftPolicy`), ``rl`` the trained models.

Per episode: ``success`` (the goal was reached within the horizon), ``steps_to_goal``
(successful episodes only) and, for the policies that are one fixed action per model state (the
planner, always drift), ``predicted_success``: the cell model's probability that the policy
reaches the goal within the horizon from the episode's start state
(`baselines.drifters.reach_probability`); for the sampled planner its own model's. On the cell backend the env is that model, so the
measured success rate estimates the mean prediction; on the continuous backend the gap between
them is how far the model is from the currents. The clock of a drifter env is its steps.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from baselines.drifters import (
    AlwaysDriftPolicy,
    HorizonReachPolicy,
    RandomLayerPolicy,
    ValueIterationPolicy,
    reach_probability,
)
from baselines.policy import Policy
from bounce_gym.cells import DRIFT, DrifterCells
from bounce_gym.envs.registration import DRIFTER_GYM_ENVS, DRIFTER_PETTINGZOO_ENVS
from bounce_gym.errors import ConfigError
from bounce_gym_experiments.families.base import Episode, Family


class DrifterEpisode(Episode):
    """An episode of a drifter env: its clock is its steps."""

    def ticks(self, info, steps):
        return steps


class DrifterFamily(Family):
    """What the drifter families share: recognised by their env ids (a drifter id, Gymnasium or
    PettingZoo as the family) and task, drawn on their flow's map; they take
    ``planner_kwargs``."""

    takes_planner_kwargs = True

    def claims(self, experiment):
        ids = DRIFTER_PETTINGZOO_ENVS if self.parallel else DRIFTER_GYM_ENVS
        return (experiment["env"] in ids
                and experiment["env_kwargs"].get("task", self.task) == self.task)

    def world_name(self, experiment):
        """The flow (``env_kwargs.flow``: a zoo name, a NetCDF file by its file name or a field
        by its name; else the env's default)."""
        from bounce_gym.envs.drifters.options import DrifterOptions  # only if needed

        world = experiment["env_kwargs"].get("flow", DrifterOptions.model_fields["flow"].default)
        return Path(world).name if isinstance(world, str) else getattr(world, "name", "?")

    def world(self, env):
        return env.unwrapped.flow

    def collect(self, data, env, policy, setup):
        data["model"] = env.unwrapped.cell_model()

    def trajectory_plots(self, folder, name, data):
        from bounce_gym_experiments.plots.drifters import plot_paths

        if not data["paths"] or "model" not in data:
            return []
        return [plot_paths(data["model"], data["paths"], folder / f"{name}-trajectories.png",
                           goal=data.get("goal"), title=f"{name}: paths (first seed)")]


def stationary_actions(policy: Policy, model: DrifterCells) -> np.ndarray | None:
    """The (N,) action of ``policy`` in every state of ``model`` if it is one fixed action per
    state (the value-iteration plan of the episode, always drift), else ``None``."""
    if isinstance(policy, ValueIterationPolicy) and policy.result is not None:
        return policy.result.policy
    if isinstance(policy, AlwaysDriftPolicy):
        return np.full(model.n_states, DRIFT, dtype=np.int64)
    return None


class ReachPrediction:
    """The model's probability of reaching the episode's goal within ``horizon`` steps, from
    every state, per (model, goal, stationary policy) — computed once for all episodes."""

    def __init__(self, horizon: int) -> None:
        self.horizon = horizon
        self._known: dict[tuple, np.ndarray] = {}

    def __call__(self, env, policy: Policy, state: int) -> float | None:
        if isinstance(policy, HorizonReachPolicy):
            return policy.predicted_success(state)
        model = env.unwrapped.cell_model()
        actions = stationary_actions(policy, model)
        if actions is None:
            return None
        goal = env.unwrapped.task.region.states
        key = (id(model), goal.tobytes(), actions.tobytes())
        if key not in self._known:
            self._known[key] = reach_probability(model, actions, goal, self.horizon)
        return float(self._known[key][int(state)])


class ReachEpisode(DrifterEpisode):
    def __init__(self, env, policy: Policy, prediction: ReachPrediction) -> None:
        self.env, self.policy, self.prediction = env, policy, prediction
        self.predicted: float | None = None

    def start(self, info):
        self.predicted = self.prediction(self.env, self.policy, info["state"])
        return False

    def metrics(self, info):
        out = {"success": bool(info["is_success"])}
        if out["success"]:
            out["steps_to_goal"] = int(info["steps"])
        if self.predicted is not None:
            out["predicted_success"] = self.predicted
        return out


class DrifterReach(DrifterFamily):
    name = "drifters"
    task = "reach"
    table = "drifters: reach the goal (Alg. 5.5)"
    columns = ("experiment", "policy", "episodes", "seeds", "success", "predicted_success",
               "steps_to_goal", "return")
    score = "success"

    def validate(self, experiment):
        super().validate(experiment)
        drifter_planner_options(experiment)

    def prepare(self, env, experiment: Mapping):
        return ReachPrediction(experiment["max_steps"])

    def policies(self, kind, env, experiment, setup):
        if kind == "planner":
            return drifter_planners(experiment)
        if kind == "random":
            return [RandomLayerPolicy()]
        return [AlwaysDriftPolicy()]  # fixed: the one fixed action that is always legal

    def episode(self, env, policy, setup):
        return ReachEpisode(env, policy, setup)

    def collect(self, data, env, policy, setup):
        super().collect(data, env, policy, setup)
        data["goal"] = env.unwrapped.task.region.states
        data["start_time"] = env.unwrapped.options.start_time
        if isinstance(policy, ValueIterationPolicy):
            data["plan"] = policy.result

    def plots(self, folder, name, data):
        from bounce_gym_experiments.plots.drifters import plot_flow, plot_policy

        if "model" not in data:
            return []
        written = [plot_flow(data["world"], folder / f"{name}-flow.png",
                             t=data["start_time"])]
        if data.get("plan") is not None:
            written.append(plot_policy(data["model"], data["plan"],
                                       folder / f"{name}-policy.png"))
        return written


#: the planners ``planner_kwargs.models`` may name
PLANNER_MODELS = ("cell", "sampled")


def drifter_planners(experiment: Mapping) -> list[Policy]:
    """The planner rows of a reach experiment (module docstring): Alg. 5.5 on the cell model
    and/or the finite-horizon plan on the sampled GCM."""
    models, sampled = drifter_planner_options(experiment)
    out: list[Policy] = []
    if "cell" in models:
        out.append(ValueIterationPolicy())
    if "sampled" in models:
        out.append(HorizonReachPolicy(experiment["max_steps"], **sampled))
    return out


def drifter_planner_options(experiment: Mapping) -> tuple[list[str], dict]:
    """The planners ``planner_kwargs.models`` names (default: the cell model's) and the
    options of the sampled one, checked."""
    kwargs = dict(experiment.get("planner_kwargs", {}))
    models = kwargs.pop("models", ["cell"])
    sampled = {key: kwargs.pop(key) for key in ("samples", "seed", "refine") if key in kwargs}
    if kwargs:
        raise ConfigError(f"planner_kwargs: unknown {sorted(kwargs)}; allowed are models, "
                          "samples, seed, refine")
    if not isinstance(models, list) or not models or any(m not in PLANNER_MODELS
                                                         for m in models):
        raise ConfigError(f"planner_kwargs.models: expected a non-empty list of "
                          f"{list(PLANNER_MODELS)}, got {models!r}")
    return models, sampled


FAMILY = DrifterReach()
