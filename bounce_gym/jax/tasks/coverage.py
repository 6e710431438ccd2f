"""Coverage (`bounce_gym.envs.tasks.coverage.CoverageTask`) on the cell backend.

What a step adds to the visit histogram — the coverage grid's cells along its path and the
ticks spent in each — depends only on the cell the step starts in and the action, so it is
tabulated in NumPy by the NumPy task's own functions (`bounce_gym.envs.tasks.base.path_samples`
on the step's segment, then `CoverageTask.cells`) as a padded list of (grid index, ticks) per
(cell, action); a reset marks the grid cell of its first contact visited with no ticks. The
state is the histogram and the visited mask; the reward and ``info`` are the NumPy task's,
computed in float32.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.envs.tasks.base import StepEvents, path_samples, tick_length
from bounce_gym.jax.tasks.base import CellFreeTask


class CoverageParams(NamedTuple):
    index: jax.Array  # (n_cells · n_actions, L) grid cells a step visits (padding: grid size)
    ticks: jax.Array  # (n_cells · n_actions, L) float32 ticks it spends in each
    start: jax.Array  # (n_cells,) the grid cell of a robot in contact in each cell
    free: jax.Array  # (grid size,) free grid cells
    target: jax.Array  # (grid size,) float32 target distribution
    weights: jax.Array  # float32 (coverage_weight, distance_weight, number of free cells)


class CoverageState(NamedTuple):
    visits: jax.Array  # (grid size,) float32 ticks spent per grid cell
    visited: jax.Array  # (grid size,) bool
    distance: jax.Array  # float32 L2 distance of the normalised histogram to the target


class CellCoverageTask(CellFreeTask):
    """The coverage task of ``task`` (a configured NumPy `CoverageTask`) for the robots of
    ``robots`` (`CellRobots`, whose per (cell, action) steps it tabulates)."""

    name = "coverage"

    def __init__(self, task, robots) -> None:
        self.size = int(task.free.size)
        self.n_actions = robots.n_actions
        self._params = _tables(task, robots)

    def params(self) -> CoverageParams:
        return self._params

    def start(self, drawn, start, z, ticks, params):
        visited = jnp.zeros(self.size, bool).at[params.start[z]].set(True)
        state = CoverageState(visits=jnp.zeros(self.size, jnp.float32), visited=visited,
                              distance=jnp.float32(0.0))
        return state._replace(distance=self._measure(state, params)[1])

    def step(self, state, step, params):
        at = step.before * self.n_actions + step.action
        index = params.index[at]
        fresh = ~state.visited.at[index].get(mode="fill", fill_value=True) \
            & params.free.at[index].get(mode="fill", fill_value=False)
        moved = CoverageState(visits=state.visits.at[index].add(params.ticks[at], mode="drop"),
                              visited=state.visited.at[index].set(True, mode="drop"),
                              distance=state.distance)
        coverage, distance, tv = self._measure(moved, params)
        coverage_weight, distance_weight, n_free = params.weights
        reward = (coverage_weight * fresh.sum().astype(jnp.float32) / n_free
                  + distance_weight * (state.distance - distance))
        info = {"coverage": coverage, "distance": distance, "tv_distance": tv}
        return moved._replace(distance=distance), reward, jnp.bool_(False), info

    def info(self, state, z, params):
        coverage, distance, tv = self._measure(state, params)
        return {"coverage": coverage, "distance": distance, "tv_distance": tv}

    def _measure(self, state, params):
        """(coverage, L2 distance, total variation distance) of a state."""
        total = state.visits.sum()
        hist = jnp.where(total > 0, state.visits / jnp.where(total > 0, total, 1.0), 0.0)
        gap = hist - params.target
        coverage = (state.visited & params.free).sum().astype(jnp.float32) / params.weights[2]
        return coverage, jnp.sqrt(jnp.sum(gap * gap)), 0.5 * jnp.abs(gap).sum()


def _tables(task, robots) -> CoverageParams:
    """Every (cell, action) step of ``robots`` as the NumPy task sees it — from the cell's
    centre, bump tick first, to the centre of the cell its drive stops in, heading as the drive
    — through `path_samples` and `CoverageTask.cells`, summed per grid cell."""
    n_steps = robots.step_end.size
    before = np.repeat(np.arange(robots.model.n_cells), robots.n_actions)
    after = robots.step_end
    events = StepEvents(
        ticks=robots.step_ticks + 1, start=robots.centre_of[before], end=robots.centre_of[after],
        heading=robots.heading_of[after], bumps=np.ones(n_steps, dtype=np.int64),
        angles=np.zeros(n_steps), angle_changed=np.zeros(n_steps, dtype=bool),
        robot_contact=np.zeros(n_steps, dtype=bool))
    step, points, ticks = path_samples(events, tick_length(task.options, events.heading),
                                       task.cell_size / 4)
    size = task.free.size
    row, col = task.cells(points)
    keys, inverse = np.unique(step * size + row * task.free.shape[1] + col, return_inverse=True)
    spent = np.zeros(len(keys))
    np.add.at(spent, inverse.reshape(-1), ticks)
    owner, cell = np.divmod(keys, size)
    count = np.bincount(owner, minlength=n_steps)
    slot = np.arange(len(keys)) - np.repeat(np.cumsum(count) - count, count)
    index = np.full((n_steps, max(1, int(count.max()))), size, dtype=np.int64)
    per_step = np.zeros(index.shape)
    index[owner, slot] = cell
    per_step[owner, slot] = spent
    row, col = task.cells(robots.centre_of)
    return CoverageParams(
        index=jnp.asarray(index, jnp.int32), ticks=jnp.asarray(per_step, jnp.float32),
        start=jnp.asarray(row * task.free.shape[1] + col, jnp.int32),
        free=jnp.asarray(task.free.ravel()), target=jnp.asarray(task.target.ravel(), jnp.float32),
        weights=jnp.asarray([task.coverage_weight, task.distance_weight, task.free.sum()],
                            jnp.float32))
