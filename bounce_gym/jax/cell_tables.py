"""The cell backend as device arrays: what a step of a lone robot does, per (cell, action).

Built from the NumPy objects the batched env steps with (`bounce_gym.envs.vector_cells.CellRobots`,
whose tables come from the `CellModel` and `ContactDrives`), so the JAX env and the NumPy envs
read one set of numbers. The float32 values the observation shows (clock readings, history
entries, privileged poses) are tabulated in NumPy with the NumPy env's own arithmetic, so they are
the same bits, not a float32 recomputation.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.envs.vector_cells import CellRobots


class CellTables(NamedTuple):
    """Per cell number z (``n_cells``) and action a, flat at z · n_actions + a:

    * ``step_turned``, ``step_end``, ``step_ticks`` — the cell the bump turns the robot to,
      where the step's drive stops, and the drive's ticks (the step's ticks are one more: the
      bump);
    * ``drive_end``, ``drive_ticks`` (per cell) — the drive to contact of a reset;
    * ``clock_value`` — the observed clock, float32, per clock reading 0 … the longest drive;
    * ``turn_value`` — the history's angle entry (a fraction of a turn) per action;
    * ``same_angle`` — (n_actions, n_actions) whether two actions' angles are equal;
    * ``pose`` — (n_cells, 4) the privileged pose features (x, y scaled to [0, 1], cos, sin);
    * ``position`` — (n_cells,) each cell's position index.
    """

    step_turned: jax.Array
    step_end: jax.Array
    step_ticks: jax.Array
    drive_end: jax.Array
    drive_ticks: jax.Array
    clock_value: jax.Array
    turn_value: jax.Array
    same_angle: jax.Array
    pose: jax.Array
    position: jax.Array


def cell_tables(env) -> tuple[CellTables, CellRobots]:
    """The tables of a `BounceEnv` on the cell backend (``env``: the unwrapped env), and the
    `CellRobots` they come from (its model and drives serve the tasks' tables)."""
    options = env.options
    angles = options.angles[0]
    robots = CellRobots(env.core.dynamics, angles)
    model = robots.model
    longest = int(robots.drive_ticks.max())
    clock = np.minimum(np.arange(longest + 1) / options.max_clock, 1.0).astype(np.float32)
    turns = (np.mod(angles, 2 * np.pi) / (2 * np.pi)).astype(np.float32)
    xmin, ymin, xmax, ymax = options.world.bounds
    pose = np.empty((model.n_cells, 4), dtype=np.float32)
    pose[:, :2] = (robots.centre_of - (xmin, ymin)) / (xmax - xmin, ymax - ymin)
    pose[:, 2] = np.cos(robots.heading_of)
    pose[:, 3] = np.sin(robots.heading_of)
    low, high = env.core.obs_low, env.core.obs_high
    if options.privileged:  # clipped to the observation's bounds, as the NumPy env clips
        col = 1 + 2 * options.history
        pose = np.minimum(np.maximum(pose, low[col:col + 4]), high[col:col + 4])
    i32 = jnp.int32
    tables = CellTables(
        step_turned=jnp.asarray(robots.step_turned, i32),
        step_end=jnp.asarray(robots.step_end, i32),
        step_ticks=jnp.asarray(robots.step_ticks, i32),
        drive_end=jnp.asarray(robots.drive_end, i32),
        drive_ticks=jnp.asarray(robots.drive_ticks, i32),
        clock_value=jnp.asarray(clock),
        turn_value=jnp.asarray(turns),
        same_angle=jnp.asarray(angles[:, None] == angles[None, :]),
        pose=jnp.asarray(pose),
        position=jnp.asarray(robots.position_of, i32),
    )
    return tables, robots
