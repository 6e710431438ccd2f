"""Navigation: reach the goal pose; the roadmap planner over (cell, bounce angle) and its
predicted cost (`baselines.navigation.NavigationPlanner`), and the stochastic shortest path on
the GCM sampled from the env's own dynamics (`baselines.navigation.sampled`).

Planners (``planner_kwargs``, all optional): ``models`` lists which of `PLANNER_MODELS` run —
``roadmap``, the papers' plan on the env's cell model run open loop (row "roadmap planner"), and
``roadmap_pose``, the same plan replanned from the true pose in ``info`` whenever the clock
departs from it (row "roadmap planner (pose observed)": privileged, the planner beside learners
that observe their pose, as on ``BounceNavigation-v1`` off the cell backend), and
``sampled``, `SampledNavigationPlanner` closed loop on its particle belief (row "sampled-gcm");
default ``[roadmap]``. The sampled planner's options `SAMPLED_OPTIONS` (``samples``, ``seed``,
``particles``, ``draws``, ``depth``, ``reach``, ``cell_size``, ``rollouts``) are passed to it; its
horizon is the experiment's ``max_steps``.

Per episode:

* ``success`` — the goal was reached; ``ticks_to_goal`` — when (successful episodes only);
* on the goal-conditioned ``BounceNavigation-v1``: ``optimal_bounces``, the fewest bounces the
  env's cell model needs for the episode's start and goal, and ``bounce_ratio``, the bounces
  the policy took over that (successful episodes only; 1 is optimal);
* ``feasible`` — the planner's model says the episode can be solved at all: on the roadmap of
  the env's cell model (Alam, Bobadilla & Shell 2017, Sec. IV) some plan leads from the start
  cell to a goal cell. Random start/goal pairs are often not connected for a given Φ, and a
  policy cannot be blamed for those; ``success_feasible`` is ``success`` on the feasible
  episodes only (absent on the others), so its count is the number of feasible episodes;
* ``plan_cost`` — the papers' cost of the executed episode, w1 per tick plus w2 per change of
  bounce angle, as the env reports it (``info["plan_cost"]``, absent from envs that do not);
* for the roadmap planner, ``predicted_ticks`` and ``predicted_weight`` of its plan; for the
  sampled planner ``predicted_success``, its model's probability of reaching the goal within the
  horizon from its first belief (its mean over the episodes is the model's prediction of
  ``success``).

Feasibility needs the roadmap, so it is measured where the planner can run (discrete actions,
bounce steps); the first policy to meet a start/goal pair asks the roadmap, the others reuse the
answer.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from baselines.policy import Policy
from bounce_gym import validate
from bounce_gym.envs.registration import is_pettingzoo_id
from bounce_gym.errors import ConfigError
from bounce_gym_experiments.families.base import Episode, SingleRobotFamily, env_task

#: the planners ``planner_kwargs.models`` may name
PLANNER_MODELS = ("roadmap", "roadmap_pose", "sampled")
#: the row of the roadmap planner that replans from the true pose (a privileged variant)
POSE_NAME = "roadmap planner (pose observed)"
#: the options of the sampled planner ``planner_kwargs`` may set
SAMPLED_OPTIONS = ("samples", "seed", "particles", "draws", "depth", "reach", "cell_size",
                   "rollouts")
#: the least value of the sampled planner's counts (the others: 1)
MINIMUM = {"samples": 2, "seed": 0}
#: the sampled planner's row
SAMPLED_NAME = "sampled-gcm"


class Feasibility:
    """Whether the roadmap has a plan from the env's current start to its goal, remembered per
    (start, goal) pose pair."""

    def __init__(self) -> None:
        from baselines.navigation import NavigationPlanner

        self.probe = NavigationPlanner()
        self.known: dict[bytes, bool] = {}

    def __call__(self, env) -> bool:
        task = env.unwrapped.task
        key = np.concatenate([np.ravel(task.start[0]), np.ravel(task.start[1]),
                              np.ravel(task.goal[0]), np.ravel(task.goal[1])]).tobytes()
        if key not in self.known:
            self.probe.reset(env.unwrapped)
            self.known[key] = self.probe.plan is not None
        return self.known[key]


class NavigationEpisode(Episode):
    def __init__(self, env, feasibility: Feasibility | None) -> None:
        self.env = env
        self.feasibility = feasibility
        self.feasible: bool | None = None

    def start(self, info):
        if self.feasibility is not None:
            self.feasible = self.feasibility(self.env)
        return False

    def metrics(self, info):
        out = {"success": bool(info.get("is_success", False))}
        if self.feasible is not None:
            out["feasible"] = self.feasible
            if self.feasible:
                out["success_feasible"] = out["success"]
        if "ticks_to_goal" in info:
            out["ticks_to_goal"] = info["ticks_to_goal"]
        if info.get("optimal_bounces", -1) > 0:  # the goal-conditioned task (v1)
            out["optimal_bounces"] = int(info["optimal_bounces"])
            if out["success"]:
                out["bounce_ratio"] = info["bumps"] / info["optimal_bounces"]
        if info.get("plan_cost") is not None:
            out["plan_cost"] = float(info["plan_cost"])
        return out


class Navigation(SingleRobotFamily):
    name = task = "navigation"
    columns = (*SingleRobotFamily.columns, "success", "feasible", "success_feasible",
               "predicted_success", "ticks_to_goal", "bounce_ratio", "optimal_bounces",
               "plan_cost", "predicted_ticks", "predicted_weight")
    score = "success"
    planner_attributes = ("predicted_success", "predicted_ticks", "predicted_weight")
    takes_planner_kwargs = True
    #: the tasks of the navigation ids (v0, and v1's goal-conditioned one)
    tasks = ("navigation", "goal_navigation")

    def claims(self, experiment):
        return not is_pettingzoo_id(experiment["env"]) and env_task(experiment) in self.tasks

    def validate(self, experiment):
        super().validate(experiment)
        navigation_planner_options(experiment)

    def prepare(self, env, experiment):
        options = env.unwrapped.options
        if options.action_type != "discrete" or options.step_mode != "bounce":
            return None
        return Feasibility()

    def policies(self, kind, env, experiment, setup):
        if kind != "planner":
            return super().policies(kind, env, experiment, setup)
        if env.unwrapped.options.action_type != "discrete":
            return []
        return navigation_planners(experiment)

    def episode(self, env, policy, setup):
        return NavigationEpisode(env, setup)


def navigation_planners(experiment: Mapping) -> list[Policy]:
    """The planner rows of a navigation experiment (module docstring), checked before any
    episode runs."""
    from baselines.navigation import NavigationPlanner
    from baselines.navigation.sampled import SampledNavigationPlanner

    models, kwargs = navigation_planner_options(experiment)
    out: list[Policy] = []
    if "roadmap" in models:
        out.append(NavigationPlanner())
    if "roadmap_pose" in models:
        privileged = NavigationPlanner(replan_from_info=True)
        privileged.name = POSE_NAME
        out.append(privileged)
    if "sampled" in models:
        sampled = SampledNavigationPlanner(horizon=experiment["max_steps"], **kwargs)
        sampled.name = SAMPLED_NAME
        out.append(sampled)
    return out


def navigation_planner_options(experiment: Mapping) -> tuple[list[str], dict]:
    """The planners ``planner_kwargs.models`` names (default: the roadmap planner) and the
    sampled planner's options, checked before any env is built."""
    kwargs = dict(experiment.get("planner_kwargs", {}))
    models = kwargs.pop("models", ["roadmap"])
    unknown = sorted(key for key in kwargs if key not in SAMPLED_OPTIONS)
    if unknown:
        raise ConfigError(f"planner_kwargs: unknown {unknown}; allowed are models, "
                          f"{', '.join(SAMPLED_OPTIONS)}")
    if not isinstance(models, list) or not models or len(set(map(str, models))) != len(models) \
            or any(m not in PLANNER_MODELS for m in models):
        raise ConfigError(f"planner_kwargs.models: expected a non-empty list of distinct "
                          f"{list(PLANNER_MODELS)}, got {models!r}")
    if kwargs and "sampled" not in models:
        raise ConfigError(f"planner_kwargs: {sorted(kwargs)} are options of the sampled planner; "
                          "add 'sampled' to planner_kwargs.models")
    return models, _sampled_options(kwargs)


def _sampled_options(kwargs: Mapping) -> dict:
    """The sampled planner's options, checked: whole counts (``samples`` at least 2, ``seed`` at
    least 0, the others at least 1), ``cell_size`` a positive number, ``rollouts`` a flag."""
    out = {}
    for key, value in kwargs.items():
        where = f"planner_kwargs.{key}"
        if key == "rollouts":
            out[key] = validate.flag(where, value)
        elif key == "cell_size":
            out[key] = validate.number(where, value, minimum=0, strict=True)
        else:
            out[key] = validate.integer(where, value, minimum=MINIMUM.get(key, 1))
    return out


FAMILY = Navigation()
