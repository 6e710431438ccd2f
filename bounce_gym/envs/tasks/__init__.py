"""Tasks: the part of an environment that owns reward, termination and task diagnostics.

The environment owns physics, observation and rendering; after every step it hands the task a
`StepEvents` record. Within one env step every robot rotates at most once (at the start) and then
drives straight, so its path is the segment ``start → end``; tasks integrate over it.

* `FreeTask` — no reward, never ends (rollouts, demos).
* `NavigationTask` — reach a goal pose; reward ``progress`` (default: success plus
  potential-based shaping by the geodesic distance to the goal), ``sparse`` or ``plan_cost``
  (−w1 per tick, −(w2 − w1) per change of bounce angle, a bonus at the goal: the weights of the
  roadmap of Alam, Bobadilla & Shell 2017, Alg. 1, w1 = 1, w2 = 100); ``info["plan_cost"]``
  reports the papers' cost whatever the reward.
* `GoalNavigationTask` — navigation between poses of the cell model that the model joins, with
  the sparse reward and the poses each step passes (the goal-conditioned ``-v1`` task).
* `CoverageTask` — match a target distribution over cells (uniform by default): reward for newly
  covered cells and for reducing the L2 distance between the visit histogram (time spent per cell)
  and the target (thesis §3.4.3, Eq. 3.8's objective; Alam, Bobadilla & Shell 2017, Eq. 5).
* `LocalizationTask` — the robot starts at an unknown pose; a localization filter plugged in
  through ``filter_factory`` (``"combinatorial"``: the built-in one, on the env's cell model)
  reports how much the robot can know; reward: bits of uncertainty removed minus a cost per
  tick until localized.
* `MonitoringTask` (multi-robot) — each robot keeps to its own region; robot–robot contacts cost.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping

from bounce_gym.envs.tasks.base import FreeTask, StepEvents, Task
from bounce_gym.envs.tasks.coverage import CoverageTask
from bounce_gym.envs.tasks.goal_navigation import GoalNavigationTask
from bounce_gym.envs.tasks.localization import LocalizationTask
from bounce_gym.envs.tasks.monitoring import MonitoringTask
from bounce_gym.envs.tasks.navigation import NavigationTask
from bounce_gym.errors import ConfigError
from bounce_gym.validate import unexpected

TASKS: dict[str, type[Task]] = {
    "free": FreeTask,
    "navigation": NavigationTask,
    "goal_navigation": GoalNavigationTask,
    "coverage": CoverageTask,
    "localization": LocalizationTask,
    "monitoring": MonitoringTask,
}

__all__ = ["TASKS", "CoverageTask", "FreeTask", "GoalNavigationTask", "LocalizationTask",
           "MonitoringTask", "NavigationTask", "StepEvents", "Task", "make_task"]


def make_task(task: object, task_kwargs: Mapping | None, allowed: tuple[str, ...]) -> Task:
    """A task from its name (plus keyword arguments) or an instance."""
    if isinstance(task, Task):
        if task_kwargs:
            raise ConfigError("task_kwargs: only allowed together with a task name")
        if task.name not in allowed:
            raise ConfigError(f"task: {task.name!r} is not available here; allowed: {list(allowed)}")
        return task
    if task not in allowed:
        raise ConfigError(f"task: expected one of {list(allowed)} or a Task, got {task!r}")
    if task_kwargs is not None and not isinstance(task_kwargs, Mapping):
        raise ConfigError(f"task_kwargs: expected a dict, got {task_kwargs!r}")
    arguments = inspect.signature(TASKS[task]).parameters
    for name in task_kwargs or {}:  # a misspelled argument names the one meant
        if name not in arguments:
            error = unexpected(f"{TASKS[task].__name__}.__init__", name, arguments)
            raise ConfigError(f"task_kwargs for {task!r}: {error}")
    try:
        return TASKS[task](**dict(task_kwargs or {}))
    except TypeError as exc:
        raise ConfigError(f"task_kwargs for {task!r}: {exc}") from None
