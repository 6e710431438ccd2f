"""Registration of the environments with Gymnasium and PettingZoo (done on ``import bounce_gym``).

Each id is a task an agent can be scored on: what it observes, what its reward makes optimal,
and ONE horizon — the registered ``max_episode_steps`` (``max_cycles`` for the PettingZoo ids),
which training and evaluation both use. Defaults: kinematic backend, bounce mode (one step =
the bump, then the drive to the next contact), Φ = {45°, 90°, 135°}, unless the table says
otherwise. The observation is ``clock`` (ticks since the last bump / max_clock), preceded by
``contact`` only where it can be 0 (tick mode, several robots, turn commands; see
`bounce_gym.envs.core`), then the optional ``history`` and ``privileged`` pose, then the task's
features.

Gymnasium ids (``gym.make(id, **overrides)``):

* ``bounce_gym/Bounce-v0`` — two_rooms, task ``free``; horizon 500 steps. Observation: clock.
  Reward 0 and no end: a sandbox for rollouts and speed, not a task to learn.
* ``bounce_gym/BounceNavigation-v0`` — lab_navigation, task ``navigation`` (random start and
  goal pose per episode), ``history=4``; horizon 200 steps. Observation: clock, the last 4
  (clock, angle) pairs, the start and goal poses. The pose is not observed: on the noise-free
  cell backend it follows from the start pose and every (clock, angle) pair since the start
  (what the roadmap planner tracks), so a policy needs memory of the whole episode — a
  recurrent policy (RecurrentPPO) or ``history`` as long as the episode's bounces; with 4 pairs
  a memoryless policy sees only the recent past. ``privileged=True`` adds the true pose (an
  oracle that needs no memory). Reward ``progress`` (default): +1 on reaching the goal plus
  potential-based shaping by the geodesic distance to the goal, so its optimal policies are
  those of the sparse success reward: reach the goal;
  ``reward="sparse"`` and the papers' ``reward="plan_cost"`` are options
  (`bounce_gym.envs.tasks.navigation`). ``info["plan_cost"]`` is the papers' w1/w2 cost so far,
  whatever the reward.
* ``bounce_gym/BounceNavigation-v1`` — lab_navigation, cell backend, task ``goal_navigation``:
  the navigation of v0 as a goal-conditioned task for learners
  (`bounce_gym.envs.goal_navigation_env.GoalNavigationEnv`); horizon 42 bounces, three times
  the longest optimal plan of the map (14 bounces; mean 4.8). Start and goal poses only where
  the cell model joins them (``info["optimal_bounces"]``: the fewest bounces). Observation: a
  ``Dict`` of ``observation`` (clock and the one-hot cell pose), ``achieved_goal`` (the poses
  the step passed) and ``desired_goal`` (the goal pose); reward 1 on reaching the goal, else 0,
  equal to ``env.compute_reward(achieved_goal, desired_goal, info)`` as SB3's
  ``HerReplayBuffer`` needs.
* ``bounce_gym/BounceCoverage-v0`` — lab_fig1, task ``coverage`` (uniform target); horizon
  500 steps. Observation: clock. Reward: newly covered cells plus the decrease of the L2
  distance between the visit histogram and the target; the (undiscounted) return is the final
  coverage plus the total decrease of that distance, so its optimum covers every cell and ends
  closest to the target. A memoryless stochastic policy (angle i with probability α_i at every
  bump) realises the papers' mixtures of bounce policies; doing better than a mixture needs
  memory.
* ``bounce_gym/BounceLocalization-v0`` — lab_localization_a, cell backend, Φ = {45°, 135°}
  (``Discrete(2)``: the angles the active filter chooses between), task ``localization`` with
  the combinatorial filter; horizon 200 steps. Observation: clock. Reward: the drop in
  log2(candidate configurations) minus 0.1 per tick until localized, so of two episodes that
  localize the faster scores higher; ends when localized. The candidate set — the filter's
  state — depends on the whole observation history, so a policy needs memory (RecurrentPPO, or
  ``history`` as long as the episode).

The free, navigation and coverage ids also have a ``vector_entry_point``: ``gym.make_vec(id,
num_envs=N)`` builds a `bounce_gym.envs.vector_env.BounceVectorEnv` (N robots stepped as one
batch, every task option above included).

PettingZoo ids (``pettingzoo.make("parallel" | "aec", id, **overrides)``), horizon
``max_cycles`` = 500 steps, 4 robots of radius 0.3 that bump into each other; each robot
observes contact and clock:

* ``bounce_gym/MultiBounce-v0`` — grid_15x15, ``free``: reward 0, a sandbox.
* ``bounce_gym/MultiBounceCoverage-v0`` — grid_15x15, shared ``coverage``: the coverage reward
  above, split evenly between the robots.
* ``bounce_gym/MultiBounceMonitoring-v0`` — grid_20x12, ``monitoring``, one region each: per
  step the share of the step's ticks a robot spent in its own region minus a penalty per robot
  contact. In tick mode (how the configs run it) the return counts the ticks spent in the own
  region, so its optimum keeps every robot in its region without contacts; in bounce mode every
  step weighs the same whatever its ticks.

Drifters (thesis ch. 5, `bounce_gym.envs.drifters`): the Gymnasium id ``bounce_gym/Drifter-v0``
(one profiling drifter, scb_like flow, cell backend, reach task; max_episode_steps 200) and the
PettingZoo id ``bounce_gym/MultiDrifter-v0`` (4 drifters covering the surface; max_cycles 500).

Patrolling (Alam 2018 thesis ch. 4, `bounce_gym.envs.patrol`): the PettingZoo id
``bounce_gym/Patrol-v0`` — patrol_15x15, 2 patrollers with a 6-cell sensor on the cell graph
and an adversary that needs 20 steps undetected; zero-sum rewards (capture, success, deterred);
max_cycles 500.
"""

from __future__ import annotations

import warnings

import gymnasium as gym
import pettingzoo

GYM_ENVS: dict[str, tuple[dict[str, object], int]] = {
    "bounce_gym/Bounce-v0": ({"world": "two_rooms", "task": "free"}, 500),
    "bounce_gym/BounceNavigation-v0": (
        {"world": "lab_navigation", "task": "navigation", "history": 4}, 200),
    "bounce_gym/BounceNavigation-v1": (
        {"world": "lab_navigation", "task": "goal_navigation", "backend": "cell"}, 42),
    "bounce_gym/BounceCoverage-v0": ({"world": "lab_fig1", "task": "coverage"}, 500),
    "bounce_gym/BounceLocalization-v0": (
        {"world": "lab_localization_a", "task": "localization", "angles": (45.0, 135.0),
         "backend": "cell",
         "task_kwargs": {"filter_factory": "combinatorial"}}, 200),
}

#: Gymnasium ids whose env is not `BounceEnv` itself, and their entry points
ENTRY_POINTS = {
    "bounce_gym/BounceNavigation-v1": "bounce_gym.envs.goal_navigation_env:GoalNavigationEnv",
}
#: the ids whose envs `BounceVectorEnv` batches (localization's filter is not batched)
VECTOR_ENTRY_POINT = "bounce_gym.envs.vector_env:BounceVectorEnv"
VECTOR_IDS = ("bounce_gym/Bounce-v0", "bounce_gym/BounceNavigation-v0",
              "bounce_gym/BounceCoverage-v0")

PETTINGZOO_ENVS = {
    "bounce_gym/MultiBounce-v0": {"world": "grid_15x15", "task": "free"},
    "bounce_gym/MultiBounceCoverage-v0": {"world": "grid_15x15", "task": "coverage"},
    "bounce_gym/MultiBounceMonitoring-v0": {"world": "grid_20x12", "task": "monitoring"},
}


#: drifter ids (thesis ch. 5): Gymnasium id -> (entry point, max_episode_steps)
DRIFTER_GYM_ENVS = {
    "bounce_gym/Drifter-v0": ("bounce_gym.envs.drifters.env:DrifterEnv", 200),
}
#: drifter PettingZoo ids -> the module with ``parallel_env`` and ``env``
DRIFTER_PETTINGZOO_ENVS = {
    "bounce_gym/MultiDrifter-v0": "bounce_gym.envs.drifters.multi_drifter_v0",
}
#: patrol PettingZoo ids (thesis ch. 4) -> the module with ``parallel_env`` and ``env``
PATROL_PETTINGZOO_ENVS = {
    "bounce_gym/Patrol-v0": "bounce_gym.envs.patrol.patrol_v0",
}


#: the Gymnasium ids of this package (another package's, e.g. ``CartPole-v1``, has none of its
#: tasks, planners or evaluation families)
GYMNASIUM_IDS = (*GYM_ENVS, *DRIFTER_GYM_ENVS)


def is_pettingzoo_id(env_id: str) -> bool:
    """Whether ``env_id`` is one of the multi-robot PettingZoo ids (not a Gymnasium id)."""
    return (env_id in PETTINGZOO_ENVS or env_id in DRIFTER_PETTINGZOO_ENVS
            or env_id in PATROL_PETTINGZOO_ENVS)


def is_drifter_id(env_id: str) -> bool:
    """Whether ``env_id`` is one of the drifter ids (Gymnasium or PettingZoo)."""
    return env_id in DRIFTER_GYM_ENVS or env_id in DRIFTER_PETTINGZOO_ENVS


_ENTRY = {
    "parallel": "bounce_gym.envs.multi_bounce_v0:parallel_env",
    "aec": "bounce_gym.envs.multi_bounce_v0:env",
}


#: Gymnasium's notice on making an id whose newer version is registered: here v0 beside v1 of
#: navigation, two different tasks (v0 kept for reproducibility), so the notice is wrong
OUT_OF_DATE = r"\x1b\[33mWARN: The environment bounce_gym/\w+-v\d+ is out of date"


def register_envs() -> None:
    """Register every environment id (idempotent), and silence Gymnasium's "out of date"
    notice for them (`OUT_OF_DATE`)."""
    warnings.filterwarnings("ignore", message=OUT_OF_DATE, category=DeprecationWarning)
    for env_id, (kwargs, steps) in GYM_ENVS.items():
        if env_id not in gym.registry:
            gym.register(env_id, entry_point=ENTRY_POINTS.get(
                             env_id, "bounce_gym.envs.bounce_env:BounceEnv"),
                         vector_entry_point=VECTOR_ENTRY_POINT if env_id in VECTOR_IDS else None,
                         kwargs=kwargs, max_episode_steps=steps)
    for env_id, (entry_point, steps) in DRIFTER_GYM_ENVS.items():
        if env_id not in gym.registry:
            gym.register(env_id, entry_point=entry_point, max_episode_steps=steps)
    for env_type, registry in (("parallel", pettingzoo.parallel_registry),
                               ("aec", pettingzoo.aec_registry)):
        for env_id, env_kwargs in PETTINGZOO_ENVS.items():
            if env_id not in registry:
                pettingzoo.register(env_type, env_id, entry_point=_ENTRY[env_type],
                                    max_cycles=500, kwargs=env_kwargs)
        for env_id, module in {**DRIFTER_PETTINGZOO_ENVS, **PATROL_PETTINGZOO_ENVS}.items():
            if env_id not in registry:
                function = "parallel_env" if env_type == "parallel" else "env"
                pettingzoo.register(env_type, env_id, entry_point=f"{module}:{function}",
                                    max_cycles=500)
