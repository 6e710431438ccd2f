"""Navigation v0 (`bounce_gym.envs.tasks.navigation.NavigationTask`) on the cell backend.

Start and goal are random cells (position and bin), as the NumPy task draws them on the cell
backend. The arrival test of a step — the drive passes within ``goal_radius`` of the goal point
with the heading within tolerance, and the tick it enters — depends only on the cell the drive
starts from and the goal, so it is tabulated in NumPy by the NumPy task's own test
(`NavigationTask.ticks_to_goal`) for every drive and every goal position it comes near; Φ of the
``progress`` reward likewise per (goal position, position).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.envs.tasks.base import StepEvents
from bounce_gym.errors import ConfigError
from bounce_gym.jax import draws
from bounce_gym.jax.tasks.base import CellFreeTask

#: drives whose nearby goals are found at once
_BLOCK = 256


class CellNavigationParams(NamedTuple):
    near_position: jax.Array  # (n_cells, L) goal positions a drive from each cell comes near (−1)
    near_tick: jax.Array  # (n_cells, L) the step's tick at which it enters their goal region
    aligned: jax.Array  # (n_bins, n_bins) heading bin within tolerance of goal bin
    potential: jax.Array  # (n_positions, n_positions) Φ[goal position, position] (progress)
    start_features: jax.Array  # (n_cells, 4) the start's observation features
    goal_features: jax.Array  # (n_cells, 4) the goal's
    reward: jax.Array  # (w1, w2, goal_bonus, tick_cost, gamma)


class CellNavigationState(NamedTuple):
    start: jax.Array  # start cell (before the reset drive)
    goal: jax.Array  # goal cell
    reached: jax.Array
    plan_cost: jax.Array
    potential: jax.Array  # Φ now


class CellNavigationTask(CellFreeTask):
    """The v0 navigation task of ``task`` (a configured NumPy `NavigationTask`) on the cell
    model of ``robots`` (`CellRobots`)."""

    name = "navigation"

    def __init__(self, task, robots, obs_low: np.ndarray, obs_high: np.ndarray) -> None:
        if not task.random_cells:
            raise ConfigError("bounce_gym.jax: navigation with a fixed start or goal is not "
                              "offered; draw them (the default) or use reset_to")
        model = self.model = robots.model
        self.n_positions, self.n_bins = model.n_positions, model.n_bins
        self.kind = task.reward
        self.observe_task = task.observe_task
        self.observation_size = task.observation_size
        self._params = self._tables(task, robots, obs_low, obs_high)

    def params(self) -> CellNavigationParams:
        return self._params

    def _tables(self, task, robots, low, high) -> CellNavigationParams:
        model = self.model
        z = np.arange(model.n_cells)
        p, k = model.decode(z)
        heading = k * model.bin_width
        near_position, near_tick = _arrivals(task, robots)
        aligned = task.heading_within(np.arange(self.n_bins)[:, None] * model.bin_width,
                                      np.arange(self.n_bins)[None, :] * model.bin_width)
        if task.geodesic is not None:
            node = task.geodesic.node_of(model.centres)
            potential = np.stack([task.goal_potentials(int(g))[node] for g in node])
        else:
            potential = np.zeros((self.n_positions, self.n_positions))
        pose = task.pose_features(model.centres[p], heading).astype(np.float32)
        first = len(low) - task.observation_size  # the features come last
        lo, hi = low[first:], high[first:]
        start_features = np.minimum(np.maximum(pose, lo[:4]), hi[:4])
        goal_features = np.minimum(np.maximum(pose, lo[4:]), hi[4:])
        return CellNavigationParams(
            near_position=jnp.asarray(near_position, jnp.int32),
            near_tick=jnp.asarray(near_tick, jnp.int32),
            aligned=jnp.asarray(aligned), potential=jnp.asarray(potential, jnp.float32),
            start_features=jnp.asarray(start_features), goal_features=jnp.asarray(goal_features),
            reward=jnp.asarray([task.w1, task.w2, task.goal_bonus, task.tick_cost, task.gamma],
                               jnp.float32))

    # -- episodes ---------------------------------------------------------------------------
    def draw(self, key, params, tables):
        # a uniform cell is a uniform position and a uniform bin (the NumPy task's two draws)
        start, goal = draws.index(draws.uniforms(key, 2), self.n_positions * self.n_bins)
        return start, goal

    def given(self, start, goal, params):
        if goal is None:
            raise ConfigError("reset_to: navigation needs a goal cell")
        return jnp.asarray(goal, jnp.int32)

    def start(self, drawn, start, z, ticks, params):
        goal = drawn
        potential = params.potential[goal % self.n_positions, z % self.n_positions]
        return CellNavigationState(start=start, goal=goal, reached=jnp.bool_(False),
                               plan_cost=params.reward[0] * ticks.astype(jnp.float32),
                               potential=potential)

    def step(self, state, step, params):
        w1, w2, bonus, tick_cost, gamma = params.reward
        goal_p, goal_k = state.goal % self.n_positions, state.goal // self.n_positions
        near = params.near_position[step.turned] == goal_p
        arrival = jnp.max(jnp.where(near, params.near_tick[step.turned], -1))
        hit = (arrival >= 0) & params.aligned[step.turned // self.n_positions, goal_k]
        spent = jnp.where(hit, jnp.minimum(step.ticks, arrival), step.ticks).astype(jnp.float32)
        changed = step.changed.astype(jnp.float32)
        if self.kind == "plan_cost":
            reward = -w1 * spent - (w2 - w1) * changed
        else:
            reward = -tick_cost * spent
        reward = reward + bonus * hit
        potential = jnp.where(hit, 0.0, params.potential[goal_p, step.after % self.n_positions])
        if self.kind == "progress":
            reward = reward + (gamma * potential - state.potential)
        state = state._replace(reached=state.reached | hit, potential=potential,
                               plan_cost=state.plan_cost + w1 * spent + (w2 - w1) * changed)
        info = {**self.info(state, step.after, params), "angle_changed": step.changed,
                "ticks_to_goal": jnp.where(hit, step.episode_ticks - step.ticks + arrival, -1)}
        return state, reward, state.reached, info

    def info(self, state, z, params):
        return {"is_success": state.reached, "plan_cost": state.plan_cost,
                "goal": state.goal}

    def features(self, state, params):
        if not self.observe_task:
            return None
        return jnp.concatenate([params.start_features[state.start],
                                params.goal_features[state.goal]])


def _arrivals(task, robots) -> tuple[np.ndarray, np.ndarray]:
    """Per cell a drive starts from: the goal positions whose region it enters (padded with
    −1) and the step's tick at which it does, by `NavigationTask.ticks_to_goal` with the
    heading test passed (each goal given the drive's own heading)."""
    model = robots.model
    n_cells = model.n_cells
    start = robots.centre_of  # the drive starts where the bump left the robot
    end = robots.centre_of[robots.drive_end]
    heading = robots.heading_of
    goals = model.centres
    # a superset of the goals the exact test can accept: within the radius (and a margin far
    # above rounding) of the drive's segment; in blocks of cells, to bound the memory
    close = np.zeros((n_cells, len(goals)), dtype=bool)
    for first in range(0, n_cells, _BLOCK):
        rows = slice(first, first + _BLOCK)
        seg = end[rows] - start[rows]
        rel = goals[None, :, :] - start[rows, None, :]
        length2 = (seg ** 2).sum(axis=1)
        along = np.clip((rel * seg[:, None, :]).sum(axis=2)
                        / np.where(length2 > 0, length2, 1.0)[:, None], 0.0, 1.0)
        gap = rel - along[:, :, None] * seg[:, None, :]
        close[rows] = (gap ** 2).sum(axis=2) <= (task.goal_radius + 1e-6) ** 2
    found: list[list[tuple[int, int]]] = [[] for _ in range(n_cells)]
    for z, g in zip(*np.nonzero(close), strict=True):
        events = StepEvents(ticks=int(robots.drive_ticks[z]) + 1, start=start[z:z + 1],
                            end=end[z:z + 1], heading=heading[z:z + 1],
                            bumps=np.ones(1, dtype=np.int64), angles=np.zeros(1),
                            angle_changed=np.zeros(1, dtype=bool),
                            robot_contact=np.zeros(1, dtype=bool))
        tick = task.ticks_to_goal(events, (goals[g:g + 1], heading[z:z + 1]))
        if tick is not None:
            found[z].append((int(g), int(tick)))
    width = max(1, max(len(f) for f in found))
    near_position = np.full((n_cells, width), -1, dtype=np.int64)
    near_tick = np.full((n_cells, width), -1, dtype=np.int64)
    for z, pairs in enumerate(found):
        for j, (g, tick) in enumerate(pairs):
            near_position[z, j], near_tick[z, j] = g, tick
    return near_position, near_tick
