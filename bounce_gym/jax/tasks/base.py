"""The task protocol of the functional cell env (`bounce_gym.jax.cell_env.CellEnv`).

A task is a Python object holding its static configuration; its arrays travel in the env's
``params`` (``params.task``) and its per-episode state in the env state (``state.task``). Every
method is a pure function of arrays.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from bounce_gym.jax import draws


class CellStep(NamedTuple):
    """What one bounce-mode step of a lone robot did on the cell backend."""

    before: jax.Array  # cell number at the start of the step (in contact)
    action: jax.Array  # the action index
    turned: jax.Array  # the cell the bump turned the robot to
    after: jax.Array  # the cell the drive stopped in
    ticks: jax.Array  # the step's ticks: the bump and the drive
    episode_ticks: jax.Array  # the episode's ticks after the step
    changed: jax.Array  # the bounce angle differs from the last one used


class CellFreeTask:
    """No reward, never terminates, no features (the ``free`` task)."""

    name = "free"
    #: observation features the task appends
    observation_size = 0

    def params(self):
        return ()

    def draw(self, key: jax.Array, params, tables) -> tuple[jax.Array, object]:
        """A random start cell (before the reset's drive) and what else the task draws."""
        return draws.index(draws.uniforms(key, 1)[0], tables.drive_end.shape[0]), ()

    def given(self, start: jax.Array, goal, params) -> object:
        """What `draw` would have drawn besides the start, for a given ``goal`` (None if the
        task has none)."""
        return ()

    def start(self, drawn, start: jax.Array, z: jax.Array, ticks: jax.Array, params):
        """The task state of an episode drawn as ``drawn`` from cell ``start``, whose reset
        drive stopped in cell ``z`` after ``ticks``."""
        return ()

    def step(self, state, step: CellStep, params):
        """(task state, reward, terminated, info) after ``step``."""
        return state, jnp.float32(0.0), jnp.bool_(False), {}

    def info(self, state, z: jax.Array, params) -> dict:
        return {}

    def features(self, state, params) -> jax.Array | None:
        return None

    def observe(self, sensed: jax.Array, state, params):
        """The observation: what the robot sensed, then the task's features."""
        features = self.features(state, params)
        return sensed if features is None else jnp.concatenate([sensed, features])
