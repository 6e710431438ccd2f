"""The tasks of the functional kinematic env (`bounce_gym.jax.kinematic.KinematicEnv`).

A task is a Python object holding its static configuration; its arrays travel in the env's
``params`` (``params.task``), its per-episode state in the env state (``state.task``). Each
reproduces the NumPy task of the same name on the kinematic backend, expression for expression,
in the float type JAX is configured for (float64 under ``jax_enable_x64``, as NumPy computes).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.cells.outcomes import GOAL_SLACK
from bounce_gym.errors import ConfigError

#: the most grid nodes whose potential table (nodes × nodes) `KinematicNavigationTask` keeps
MAX_POTENTIAL_NODES = 4096


class KinematicStep(NamedTuple):
    """What one bounce-mode step of a lone robot did: it bumped at ``start`` (2,), turned to
    ``heading`` and drove to ``end`` (2,) in ``ticks`` (the bump and the drive); the episode's
    ticks are ``episode_ticks``; ``changed``: the bounce angle differs from the last one."""

    start: jax.Array
    end: jax.Array
    heading: jax.Array
    ticks: jax.Array
    episode_ticks: jax.Array
    changed: jax.Array


#: draws a uniform pose of the free space: key -> (position (2,), heading)
PoseSampler = Callable[[int], tuple[jax.Array, jax.Array]]


class KinematicFreeTask:
    """No reward, never terminates, no features (the ``free`` task)."""

    name = "free"
    #: observation features the task appends
    observation_size = 0

    def params(self, dtype):
        return ()

    #: the random poses a reset draws (the start, and the goal of a task with one)
    poses_drawn = 1

    def draw(self, params, sample_pose: PoseSampler):
        """A random start pose (position, heading) and what else the task draws;
        ``sample_pose(i)`` is the i-th of the reset's `poses_drawn` random poses."""
        position, heading = sample_pose(0)
        return position, heading, ()

    def given(self, goal_position, goal_heading, params):
        """What `draw` would have drawn besides the start, for a given goal pose (None: the task
        has no goal)."""
        return ()

    def start(self, drawn, position, heading, z_position, ticks, params):
        """The task state of an episode drawn as ``drawn`` from pose (``position``,
        ``heading``), whose reset drive stopped at ``z_position`` after ``ticks``."""
        return ()

    def step(self, state, step: KinematicStep, params):
        """(task state, reward, terminated, info) after ``step``."""
        return state, jnp.zeros((), step.end.dtype), jnp.bool_(False), {}

    def features(self, state, params) -> jax.Array | None:
        return None


class KinematicNavigationParams(NamedTuple):
    reward: jax.Array  # (w1, w2, goal_bonus, tick_cost, gamma)
    goal_radius: jax.Array
    heading_tolerance: jax.Array
    tick_length: jax.Array  # the distance of a drive tick (step_length)
    potential: jax.Array  # (n_nodes, n_nodes) Φ[goal node, node] (progress; else (1, 1) zeros)
    node_of_cell: jax.Array  # (rows · cols,) the grid node of each cell of Φ's grid
    grid_origin: jax.Array  # (2,)
    cell_size: jax.Array
    low: jax.Array  # (2,) the world's lower corner and size, for the features
    span: jax.Array


class KinematicNavigationState(NamedTuple):
    start_position: jax.Array
    start_heading: jax.Array
    goal_position: jax.Array
    goal_heading: jax.Array
    goal_node: jax.Array
    reached: jax.Array
    plan_cost: jax.Array
    potential: jax.Array  # Φ now


class KinematicNavigationTask(KinematicFreeTask):
    """Navigation v0 (`bounce_gym.envs.tasks.navigation.NavigationTask`, the configured
    ``task`` of the NumPy env with `EnvOptions` ``options``) on the kinematic backend.

    Start and goal poses are drawn uniformly in the free space (start first). The goal is
    reached in the step whose drive enters the goal disc with the heading within tolerance
    (`NavigationTask.ticks_to_goal`); Φ of the ``progress`` reward is tabulated per
    (goal node, node) of the task's geodesic grid by the task's own `goal_potentials`, so the
    potentials are its numbers.
    """

    name = "navigation"

    def __init__(self, task, options) -> None:
        kwargs = options.task_kwargs or {}
        if any(kwargs.get(key) is not None for key in ("start", "goal")):
            raise ConfigError("bounce_gym.jax: navigation with a fixed start or goal is not "
                              "offered; draw them (the default) or use reset_to")
        self.kind = task.reward
        self.observe_task = task.observe_task
        self.observation_size = task.observation_size
        xmin, ymin, xmax, ymax = options.world.bounds
        geodesic = task.geodesic
        if geodesic is not None:
            if geodesic.n_nodes > MAX_POTENTIAL_NODES:
                raise ConfigError(
                    f"bounce_gym.jax: the 'progress' reward's potential table has "
                    f"{geodesic.n_nodes} nodes squared entries, more than "
                    f"{MAX_POTENTIAL_NODES} squared; use a larger step_length or "
                    "reward='sparse'")
            rows, cols = geodesic.shape
            size = geodesic.cell_size
            centre = (np.stack(np.meshgrid(np.arange(cols), np.arange(rows)), axis=-1)
                      .reshape(-1, 2) + 0.5) * size + geodesic.origin
            node_of_cell = geodesic.node_of(centre)
            potential = np.stack([task.goal_potentials(g) for g in range(geodesic.n_nodes)])
            origin = geodesic.origin
        else:
            rows, cols, size, origin = 1, 1, 1.0, (0.0, 0.0)
            node_of_cell, potential = np.zeros(1, dtype=np.int64), np.zeros((1, 1))
        self.grid_shape = (rows, cols)
        self._numbers = {
            "reward": [task.w1, task.w2, task.goal_bonus, task.tick_cost, task.gamma],
            "goal_radius": task.goal_radius, "heading_tolerance": task.heading_tolerance,
            "tick_length": options.step_length, "potential": potential,
            "grid_origin": origin, "cell_size": size, "low": [xmin, ymin],
            "span": [xmax - xmin, ymax - ymin]}
        self._node_of_cell = node_of_cell

    def params(self, dtype) -> KinematicNavigationParams:
        reals = {k: jnp.asarray(np.asarray(v, dtype=np.float64), dtype)
                 for k, v in self._numbers.items()}
        return KinematicNavigationParams(node_of_cell=jnp.asarray(self._node_of_cell, jnp.int32), **reals)

    # -- episodes ---------------------------------------------------------------------------
    poses_drawn = 2

    def draw(self, params, sample_pose):
        position, heading = sample_pose(0)
        return position, heading, sample_pose(1)

    def given(self, goal_position, goal_heading, params):
        if goal_position is None or goal_heading is None:
            raise ConfigError("reset_to: navigation needs a goal pose")
        dtype = params.goal_radius.dtype
        return jnp.asarray(goal_position, dtype), jnp.asarray(goal_heading, dtype)

    def start(self, drawn, position, heading, z_position, ticks, params):
        goal_position, goal_heading = drawn
        goal_node = self._node(goal_position, params)
        return KinematicNavigationState(
            start_position=position, start_heading=heading, goal_position=goal_position,
            goal_heading=goal_heading, goal_node=goal_node, reached=jnp.bool_(False),
            plan_cost=params.reward[0] * ticks.astype(params.reward.dtype),
            potential=params.potential[goal_node, self._node(z_position, params)])

    def _node(self, point, params):
        """The grid node of Φ holding ``point`` (`GridGeodesic.node_at`)."""
        rows, cols = self.grid_shape
        cell = jnp.floor((point - params.grid_origin) / params.cell_size)
        col = jnp.clip(cell[0], 0, cols - 1).astype(jnp.int32)
        row = jnp.clip(cell[1], 0, rows - 1).astype(jnp.int32)
        return params.node_of_cell[row * cols + col]

    def arrival(self, state, step: KinematicStep, params):
        """(hit, tick of the step at which the drive enters the goal region with the heading
        within tolerance) — `NavigationTask.ticks_to_goal`."""
        two_pi = 2 * jnp.pi
        err = jnp.mod(step.heading - state.goal_heading + jnp.pi, two_pi) - jnp.pi
        within = jnp.abs(err) <= params.heading_tolerance
        seg = step.end - step.start
        length = jnp.hypot(seg[0], seg[1])
        rel = step.start - state.goal_position
        rr = rel[0] * rel[0] + rel[1] * rel[1]
        radius = params.goal_radius + GOAL_SLACK  # the closed disk, as the env's test
        r2 = radius * radius
        at_start = rr <= r2
        d = seg / jnp.where(length == 0, 1.0, length)
        b = rel[0] * d[0] + rel[1] * d[1]
        disc = b * b - (rr - r2)
        s = -b - jnp.sqrt(jnp.maximum(disc, 0.0))
        enters = (length != 0) & (disc >= 0) & (s >= 0) & (s <= length)
        s = jnp.where(at_start, 0.0, s)
        drive = jnp.ceil(s / params.tick_length - 1e-9).astype(jnp.int32)
        return within & (at_start | enters), 1 + drive  # one bump, then the drive

    def step(self, state, step, params):
        w1, w2, bonus, tick_cost, gamma = params.reward
        hit, arrive = self.arrival(state, step, params)
        dtype = params.reward.dtype
        ticks = jnp.where(hit, jnp.minimum(step.ticks, arrive), step.ticks).astype(dtype)
        changed = step.changed.astype(dtype)
        if self.kind == "plan_cost":
            reward = -w1 * ticks - (w2 - w1) * changed
        else:
            reward = -tick_cost * ticks
        reward = reward + bonus * hit.astype(dtype)
        potential = state.potential
        if self.kind == "progress":
            after = params.potential[state.goal_node, self._node(step.end, params)]
            reward = reward + (gamma * jnp.where(hit, 0.0, after) - state.potential)
            potential = jnp.where(hit, 0.0, after)
        state = state._replace(reached=state.reached | hit, potential=potential,
                               plan_cost=state.plan_cost + (w1 * ticks + (w2 - w1) * changed))
        gap = step.end - state.goal_position
        info = {"is_success": state.reached, "plan_cost": state.plan_cost,
                "distance_to_goal": jnp.hypot(gap[0], gap[1]), "angle_changed": step.changed,
                "ticks_to_goal": jnp.where(hit, step.episode_ticks - step.ticks + arrive, -1)}
        return state, reward, state.reached, info

    def features(self, state, params):
        if not self.observe_task:
            return None

        def pose(position, heading):
            xy = (position - params.low) / params.span * 2 - 1
            return jnp.concatenate([xy, jnp.stack([jnp.cos(heading), jnp.sin(heading)])])

        return jnp.concatenate([pose(state.start_position, state.start_heading),
                                pose(state.goal_position, state.goal_heading)])
