"""Navigation v0 (`bounce_gym.envs.tasks.navigation.NavigationTask`) on the cell backend.

Start and goal are random cells (position and bin), as the NumPy task draws them on the cell
backend. The arrival test of a step — the drive passes within ``goal_radius`` of the goal point
with the heading within tolerance, and the tick it enters — depends only on the cell the drive
starts from and the goal, so it is tabulated by the NumPy batch's `GoalTables` (the NumPy task's
own test) for every goal position, and kept here per drive as the short list of goal positions
it enters; Φ of the ``progress`` reward likewise per (goal position, position).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.envs.goal_tables import GoalTables
from bounce_gym.errors import ConfigError
from bounce_gym.jax import draws
from bounce_gym.jax.tasks.base import CellFreeTask


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
        tables = GoalTables(robots, task)
        every = np.arange(self.n_positions)  # every position a goal
        nodes = tables.node_of_position
        tables.fill(every, nodes)
        near_position, near_tick = _arrivals(tables)
        aligned = tables.aligned.reshape(self.n_bins, self.n_bins)
        if tables.potential is not None and nodes is not None:
            potential = tables.potential.reshape(-1, self.n_positions)[nodes]
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


def _arrivals(tables: GoalTables) -> tuple[np.ndarray, np.ndarray]:
    """Per cell a drive starts from: the goal positions whose region it enters, in order
    (padded with −1), and the step's tick at which it does (the bump's, then the drive's), from
    the filled arrival columns of ``tables``."""
    drive = tables.arrival[:tables.off_cell * tables.n_cells].reshape(tables.n_positions, -1).T
    enters = drive >= 0
    width = max(1, int(enters.sum(axis=1).max()))
    order = np.argsort(~enters, axis=1, kind="stable")[:, :width]  # the goals entered first
    kept = np.take_along_axis(enters, order, axis=1)
    return (np.where(kept, order, -1),
            np.where(kept, np.take_along_axis(drive, order, axis=1) + 1, -1))
