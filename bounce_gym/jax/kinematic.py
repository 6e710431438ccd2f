"""`KinematicEnv`: a lone bouncing robot on the exact kinematic backend as a pure JAX function.

The NumPy `BounceEnv` with ``backend="kinematic"``, one robot, ``step_mode="bounce"`` and no
noise, step for step. A lone robot in bounce mode is in contact at the start of every step, so a
step is the bump tick — the bounce rule turns the heading (`turn`) — then the swept-disk ray cast
from the contact (`bounce_gym.jax.raycast`): facing the wall still, the robot stays (the step is
the bump alone); else it drives the cast's distance in ceil(distance / step_length − time_tol)
ticks and stops against what it hit, whose normal the next bump reads
(`bounce_gym.dynamics.simulator.BounceDynamics.bounce`, `KinematicBackend._drive_one`). A reset
places the robot and drives it to its first contact as the NumPy reset does.

**Precision.** The env computes in the float type JAX is configured for, which its ``params``
carry (`default_params` builds them in it). Positions match the NumPy env's to 1e-9 only in
float64: ``jax.config.update("jax_enable_x64", True)`` before `bounce_gym.jax.make` (or
``with jax.enable_x64(True):`` around making and running the env); the library never turns x64
on itself. In float32 a position differs from NumPy's by float32 rounding of the world's
coordinates per bounce, and the difference compounds: measured over 40 episodes of 256 random
actions, the median gap over the first 10 steps is 1e-6 (lab_navigation, two_rooms) to 5e-5 (a
generated star map of size ~500), and half the episodes part by more than 1e-3 after 87 steps
(lab_navigation) or 28 (the star); contact tolerances are widened accordingly
(`bounce_gym.jax.raycast`). In float64 the positions agree to ~1e-12, but XLA fuses
multiply-adds where NumPy rounds twice, so the last bits differ: a robot resting on a wall along
a line of the ``progress`` reward's grid may be read in the neighbouring cell, which changes
that step's and the next step's shaping (about 2 % of the steps on lab_navigation); under the
boundary-relative rules ``fixed`` and ``monotonic`` the motion is chaotic, and any
rounding difference grows along a trajectory as it does between two NumPy runs whose starts
differ by 1e-11.

**Random starts** are drawn by rejection sampling with a fixed number of candidates
(`bounce_gym.jax.kinematic_world`): the same distribution as the NumPy env's uniform draw, not
the same numbers. To start both envs alike use `KinematicEnv.reset_to`, the twin of the NumPy
``reset(options={"start": {...}, "goal": {...}})``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.jax.environment import Environment
from bounce_gym.jax.kinematic_tasks import KinematicFreeTask, KinematicNavigationTask, KinematicStep
from bounce_gym.jax.kinematic_world import FreeSpace, free_space, sample_free_point
from bounce_gym.jax.raycast import Walls, cast, walls

#: the bounce rules the kinematic JAX env runs
RULES = ("relative", "fixed", "specular", "monotonic")
#: its tasks, by the NumPy task's name
TASKS = ("free", "navigation")
TWO_PI = 2 * np.pi


class KinematicParams(NamedTuple):
    walls: Walls
    free: FreeSpace
    angles: jax.Array  # (n,) the bounce angles Φ (radians)
    turn_value: jax.Array  # (n,) float32: the history's angle entry of each angle
    angle_range: jax.Array  # (2,) radians: continuous actions map [-1, 1] onto it
    clock_value: jax.Array  # float32 clock readings per tick count 0 … max_clock
    step_length: jax.Array
    time_tol: jax.Array  # ticks
    contact_tol: jax.Array  # length
    low: jax.Array  # (2,) the world's lower corner and size (privileged pose)
    span: jax.Array
    obs_low: jax.Array  # float32 observation bounds
    obs_high: jax.Array
    task: object
    max_steps_in_episode: jax.Array


class KinematicState(NamedTuple):
    """The robot (in contact after every reset and step) and its task's state."""

    position: jax.Array  # (2,)
    heading: jax.Array  # radians, [0, 2π)
    normal: jax.Array  # (2,) the contact's normal, pointing at the robot
    edge: jax.Array  # the contact's edge
    clock: jax.Array  # ticks since the last bump
    ticks: jax.Array  # the episode's ticks
    bumps: jax.Array
    steps: jax.Array
    last_angle: jax.Array  # the last bounce angle (NaN: none yet)
    history: jax.Array  # (k, 2) float32: (clock before the bump, angle / 2π), newest first
    task: object


class KinematicEnv(Environment):
    """A lone robot on the kinematic backend with a task (`bounce_gym.jax.kinematic_tasks`),
    built by `bounce_gym.jax.make` from the NumPy env of the same id and options (`kinematic_env`),
    whose spaces it has."""

    def __init__(self, env_id: str, options, task, max_clock: int, obs_low: np.ndarray,
                 obs_high: np.ndarray, max_steps: int, observation_space, action_space) -> None:
        self.env_id = env_id
        self.options = options
        self.task = task
        self.rule = options.bounce_rule
        self.continuous = options.action_type == "continuous"
        self.history = options.history
        self.privileged = options.privileged
        self.max_clock = max_clock
        self.max_steps = max_steps
        self._obs_bounds = (obs_low, obs_high)
        self._observation_space = observation_space
        self._action_space = action_space
        self._candidates = free_space(options.world, options.robot_radius, jnp.float32)[1]

    @property
    def default_params(self) -> KinematicParams:
        """The parameters in the float type JAX is configured for now (module docstring)."""
        dtype = jax.dtypes.canonicalize_dtype(jnp.float64)
        opts = self.options
        world = opts.world
        wall = walls(world, opts.robot_radius, dtype)
        angles = np.asarray(opts.angles[0], dtype=np.float64)
        xmin, ymin, xmax, ymax = world.bounds
        tol = float(wall.ttol)

        def real(values):
            return jnp.asarray(np.asarray(values, dtype=np.float64), dtype)

        clock = np.minimum(np.arange(self.max_clock + 1) / self.max_clock, 1.0)
        return KinematicParams(
            walls=wall, free=free_space(world, opts.robot_radius, dtype)[0], angles=real(angles),
            turn_value=jnp.asarray((np.mod(angles, TWO_PI) / TWO_PI).astype(np.float32)),
            angle_range=real(opts.angle_range[0]),
            clock_value=jnp.asarray(clock.astype(np.float32)),
            step_length=real(opts.step_length), time_tol=real(tol / opts.step_length),
            contact_tol=real(10.0 * tol), low=real([xmin, ymin]),
            span=real([xmax - xmin, ymax - ymin]),
            obs_low=jnp.asarray(self._obs_bounds[0]), obs_high=jnp.asarray(self._obs_bounds[1]),
            task=self.task.params(dtype), max_steps_in_episode=jnp.int32(self.max_steps))

    def action_space(self, params=None):
        return self._action_space

    def observation_space(self, params=None):
        return self._observation_space

    # -- episodes ---------------------------------------------------------------------------
    def reset_env(self, key: jax.Array, params: KinematicParams):
        # every random number of the reset in one draw: per pose 3 × candidates for the
        # position and one for the heading
        uniforms = jax.random.uniform(key, (self.task.poses_drawn, 3 * self._candidates + 1),
                                      params.angles.dtype)

        def sample_pose(i):
            return sample_free_point(uniforms[i, :-1], params.free), uniforms[i, -1] * TWO_PI

        position, heading, drawn = self.task.draw(params.task, sample_pose)
        return self._start(position, heading, drawn, params)

    def reset_to(self, params: KinematicParams | None, position, heading, goal_position=None,
                 goal_heading=None):
        """Start an episode at pose (``position`` (x, y), ``heading`` radians), with the goal
        pose for a task with goals, before the drive to the first contact: the JAX twin of the
        NumPy ``reset(options={"start": {"position": position, "heading": heading},
        "goal": {"position": goal_position, "heading": goal_heading}})``. The start is not
        checked (the NumPy reset raises `ConfigError` outside the free space). ``params``:
        None for `default_params`."""
        params = self.default_params if params is None else params
        dtype = params.angles.dtype
        drawn = self.task.given(goal_position, goal_heading, params.task)
        return self._start(jnp.asarray(position, dtype), jnp.asarray(heading, dtype), drawn,
                           params)

    def _start(self, position, heading, drawn, params: KinematicParams):
        turned = jnp.mod(heading, TWO_PI)
        direction = jnp.stack([jnp.cos(turned), jnp.sin(turned)])
        hit = cast(params.walls, position, direction)
        wall = hit.distance <= params.contact_tol
        distance = jnp.where(wall, 0.0, hit.distance)
        step, tol = params.step_length, params.time_tol
        # the drive to the first contact (`EventDrivenBackend._drive_lone`): its window closes
        # at the end of the tick of the contact
        limit = jnp.maximum(jnp.ceil(distance / step - tol), 0.0) * step
        ticks = jnp.where(wall, 0, jnp.ceil(limit / step - tol)).astype(jnp.int32)
        clock = jnp.minimum(jnp.ceil(distance / step - tol).astype(jnp.int32), ticks)
        moved = jnp.where(wall, position, position + direction * distance)
        state = KinematicState(
            position=moved, heading=turned, normal=hit.normal, edge=hit.edge, clock=clock,
            ticks=ticks, bumps=jnp.int32(0), steps=jnp.int32(0),
            last_angle=jnp.full((), jnp.nan, turned.dtype),
            history=jnp.zeros((self.history, 2), jnp.float32),
            task=self.task.start(drawn, position, heading, moved, ticks, params.task))
        return self._observe(state, params), state

    def step_env(self, key: jax.Array, state: KinematicState, action, params: KinematicParams):
        angle = self._angle(action, params)
        heading = turn(self.rule, state.heading, state.normal, angle)
        direction = jnp.stack([jnp.cos(heading), jnp.sin(heading)])
        hit = cast(params.walls, state.position, direction)
        wall = hit.distance <= params.contact_tol  # still facing the wall: the bump alone
        drive = jnp.where(wall, 0, jnp.ceil(hit.distance / params.step_length - params.time_tol))
        drive = drive.astype(jnp.int32)
        position = jnp.where(wall, state.position, state.position + direction * hit.distance)
        changed = ~jnp.isnan(state.last_angle) & (angle != state.last_angle)
        history = state.history
        if self.history:
            newest = jnp.stack([params.clock_value[jnp.minimum(state.clock, self.max_clock)],
                                self._turn_value(action, angle, params)])
            history = jnp.concatenate([newest[None], history[:-1]])
        ticks = state.ticks + 1 + drive
        step = KinematicStep(start=state.position, end=position, heading=heading,
                             ticks=1 + drive, episode_ticks=ticks, changed=changed)
        task_state, reward, terminated, task_info = self.task.step(state.task, step, params.task)
        moved = KinematicState(
            position=position, heading=heading, normal=hit.normal, edge=hit.edge, clock=drive,
            ticks=ticks, bumps=state.bumps + 1, steps=state.steps + 1, last_angle=angle,
            history=history, task=task_state)
        truncated = moved.steps >= params.max_steps_in_episode
        info = {"ticks": ticks, "clock": drive, "step_ticks": 1 + drive, "position": position,
                "heading": heading, "bumps": moved.bumps, "contact_edge": hit.edge,
                **task_info, "terminated": terminated, "truncated": truncated}
        return self._observe(moved, params), moved, reward, terminated | truncated, info

    def _angle(self, action, params: KinematicParams):
        """The bounce angle of ``action`` (`bounce_gym.envs.actions.to_angle`; a continuous
        action outside [-1, 1] is not refused here: it maps on linearly)."""
        if not self.continuous:
            return params.angles[jnp.asarray(action, jnp.int32)]
        a = jnp.asarray(action).reshape(()).astype(params.angles.dtype)
        lo, hi = params.angle_range
        return lo + (a + 1.0) / 2.0 * (hi - lo)

    def _turn_value(self, action, angle, params: KinematicParams):
        if not self.continuous:  # tabulated in NumPy: the NumPy env's bits
            return params.turn_value[jnp.asarray(action, jnp.int32)]
        return (jnp.mod(angle, TWO_PI) / TWO_PI).astype(jnp.float32)

    # -- sensing ----------------------------------------------------------------------------
    def _observe(self, state: KinematicState, params: KinematicParams):
        parts = [params.clock_value[jnp.minimum(state.clock, self.max_clock)][None]]
        if self.history:
            parts.append(state.history.reshape(-1))
        if self.privileged:
            xy = (state.position - params.low) / params.span
            parts.append(jnp.concatenate([xy, jnp.stack([jnp.cos(state.heading),
                                                         jnp.sin(state.heading)])]
                                         ).astype(jnp.float32))
        features = self.task.features(state.task, params.task)
        if features is not None:
            parts.append(features.astype(jnp.float32))
        obs = jnp.concatenate(parts)
        if self.privileged or features is not None:
            obs = jnp.clip(obs, params.obs_low, params.obs_high)
        return obs


def turn(rule: str, heading, normal, angle):
    """The heading after a bump by bounce ``rule`` with parameter ``angle`` at a contact of
    inward ``normal`` (`bounce_gym.dynamics.rules`)."""
    if rule == "relative":
        return _wrap(heading + angle)
    tangent = jnp.arctan2(-normal[0], normal[1])
    alpha = _wrap(heading + jnp.pi - tangent)
    if rule == "fixed":
        u = angle
    elif rule == "specular":
        u = jnp.pi - alpha
    else:  # monotonic
        cos_a = jnp.cos(alpha)
        keep = jnp.sign(jnp.cos(angle)) == -jnp.sign(cos_a)
        u = jnp.where((jnp.abs(cos_a) < 1e-12) | keep, angle, jnp.pi - angle)
    return _wrap(tangent + u)


def _wrap(angle):
    out = jnp.mod(angle, TWO_PI)
    return jnp.where(out >= TWO_PI, 0.0, out)


def kinematic_env(env_id: str, numpy_env, max_steps: int, observation_space,
                  action_space) -> KinematicEnv:
    """The `KinematicEnv` of the (unwrapped) NumPy `BounceEnv` ``numpy_env``, whose options
    `unsupported` accepts."""
    opts = numpy_env.options
    core = numpy_env.core
    name = core.task.name
    task = KinematicNavigationTask(core.task, opts) if name == "navigation" else KinematicFreeTask()
    return KinematicEnv(env_id, opts, task, opts.max_clock, core.obs_low, core.obs_high,
                        max_steps, observation_space, action_space)


def unsupported(opts, task: str) -> str | None:
    """Why the options of a kinematic-backend env have no `KinematicEnv`, or None."""
    if task not in TASKS:
        return f"task {task!r} (the kinematic env has {list(TASKS)})"
    if opts.bounce_rule not in RULES:
        return f"bounce_rule {opts.bounce_rule!r} (the kinematic env has {list(RULES)})"
    return None
