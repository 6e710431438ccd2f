"""`make`: the functional JAX env of a Gymnasium id of this package, with its parameters.

The NumPy env of the same id and options is built first: it validates the options (with the
package's one-line errors), and its tables, spaces and horizon are what the JAX env is made of.
The NumPy envs are the reference; the JAX envs are kept equal to them by differential tests
(same start, goal and actions: same observations, rewards and ends).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from bounce_gym.dynamics.noise import Exact
from bounce_gym.envs.tasks.goal_navigation import GoalNavigationTask
from bounce_gym.errors import ConfigError
from bounce_gym.jax import spaces
from bounce_gym.jax.cell_env import CellEnv
from bounce_gym.jax.cell_tables import cell_tables
from bounce_gym.jax.kinematic import kinematic_env
from bounce_gym.jax.kinematic import unsupported as kinematic_unsupported
from bounce_gym.jax.tasks.base import CellFreeTask
from bounce_gym.jax.tasks.coverage import CellCoverageTask
from bounce_gym.jax.tasks.goal_navigation import CellGoalNavigationTask
from bounce_gym.jax.tasks.localization import CellLocalizationTask
from bounce_gym.jax.tasks.navigation import CellNavigationTask

#: the tasks of the cell env, by the NumPy task's name
CELL_TASKS = ("free", "navigation", "goal_navigation", "localization", "coverage")


def make(env_id: str, **options):
    """``(env, params)`` for ``env_id`` (a Gymnasium id of this package) with the NumPy env's
    keyword arguments ``options``; `ConfigError` where no JAX env reproduces it (saying why)."""
    numpy_env = gym.make(env_id, **options)
    try:
        spec = numpy_env.spec  # gym.make sets it; its horizon may be None
        env = _build(env_id, numpy_env.unwrapped,
                     spec.max_episode_steps if spec is not None else None)
    finally:
        numpy_env.close()
    return env, env.default_params


def _build(env_id: str, numpy_env, max_steps: int | None):
    opts = getattr(numpy_env, "options", None)
    if opts is None or not hasattr(numpy_env, "core"):
        raise ConfigError(f"bounce_gym.jax: {env_id!r} has no JAX env (only the single-robot "
                          "bouncing envs do)")
    task = numpy_env.core.task
    name = "goal_navigation" if isinstance(task, GoalNavigationTask) else task.name
    reason = _unsupported(opts, name)
    if reason:
        raise ConfigError(f"bounce_gym.jax: {env_id!r} with these options has no JAX env: "
                          f"{reason}")
    if max_steps is None:
        raise ConfigError(f"bounce_gym.jax: {env_id!r} has no registered horizon "
                          "(max_episode_steps); the JAX env truncates by one")
    if opts.backend == "kinematic":
        return kinematic_env(env_id, numpy_env, int(max_steps),
                             _space(numpy_env.observation_space), _space(numpy_env.action_space))
    tables, robots = cell_tables(numpy_env)
    core = numpy_env.core
    jax_task: CellFreeTask
    if name == "goal_navigation":
        jax_task = CellGoalNavigationTask(task, robots)
    elif name == "navigation":
        jax_task = CellNavigationTask(task, robots, core.obs_low, core.obs_high)
    elif name == "localization":
        jax_task = CellLocalizationTask(task, robots, opts.angles[0])
    elif name == "coverage":
        jax_task = CellCoverageTask(task, robots)
    else:
        jax_task = CellFreeTask()
    return CellEnv(env_id, robots.model, tables, jax_task, len(opts.angles[0]), opts.history,
                   opts.privileged, int(max_steps), _space(numpy_env.observation_space),
                   _space(numpy_env.action_space))


def _unsupported(opts, task: str) -> str | None:
    """Why options cannot be a JAX env, or None."""
    if opts.backend not in ("cell", "kinematic"):
        return f"backend {opts.backend!r} (the JAX envs run the cell and kinematic backends)"
    if opts.backend == "kinematic" and kinematic_unsupported(opts, task):
        return kinematic_unsupported(opts, task)
    if opts.backend == "cell" and task not in CELL_TASKS:
        return f"task {task!r} (the cell env has {list(CELL_TASKS)})"
    if opts.step_mode != "bounce":
        return "step_mode 'tick' (a JAX step is a bounce)"
    if len(opts.turn_angles):
        return "turn commands"
    if not isinstance(opts.noise, Exact):
        return "actuation noise"
    return None


def _space(space):
    """The `bounce_gym.jax.spaces` twin of a Gymnasium space."""
    if isinstance(space, gym.spaces.Discrete):
        return spaces.Discrete(int(space.n))
    if isinstance(space, gym.spaces.Box):
        return spaces.Box(np.asarray(space.low), np.asarray(space.high))
    if isinstance(space, gym.spaces.Dict):
        return spaces.Dict({name: _space(sub) for name, sub in space.spaces.items()})
    raise ConfigError(f"bounce_gym.jax: no JAX twin of space {space!r}")


def pose_options(env: CellEnv, z: int) -> dict:
    """The NumPy env's ``reset(options=...)`` pose of cell number ``z`` of the JAX cell env
    ``env``'s model (its centre and bin heading), to start both envs alike
    (`CellEnv.reset_to`)."""
    centre, heading = env.model.configuration(int(z))
    return {"position": [float(v) for v in centre], "heading": float(heading)}
