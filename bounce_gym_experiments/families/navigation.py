"""Navigation: reach the goal pose; the roadmap planner over (cell, bounce angle) and its
predicted cost (`baselines.navigation.NavigationPlanner`), and the stochastic shortest path on
the GCM sampled from the env's own dynamics (`baselines.navigation.sampled`).

Planners (``planner_kwargs``, all optional): ``models`` lists which of `PLANNER_MODELS` run —
``roadmap``, the papers' plan on the env's cell model run open loop (row "roadmap planner"; on
a continuous backend "roadmap planner (open loop)"), ``roadmap_pose``, the same plan replanned
from the true pose in ``info`` whenever the clock departs from it (row "roadmap planner (pose
observed)": privileged, the planner beside learners that observe their pose, as on
``BounceNavigation-v1`` off the cell backend), ``sampled``, `SampledNavigationPlanner` closed
loop on its particle belief (row "sampled-gcm"), and ``search``, `ContinuousNavigationPlanner`
restricted to Φ (row "search planner": closed loop from contact and clock, searching the
simulator — on pymunk's dynamic physics the tabulated bump map — from its belief). These take
discrete actions; on an env with ``action_type: continuous`` the model is ``continuous``,
`ContinuousNavigationPlanner` choosing every bounce angle from the continuous range (row
"continuous-angle planner"). Without ``models`` an experiment runs the planner that works on its
motion model (`default_planner_models`): the roadmap on the cell backend, elsewhere ``search``
(``continuous`` with continuous actions; ``roadmap_pose`` on v1). Every planner's horizon is the
experiment's ``max_steps``; the sampled planner's options `SAMPLED_OPTIONS` (``samples``,
``seed``, ``particles``, ``draws``, ``depth``, ``reach``, ``cell_size``, ``rollouts``) are
passed to it.

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

* ``world_reachable`` (on the kinematic backend and on pymunk's dynamic physics, whose walks
  read the tabulated bump map and replay a hit in the simulator; on pymunk's ideal physics the
  walks' 200,000 simulated bumps per pair take too long) — random walks from the start with the
  env's own actions (angles uniform in the continuous range, or uniform among Φ), simulated in
  the noise-free world, pass through the goal
  (`baselines.navigation.reachability.world_reachable`: no planner is asked, and a pair it
  misses may still be reachable); ``success_world_reachable`` is ``success`` on those episodes.

Feasibility needs the roadmap, so it is measured in bounce steps (with continuous actions, for
the roadmap of the env's Φ: "cell-feasible"); the first policy to meet a start/goal pair asks
the roadmap and the random walks, the others reuse the answers.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from baselines.policy import Policy
from bounce_gym import validate
from bounce_gym.envs.registration import is_pettingzoo_id
from bounce_gym.errors import ConfigError
from bounce_gym_experiments.families.base import (
    Episode,
    SingleRobotFamily,
    env_option,
    env_task,
)

#: the planners ``planner_kwargs.models`` may name
PLANNER_MODELS = ("roadmap", "roadmap_pose", "sampled", "search", "continuous")
#: the planners of envs with continuous actions
CONTINUOUS_MODELS = ("continuous",)
#: the roadmap's row on a continuous backend, where its plan (made on the cell model) runs open
#: loop from the observations
OPEN_LOOP_NAME = "roadmap planner (open loop)"
#: the search planner's row: `ContinuousNavigationPlanner` restricted to the env's Φ
SEARCH_NAME = "search planner"
#: the row of the roadmap planner that replans from the true pose (a privileged variant)
POSE_NAME = "roadmap planner (pose observed)"
#: the options of the sampled planner ``planner_kwargs`` may set
SAMPLED_OPTIONS = ("samples", "seed", "particles", "draws", "depth", "reach", "cell_size",
                   "rollouts")
#: the least value of the sampled planner's counts (the others: 1)
MINIMUM = {"samples": 2, "seed": 0}
#: the sampled planner's row
SAMPLED_NAME = "sampled-gcm"
#: the seed of the random walks of the world-reachability check
WALK_SEED = 0
#: the motion models (backend, physics) whose walks play the check's 200,000 bumps per pair in
#: about a second: the kinematic simulator, pymunk's dynamic physics through the bump table
WALK_MODELS = (("kinematic", "ideal"), ("pymunk", "dynamic"))


def _pair(env) -> bytes:
    task = env.unwrapped.task
    return np.concatenate([np.ravel(task.start[0]), np.ravel(task.start[1]),
                           np.ravel(task.goal[0]), np.ravel(task.goal[1])]).tobytes()


class Feasibility:
    """Whether the roadmap of the env's cell model and Φ has a plan from the env's current start
    to its goal (as `NavigationPlanner` plans it), remembered per (start, goal) pose pair."""

    def __init__(self) -> None:
        self.known: dict[bytes, bool] = {}
        self._roadmap = None

    def __call__(self, env) -> bool:
        key = _pair(env)
        if key not in self.known:
            self.known[key] = self._has_plan(env.unwrapped)
        return self.known[key]

    def _has_plan(self, env) -> bool:
        from baselines.navigation import Roadmap, goal_cells

        task, model = env.task, env.cell_model()
        if self._roadmap is None or self._roadmap.model is not model:
            degrees = np.round(np.degrees(env.options.angles[0]), 9)
            self._roadmap = Roadmap(model, degrees, task.w1, task.w2)
        start = int(model.cell_of(task.start[0], task.start[1])[0])
        goals = goal_cells(model, task.goal[0][0], float(task.goal[1][0]), task.goal_radius,
                           task.heading_tolerance)
        return start >= 0 and len(goals) > 0 and self._roadmap.bounce_plan(start, goals) is not None


class WorldReachability:
    """Whether random walks with the env's actions reach its current goal from its start in the
    noise-free world (`baselines.navigation.reachability`), remembered per pair."""

    def __init__(self, bumps: int) -> None:
        self.bumps = int(bumps)
        self.known: dict[bytes, bool] = {}

    def __call__(self, env) -> bool:
        from baselines.navigation.reachability import noise_free, world_reachable
        from baselines.navigation.shots import GoalRegion
        from bounce_gym.dynamics.bump_table import bump_motion

        key = _pair(env)
        if key not in self.known:
            env = env.unwrapped
            task, options = env.task, env.options
            motion = bump_motion(env.cell_model(), noise_free(options.robot_dynamics))
            goal = GoalRegion(np.asarray(task.goal[0][0], dtype=np.float64),
                              float(task.goal[1][0]), task.goal_radius, task.heading_tolerance)
            phi = None if options.action_type == "continuous" else options.angles[0]
            self.known[key] = world_reachable(
                motion, (task.start[0][0], float(task.start[1][0])), goal,
                options.angle_range[0], self.bumps, WALK_SEED, phi=phi).reached
        return self.known[key]


class NavigationChecks:
    """What an episode's start/goal pair is measured by besides the policy: the roadmap's
    feasibility and, with continuous actions, the world-reachability check (None: not
    measured)."""

    def __init__(self, feasibility: Feasibility | None,
                 reachability: WorldReachability | None) -> None:
        self.feasibility, self.reachability = feasibility, reachability


class NavigationEpisode(Episode):
    def __init__(self, env, checks: NavigationChecks | None) -> None:
        self.env = env
        self.checks = checks
        self.feasible: bool | None = None
        self.reachable: bool | None = None

    def start(self, info):
        if self.checks is not None and self.checks.feasibility is not None:
            self.feasible = self.checks.feasibility(self.env)
        if self.checks is not None and self.checks.reachability is not None:
            self.reachable = self.checks.reachability(self.env)
        return False

    def metrics(self, info):
        out = {"success": bool(info.get("is_success", False))}
        if self.feasible is not None:
            out["feasible"] = self.feasible
            if self.feasible:
                out["success_feasible"] = out["success"]
        if self.reachable is not None:
            out["world_reachable"] = self.reachable
            if self.reachable:
                out["success_world_reachable"] = out["success"]
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
               "world_reachable", "success_world_reachable", "predicted_success", "ticks_to_goal",
               "bounce_ratio", "optimal_bounces", "plan_cost", "predicted_ticks", "predicted_weight")
    score = "success"
    planner_attributes = ("predicted_success", "predicted_ticks", "predicted_weight")
    takes_planner_kwargs = True
    #: the tasks of the navigation ids (v0, and v1's goal-conditioned one)
    tasks = ("navigation", "goal_navigation")

    def claims(self, experiment):
        return not is_pettingzoo_id(experiment["env"]) and env_task(experiment) in self.tasks

    def validate(self, experiment):
        super().validate(experiment)
        models, _ = navigation_planner_options(experiment)
        continuous = experiment.get("env_kwargs", {}).get("action_type") == "continuous"
        named = "models" in experiment.get("planner_kwargs", {})
        if named and any((m in CONTINUOUS_MODELS) != continuous for m in models):
            raise ConfigError(f"planner_kwargs.models: {list(CONTINUOUS_MODELS)} take continuous "
                              f"actions, the others discrete ones; env_kwargs.action_type is "
                              f"{'continuous' if continuous else 'discrete'}, got {models!r}")

    def prepare(self, env, experiment):
        options = env.unwrapped.options
        if options.step_mode != "bounce":
            return None
        walks = options.backend != "cell" and (options.backend, options.physics) in WALK_MODELS
        return NavigationChecks(Feasibility(), WorldReachability(experiment["max_steps"])
                                if walks else None)

    def policies(self, kind, env, experiment, setup):
        if kind != "planner":
            return super().policies(kind, env, experiment, setup)
        continuous = env.unwrapped.options.action_type == "continuous"
        return [policy for model, policy in navigation_planners(experiment)
                if (model in CONTINUOUS_MODELS) == continuous]

    def episode(self, env, policy, setup):
        return NavigationEpisode(env, setup)


def navigation_planners(experiment: Mapping) -> list[tuple[str, Policy]]:
    """The planner rows of a navigation experiment (module docstring), each with its model's
    name, checked before any episode runs."""
    from baselines.navigation import NavigationPlanner
    from baselines.navigation.continuous import ContinuousNavigationPlanner
    from baselines.navigation.sampled import SampledNavigationPlanner

    models, kwargs = navigation_planner_options(experiment)
    out: list[tuple[str, Policy]] = []
    if "roadmap" in models:
        roadmap = NavigationPlanner()
        if _motion_model(experiment)[0] != "cell":
            roadmap.name = OPEN_LOOP_NAME
        out.append(("roadmap", roadmap))
    if "roadmap_pose" in models:
        privileged = NavigationPlanner(replan_from_info=True)
        privileged.name = POSE_NAME
        out.append(("roadmap_pose", privileged))
    if "sampled" in models:
        sampled = SampledNavigationPlanner(horizon=experiment["max_steps"], **kwargs)
        sampled.name = SAMPLED_NAME
        out.append(("sampled", sampled))
    if "search" in models:
        search = ContinuousNavigationPlanner(horizon=experiment["max_steps"])
        search.name = SEARCH_NAME
        out.append(("search", search))
    if "continuous" in models:
        out.append(("continuous", ContinuousNavigationPlanner(horizon=experiment["max_steps"])))
    return out


def _motion_model(experiment: Mapping) -> tuple[str, str]:
    """The backend and the action type of an experiment's env."""
    return (str(env_option(experiment["env"], experiment["env_kwargs"], "backend")),
            str(env_option(experiment["env"], experiment["env_kwargs"], "action_type")))


def default_planner_models(experiment: Mapping) -> list[str]:
    """The planners an experiment runs when ``planner_kwargs.models`` names none: the one that
    works on its motion model. On the cell backend the papers' roadmap (the cell model is the
    env); on a continuous backend the closed-loop planners — the continuous-angle planner with
    continuous actions, the search planner with Φ on ``BounceNavigation-v0``, and on the
    goal-conditioned v1 (whose learners observe their pose) the roadmap replanned from the true
    pose."""
    backend, action_type = _motion_model(experiment)
    if backend == "cell":
        return ["roadmap"]
    if action_type == "continuous":
        return ["continuous"]
    return ["search"] if env_task(experiment) == "navigation" else ["roadmap_pose"]


def navigation_planner_options(experiment: Mapping) -> tuple[list[str], dict]:
    """The planners ``planner_kwargs.models`` names (default: the roadmap planner) and the
    sampled planner's options, checked before any env is built."""
    kwargs = dict(experiment.get("planner_kwargs", {}))
    models = kwargs.pop("models", None) or default_planner_models(experiment)
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
