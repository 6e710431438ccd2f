"""Goal-conditioned navigation v1 (`bounce_gym.envs.tasks.goal_navigation.GoalNavigationTask`)
on the cell backend: start and goal poses drawn as the NumPy task draws them (``draw``), the
goal reached when a step's drive stops in the goal pose, the sparse reward, and the
goal-conditioned observation (one-hot position and bin of the achieved and desired poses).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.jax import draws
from bounce_gym.jax.tasks.base import CellFreeTask


class GoalParams(NamedTuple):
    starts: jax.Array  # the poses starts are drawn from
    decisions: jax.Array  # the decision poses (goals)
    goal_choices: jax.Array  # (n_cells, C) per first-bump pose: the indices of the goals it
    #                          may draw, in order, padded (C: the most any pose has)
    goal_counts: jax.Array  # (n_cells,) how many goals each first-bump pose may draw
    bounces: jax.Array  # (n_cells, D) fewest bounces from a first-bump pose to each goal (−1)
    goal_index: jax.Array  # per pose: its index among the decision poses (−1)
    reward: jax.Array  # (w1, w2, goal_bonus)


class GoalState(NamedTuple):
    goal: jax.Array
    achieved: jax.Array
    reached: jax.Array
    plan_cost: jax.Array
    optimal_bounces: jax.Array


class CellGoalNavigationTask(CellFreeTask):
    """The v1 task of ``task`` (a configured NumPy `GoalNavigationTask`)."""

    name = "goal_navigation"

    def __init__(self, task, robots) -> None:
        model = task.model
        self.n_positions, self.n_bins = model.n_positions, model.n_bins
        self.reachable = task.draw == "reachable"
        reach = task.reach
        bounces = task.bounces[reach.arrival]  # (n_cells, D): from each start's first bump
        choices = (bounces > 0) & (np.arange(len(reach.decisions))[None, :]
                                   != reach.arrival[:, None])
        counts = choices.sum(axis=1)
        # each pose's goals listed in order: the k-th of a row is what a cumulative search of
        # its row of ``choices`` finds for k, so a draw is one index, O(1) however many goals
        listed = np.zeros((len(choices), max(int(counts.max(initial=0)), 1)), np.int32)
        rows, columns = np.nonzero(choices)
        listed[rows, np.arange(len(rows)) - np.repeat(np.cumsum(counts) - counts, counts)] = \
            columns
        self._params = GoalParams(
            starts=jnp.asarray(task.starts, jnp.int32),
            decisions=jnp.asarray(reach.decisions, jnp.int32),
            goal_choices=jnp.asarray(listed), goal_counts=jnp.asarray(counts, jnp.int32),
            bounces=jnp.asarray(np.where(bounces > 0, bounces, -1), jnp.int32),
            goal_index=jnp.asarray(task.goal_index, jnp.int32),
            reward=jnp.asarray([task.w1, task.w2, task.goal_bonus], jnp.float32))

    def params(self) -> GoalParams:
        return self._params

    def draw(self, key, params, tables):
        u_start, u_goal = draws.uniforms(key, 2)
        if self.reachable:
            start = params.starts[draws.index(u_start, params.starts.shape[0])]
            pick = draws.index(u_goal, params.goal_counts[start])
            goal = params.decisions[params.goal_choices[start, pick]]
        else:
            start = draws.index(u_start, tables.drive_end.shape[0])
            goal = params.decisions[draws.index(u_goal, params.decisions.shape[0])]
        return start, goal

    def given(self, start, goal, params):
        return jnp.asarray(goal, jnp.int32)

    def start(self, drawn, start, z, ticks, params):
        goal = drawn
        return GoalState(goal=goal, achieved=z, reached=jnp.bool_(False),
                         plan_cost=params.reward[0] * ticks.astype(jnp.float32),
                         optimal_bounces=params.bounces[start, params.goal_index[goal]])

    def step(self, state, step, params):
        w1, w2, bonus = params.reward
        hit = step.after == state.goal
        changed = step.changed.astype(jnp.float32)
        reward = bonus * hit.astype(jnp.float32)
        state = state._replace(achieved=step.after, reached=state.reached | hit,
                               plan_cost=state.plan_cost + w1 * step.ticks.astype(jnp.float32)
                               + (w2 - w1) * changed)
        info = {**self.info(state, step.after, params), "angle_changed": step.changed,
                "ticks_to_goal": jnp.where(hit, step.episode_ticks, -1)}
        return state, reward, state.reached, info

    def info(self, state, z, params):
        return {"is_success": state.reached, "plan_cost": state.plan_cost,
                "optimal_bounces": state.optimal_bounces, "goal": state.goal,
                "achieved_goal": state.achieved}

    def one_hot(self, z: jax.Array) -> jax.Array:
        """A pose as a one-hot of its position then a one-hot of its bin."""
        position = jax.nn.one_hot(z % self.n_positions, self.n_positions, dtype=jnp.float32)
        heading = jax.nn.one_hot(z // self.n_positions, self.n_bins, dtype=jnp.float32)
        return jnp.concatenate([position, heading])

    def observe(self, sensed, state, params):
        return {"observation": sensed, "achieved_goal": self.one_hot(state.achieved),
                "desired_goal": self.one_hot(state.goal)}

    def compute_reward(self, achieved_goal, desired_goal, params) -> jax.Array:
        """The step reward of (achieved, desired) one-hot poses (leading dimensions
        broadcast), as `GoalNavigationEnv.compute_reward`."""
        n = self.n_positions
        cell = (achieved_goal[..., :n] * desired_goal[..., :n]).sum(-1) > 0
        heading = (achieved_goal[..., n:] * desired_goal[..., n:]).sum(-1) > 0
        return jnp.where(cell & heading, params.reward[2], 0.0)
