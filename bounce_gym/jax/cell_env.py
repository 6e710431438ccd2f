"""`CellEnv`: a lone bouncing robot on the cell backend as a pure JAX function.

The robot is its cell (a position of the `CellModel` and a heading bin). A bounce-mode step is
the bump (one tick, the rotation of the bounce rule) and the drive to the next contact, both
looked up per (cell, action) in `bounce_gym.jax.cell_tables.CellTables`; a reset draws a start
cell and drives to the first contact. The observation is the NumPy env's, value for value:
the clock, the optional sensing history and privileged pose, then the task's features
(`bounce_gym.envs.core`).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from bounce_gym.jax.cell_tables import CellTables
from bounce_gym.jax.environment import Environment
from bounce_gym.jax.tasks.base import CellStep


class Robot(NamedTuple):
    """The robot's state: its cell (in contact), the clock reading (the last drive's ticks),
    the sensing history, the episode's ticks and steps, and the last action (−1: none yet)."""

    z: jax.Array
    clock: jax.Array
    history: jax.Array
    ticks: jax.Array
    steps: jax.Array
    last_action: jax.Array


class CellState(NamedTuple):
    robot: Robot
    task: object


class CellParams(NamedTuple):
    tables: CellTables
    task: object
    max_steps_in_episode: jax.Array


class CellEnv(Environment):
    """A lone robot on the cell backend with a task (`bounce_gym.jax.tasks`).

    Built by `bounce_gym.jax.make` from the NumPy env of the same id and options, whose
    spaces it has (as `bounce_gym.jax.spaces`).
    """

    deterministic_step = True  # a step is table lookups; only resets draw

    def __init__(self, env_id: str, model, tables: CellTables, task, n_actions: int, history: int,
                 privileged: bool, max_steps: int, observation_space, action_space) -> None:
        self.env_id = env_id
        #: the `CellModel` (NumPy) the tables come from
        self.model = model
        self.tables = tables
        self.task = task
        self.n_actions = n_actions
        self.history = history
        self.privileged = privileged
        self.max_steps = max_steps
        self._observation_space = observation_space
        self._action_space = action_space

    @property
    def default_params(self) -> CellParams:
        return CellParams(self.tables, self.task.params(), jnp.int32(self.max_steps))

    def action_space(self, params=None):
        return self._action_space

    def observation_space(self, params=None):
        return self._observation_space

    # -- episodes ---------------------------------------------------------------------------
    def reset_env(self, key: jax.Array, params: CellParams):
        start, drawn = self.task.draw(key, params.task, params.tables)
        return self._start(start, drawn, params)

    def reset_to(self, start, goal=None, params: CellParams | None = None):
        """Start an episode in cell number ``start`` (before its drive to the first contact),
        with goal cell number ``goal`` for a task with goals: the pose
        ``bounce_gym.jax.pose_options`` turns into the NumPy env's ``reset(options=...)``."""
        params = self.default_params if params is None else params
        start = jnp.asarray(start, jnp.int32)
        return self._start(start, self.task.given(start, goal, params.task), params)

    def _start(self, start, drawn, params: CellParams):
        tables = params.tables
        z, ticks = tables.drive_end[start], tables.drive_ticks[start]
        robot = Robot(z=z, clock=ticks, history=jnp.zeros((self.history, 2), jnp.float32),
                      ticks=ticks, steps=jnp.int32(0), last_action=jnp.int32(-1))
        state = CellState(robot, self.task.start(drawn, start, z, ticks, params.task))
        return self._observe(state, params), state

    def step_env(self, key: jax.Array, state: CellState, action, params: CellParams):
        tables = params.tables
        robot = state.robot
        action = jnp.asarray(action, jnp.int32)
        at = robot.z * self.n_actions + action
        drive = tables.step_ticks[at]
        after = tables.step_end[at]
        ticks = drive + 1  # the bump, then the drive
        changed = (robot.last_action >= 0) & ~tables.same_angle[action,
                                                                 jnp.maximum(robot.last_action, 0)]
        history = robot.history
        if self.history:
            newest = jnp.stack([tables.clock_value[robot.clock], tables.turn_value[action]])
            history = jnp.concatenate([newest[None], history[:-1]])
        moved = Robot(z=after, clock=drive, history=history, ticks=robot.ticks + ticks,
                      steps=robot.steps + 1, last_action=action)
        step = CellStep(before=robot.z, action=action, turned=tables.step_turned[at],
                        after=after, ticks=ticks, episode_ticks=moved.ticks, changed=changed)
        task_state, reward, terminated, task_info = self.task.step(state.task, step, params.task)
        truncated = moved.steps >= params.max_steps_in_episode
        next_state = CellState(moved, task_state)
        info = {"ticks": moved.ticks, "clock": drive, "step_ticks": ticks,
                "cell": after, **task_info, "terminated": terminated, "truncated": truncated}
        return (self._observe(next_state, params), next_state, reward, terminated | truncated,
                info)

    # -- sensing ----------------------------------------------------------------------------
    def _observe(self, state: CellState, params: CellParams):
        tables = params.tables
        robot = state.robot
        parts = [tables.clock_value[robot.clock][None]]
        if self.history:
            parts.append(robot.history.reshape(-1))
        if self.privileged:
            parts.append(tables.pose[robot.z])
        return self.task.observe(jnp.concatenate(parts), state.task, params.task)
