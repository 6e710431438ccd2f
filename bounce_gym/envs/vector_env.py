"""`BounceVectorEnv`: N independent single-robot episodes stepped as one batch.

A Gymnasium 1.x ``VectorEnv`` (registered as the ``vector_entry_point`` of the free, navigation
and coverage ids, so ``gym.make_vec(id, num_envs=N)`` builds it). On the kinematic backend the N
robots live in ONE `BounceDynamics` with ``robot_collisions="ignore"``: a step rotates every robot
and drives each to its own next contact in one vectorised call (`BounceDynamics.bounce_each`). On
the cell backend each robot is kept as its cell (`bounce_gym.envs.vector_cells.CellRobots`) and a
step is a lookup in tables of the `CellModel`; the batch keeps no odometer there (nothing it
reports reads one). Rewards and terminations are the tasks' formulas on arrays.

It reproduces ``gym.make_vec(id, num_envs=N, vectorization_mode="sync")`` step for step:
``reset(seed=s)`` seeds env i with s + i, each env starts where a single env reset with that seed
starts (each env draws its start, and its task's poses, from its own generator as a single env
does; navigation on the cell backend draws its random cells directly), autoreset is
``NEXT_STEP`` and the registered ``max_episode_steps`` truncates each env. Infos are dicts of
arrays with ``_key`` masks, as SyncVectorEnv builds them, except ``cell``, an (N, 2) int array
(row, col) where SyncVectorEnv has an object array of tuples, and the masks of keys every env
reports, which are one shared read-only all-True array.

Not batched (a `ConfigError` says why): ``step_mode="tick"``, the pymunk backend (its exact and
its dynamic physics), actuation noise, rendering and the localization task.
"""

from __future__ import annotations

import math

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from bounce_gym.dynamics import BounceDynamics, RobotState
from bounce_gym.dynamics.backends.kinematic import KinematicBackend
from bounce_gym.dynamics.noise import Exact
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.reset_options import checked_reset_options
from bounce_gym.envs.tasks.base import StepEvents
from bounce_gym.envs.vector_cells import CellRobots
from bounce_gym.envs.vector_tasks import BATCHED, EVERY
from bounce_gym.errors import ActionError, ConfigError
from bounce_gym.validate import integer

#: the single-robot tasks this env batches
VECTOR_TASKS = tuple(BATCHED)
#: the fields of a `RobotState` row that a reset writes
_STATE_FIELDS = ("position", "heading", "blocked", "clock", "bumps", "contact_edge",
                 "contact_robot", "contact_normal", "odometer")


class BounceVectorEnv(VectorEnv):
    """N single-robot `BounceEnv` episodes in numpy arrays, stepped together.

    Args:
        num_envs: N.
        max_episode_steps: per-env truncation (``gym.make_vec`` passes the registered value);
            None: never truncated.
        render_mode: only None.
        **options: the keyword arguments of `BounceEnv` (one set, shared by the N envs).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int, max_episode_steps: int | None = None,
                 render_mode: str | None = None, **options: object) -> None:
        num_envs = integer("num_envs", num_envs, 1)
        if render_mode is not None:
            raise ConfigError("render_mode: the batched env does not render; render one "
                              "gym.make env instead")
        self.single = BounceEnv(None, **options)  # validates the options; resets run its core
        opts = self.options = self.single.options
        task = self.single.core.task
        reason = _unbatchable(opts, task)
        if reason:
            raise ConfigError(f"BounceVectorEnv: {reason}; use "
                              "gym.make_vec(..., vectorization_mode='sync')")
        self.num_envs = n = int(num_envs)
        self.max_episode_steps = max_episode_steps
        self.single_observation_space = self.single.observation_space
        self.single_action_space = self.single.action_space
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self.render_mode = None
        self.dynamics = BounceDynamics(
            opts.world, n, backend=opts.backend, rule=opts.bounce_rule, noise=opts.noise,
            radius=opts.robot_radius, step_length=opts.step_length, robot_collisions="ignore",
            backend_options=opts.backend_options)
        #: the cell backend's robots, kept as cells (None on the kinematic backend)
        self.cell_robots = (CellRobots(self.dynamics, opts.angles[0])
                            if opts.backend == "cell" else None)
        model = self.cell_robots.model if self.cell_robots else None
        core = self.single.core
        first = self._first_feature = len(core.obs_low) - task.observation_size  # they come last
        self.task = BATCHED[task.name](task, n, self.cell_robots,
                                       (core.obs_low[first:], core.obs_high[first:]))
        self._rngs: list[np.random.Generator | None] = [None] * n
        self._ticks = np.zeros(n, dtype=np.int64)
        self._elapsed = np.zeros(n, dtype=np.int64)
        self._autoreset = np.zeros(n, dtype=bool)
        #: the observation's columns kept from step to step (each step copies it and writes the
        #: clock and any privileged pose): the history (`_history`) and the task's features
        self._kept_obs = np.zeros((n, len(self.single.core.obs_low)), dtype=np.float32)
        self._last_angle = np.full(n, math.nan)
        self._origin = np.array(opts.world.bounds[:2], dtype=np.float64)
        self._all_true = _read_only(np.ones(n, dtype=bool))
        self._no_contact = _read_only(np.zeros(n, dtype=bool))
        self._one_bump = _read_only(np.ones(n, dtype=np.int64))
        #: each discrete action's angle as the history records it (a fraction of a turn)
        self._history_turns = np.mod(opts.angles[0], 2 * np.pi) / (2 * np.pi)
        #: ``info["cell"]`` of each position index of the cell model
        self._cell_rc = (np.ascontiguousarray(self._cells(model.centres)) if model is not None
                         else None)

    @property
    def state(self) -> RobotState | None:
        """The robots' state (None before the first reset)."""
        return self.cell_robots.state if self.cell_robots else self.dynamics.state

    # -- episodes ---------------------------------------------------------------------------
    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        """Reset every env; ``seed`` s seeds env i with s + i (a list gives one seed per env).

        ``options["reset_mask"]`` (an (N,) bool array, as SyncVectorEnv takes it) resets only
        those envs; the other options go to every env's reset.
        """
        super().reset(seed=seed if isinstance(seed, int | np.integer) else None)
        n = self.num_envs
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        rows = np.arange(n)
        if mask is not None:
            mask = np.asarray(mask)
            if mask.shape != (n,) or mask.dtype != np.bool_:
                raise ConfigError(f"options['reset_mask']: expected {n} bools, got dtype "
                                  f"{mask.dtype}, shape {mask.shape}")
            if self.state is None and not mask.all():
                raise ConfigError("options['reset_mask']: the first reset resets every env")
            rows = np.flatnonzero(mask)
        seeds: list[int | None]
        if seed is None:
            seeds = [None] * n
        elif isinstance(seed, int | np.integer):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise ConfigError(f"seed: expected {n} seeds, got {len(seeds)}")
        for i in rows:
            if seeds[i] is not None or self._rngs[i] is None:
                self._rngs[i] = seeding.np_random(seeds[i])[0]
        self._reset_envs(rows, options)
        self._autoreset[rows] = False
        return self._observation(), self._reset_infos(rows)

    def _reset_envs(self, rows: np.ndarray, options: dict | None = None) -> None:
        """Start new episodes in ``rows``: each draws its start (and task) poses from its own
        generator with ``options`` (an autoreset passes none) as a single env's reset draws them;
        then the rows are placed, driven to their first contact and handed to the task at once."""
        core = self.single.core
        checked = checked_reset_options(options, core.option_keys)
        robots = self.cell_robots
        if robots is not None and not checked and self.task.draws_cells:
            cells = self.task.draw_cells([self._rngs[i] for i in rows.tolist()], rows)
            self._ticks[rows] = robots.place(rows, *cells)
        else:
            m = len(rows)
            position, heading = np.empty((m, 2)), np.empty(m)
            for j, i in enumerate(rows.tolist()):
                position[j], heading[j] = (x[0] for x in core.draw_start(self._rngs[i], checked))
                self.task.drawn(i, core.task)
            if robots is not None:
                self._ticks[rows] = robots.place(rows, *robots.cells_of(position, heading))
            else:
                self._ticks[rows] = self._place_kinematic(rows, position, heading)
        self.task.start(rows, self.state, self._ticks, self.cell_robots)
        self._elapsed[rows] = 0
        self._history()[rows] = 0.0
        features = self.task.observation()
        if features is not None:
            self._kept_obs[rows, self._first_feature:] = features[rows]
        self._last_angle[rows] = math.nan

    def _place_kinematic(self, rows: np.ndarray, position: np.ndarray,
                         heading: np.ndarray) -> np.ndarray:
        """Kinematic backend: start robots ``rows`` at the poses and drive each to its first
        contact. Returns the ticks each drove."""
        state = self.dynamics.state
        if state is None:  # the first reset: every row
            state = self.dynamics.reset(np.random.default_rng(0), position, heading)
        else:
            fresh = RobotState.at(position, heading)
            for name in _STATE_FIELDS:
                getattr(state, name)[rows] = getattr(fresh, name)
            backend = self.dynamics.backend
            assert isinstance(backend, KinematicBackend)  # `_unbatchable`: no pymunk backend
            backend.place(state, rows)
        # every robot not reset ended its last step in contact: only the rows drive
        return self.dynamics.backend.drive_each(state)[rows]

    def _started(self) -> RobotState:
        """The robots' state, once a reset has placed them."""
        state = self.state
        if state is None:
            raise ConfigError("call reset() before step()")
        return state

    def step(self, actions):
        state = self._started()
        angles, choices = self._angles(actions)
        opts = self.options
        start = state.position.copy()
        if self.cell_robots is not None:  # each step and each reset ends in contact
            bumping, every = self._all_true, True
        else:
            bumping = state.blocked.copy()
            every = bool(bumping.all())
        if opts.history:
            rows = EVERY if every else np.flatnonzero(bumping)
            clock_before = state.clock.copy() if every else state.clock[rows]
        if self.cell_robots is not None:
            # every robot is blocked (each step and each reset ends in contact): the bump tick
            # is the rotation, then each robot drives on by itself
            driven = self.cell_robots.bounce(choices)  # discrete actions only (options)
        else:
            driven = self.dynamics.bounce_each(angles)
        ticks = bumping + driven
        self._ticks += ticks
        last = self._last_angle
        changed = (angles != last) & (last == last)  # last == last: not NaN
        if every:
            self._last_angle = angles
        else:
            changed &= bumping
            last[bumping] = angles[bumping]
        if opts.history:
            history = self._history()
            history[rows, 1:] = history[rows, :-1]  # numpy buffers the overlapping copy
            history[rows, 0, 0] = clock_before / opts.max_clock
            turns = (self._history_turns.take(choices) if choices is not None
                     else np.mod(angles, 2 * np.pi) / (2 * np.pi))
            history[rows, 0, 1] = turns[rows]
        # a bump is the one rotation tick of a blocked robot, so bumps grew by ``bumping``
        events = StepEvents(
            ticks=ticks, start=start, end=state.position.copy(), heading=state.heading.copy(),
            bumps=self._one_bump if every else bumping.astype(np.int64),
            angles=angles if every else np.where(bumping, angles, math.nan),
            angle_changed=changed, robot_contact=self._no_contact)
        rewards, terminated, task_info = self.task.step(state, events, self._ticks,
                                                        self.cell_robots)
        self._elapsed += 1
        truncated = (np.zeros(self.num_envs, dtype=bool) if self.max_episode_steps is None
                     else self._elapsed >= self.max_episode_steps)
        resetting = np.flatnonzero(self._autoreset)
        if len(resetting):
            self._reset_envs(resetting)
        infos = self._step_infos({**task_info, "step_ticks": ticks}, resetting)
        if len(resetting):
            rewards[resetting] = 0.0
            terminated[resetting] = False
            truncated[resetting] = False
        self._autoreset = terminated | truncated
        return self._observation(), rewards, terminated, truncated, infos

    def _angles(self, actions) -> tuple[np.ndarray, np.ndarray | None]:
        """(N,) bounce angles in radians, and the (N,) discrete actions (None for continuous
        ones); malformed actions raise `ActionError`."""
        opts = self.options
        n = self.num_envs
        raw = np.asarray(actions)
        if opts.action_type == "discrete":
            if raw.shape != (n,) or raw.dtype.kind not in "iu":
                raise ActionError(f"actions: expected {n} integer indices, got dtype "
                                  f"{raw.dtype}, shape {raw.shape}")
            phi = opts.angles[0]
            if raw.min() < 0 or raw.max() >= len(phi):
                bad = (raw < 0) | (raw >= len(phi))
                i = int(np.flatnonzero(bad)[0])
                raise ActionError(f"actions[{i}]: index {int(raw[i])} is out of range "
                                  f"[0, {len(phi)})")
            return phi.take(raw), raw
        if raw.dtype.kind not in "iuf":
            raise ActionError(f"actions: expected real numbers in [-1, 1], got dtype {raw.dtype}")
        if raw.shape not in ((n, 1), (n,)):
            raise ActionError(f"actions: expected shape ({n}, 1), got shape {raw.shape}")
        a = raw.astype(np.float64).reshape(n)
        bad = ~((a >= -1.0) & (a <= 1.0))  # NaN too
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ActionError(f"actions[{i}]: {a[i]} is outside [-1, 1] (actions are not "
                              "clipped)")
        lo, hi = opts.angle_range[0]
        return lo + (a + 1.0) / 2.0 * (hi - lo), None

    # -- sensing ----------------------------------------------------------------------------
    def _history(self) -> np.ndarray:
        """(N, history, 2) the history columns of `_kept_obs`, a view."""
        return self._kept_obs[:, 1:1 + 2 * self.options.history].reshape(self.num_envs, -1, 2)

    def _observation(self) -> np.ndarray:
        """(N, d) float32 observations in one fresh array, the values `BounceCore.observation`
        concatenates, cast the same way: `_kept_obs` with the clock and any privileged pose
        written in."""
        state = self._started()
        opts = self.options
        core = self.single.core
        obs = self._kept_obs.copy()
        # bounce mode, one robot per env: every step ends in contact, so no contact column
        obs[:, 0] = state.clock / opts.max_clock
        col = 1 + 2 * opts.history
        if opts.privileged:
            xmin, ymin, xmax, ymax = opts.world.bounds
            pose = obs[:, col:col + 4]
            pose[:, :2] = (state.position - (xmin, ymin)) / (xmax - xmin, ymax - ymin)
            pose[:, 2:] = state.direction
            # np.clip's arithmetic, without its wrapper; the clock and the history are in range
            # by construction, and the task's features were bounded when drawn
            np.minimum(np.maximum(pose, core.obs_low[col:col + 4], out=pose),
                       core.obs_high[col:col + 4], out=pose)
        return obs

    def _robot_values(self, rows: np.ndarray | None = None) -> dict:
        """The info values of the robots themselves (fresh arrays) for envs ``rows`` (None:
        every env)."""
        state = self._started()
        arrays = {"ticks": self._ticks, "position": state.position, "heading": state.heading,
                  "clock": state.clock, "bumps": state.bumps, "contact_edge": state.contact_edge}
        if rows is None:
            values = {key: array.copy() for key, array in arrays.items()}
        else:  # ``take``: fancy indexing's values, faster
            values = {key: array.take(rows, axis=0) for key, array in arrays.items()}
        values["cell"] = self._info_cells(values["position"], EVERY if rows is None else rows)
        return values

    def _reset_values(self, rows: np.ndarray) -> dict:
        """The info values of envs ``rows`` just reset, one row each."""
        return {**self._robot_values(rows), **self.task.info(self.state, rows)}

    def _step_infos(self, values: dict, resetting: np.ndarray) -> dict:
        """The infos of a step (arrays with ``_key`` masks, as SyncVectorEnv builds them), taken
        after envs ``resetting`` were reset: the robots' values (`_robot_values`, so the reset
        envs' already), then the step's own ``values`` (the task's info and ``step_ticks``,
        fresh arrays; ``(values, mask)`` for a key only some envs report), where the reset envs
        report the task's reset info instead, or nothing (0, mask False) for a key it lacks.

        The value arrays are handed out as they are; a key every env reports has the shared
        read-only all-True array as its mask, and the keys only the stepped envs report share
        one read-only mask.
        """
        infos = {}
        for key, value in self._robot_values().items():
            infos[key] = value
            infos[f"_{key}"] = self._all_true
        reset = self.task.info(self.state, resetting) if len(resetting) else {}
        stepped = None
        if len(resetting):  # one read-only mask, shared by the keys the reset envs lack
            stepped = np.ones(self.num_envs, dtype=bool)
            stepped[resetting] = False
            stepped.flags.writeable = False
        for key, value in values.items():
            present = self._all_true
            if isinstance(value, tuple):  # (values, mask): a key only some envs report
                value, present = value
                if stepped is not None:
                    present = present & stepped
            elif key not in reset and stepped is not None:
                present = stepped
            if key in reset:
                value[resetting] = reset[key]
            elif stepped is not None:
                value[resetting] = 0
            if present is self._all_true or present.any():
                infos[key] = value
                infos[f"_{key}"] = present
        return infos

    def _reset_infos(self, rows: np.ndarray) -> dict:
        """The infos of `reset` for envs ``rows`` (arrays with ``_key`` masks)."""
        n = self.num_envs
        infos = {}
        for key, value in self._reset_values(rows).items():
            if len(rows) == n:
                infos[key] = value  # fresh arrays, in env order
                infos[f"_{key}"] = self._all_true
                continue
            infos[key] = np.zeros((n, *value.shape[1:]), dtype=value.dtype)
            infos[key][rows] = value
            infos[f"_{key}"] = np.zeros(n, dtype=bool)
            infos[f"_{key}"][rows] = True
        return infos

    def _info_cells(self, position: np.ndarray, rows: np.ndarray | slice = EVERY) -> np.ndarray:
        """``info["cell"]`` of robots ``rows`` at positions ``position`` (their rows of the
        state): on the cell backend looked up by position index."""
        robots = self.cell_robots
        if self._cell_rc is not None and robots is not None:
            return self._cell_rc.take(robots.p[rows], axis=0)
        return self._cells(position)

    def _cells(self, position: np.ndarray) -> np.ndarray:
        """(n, 2) int (row, col) of ``info["cell"]`` at positions ``position`` (n, 2)."""
        cells = (position - self._origin) / self.options.step_length
        cells = np.floor(cells, out=cells).astype(np.int64)
        np.minimum(np.maximum(cells, 0, out=cells), self.single.core.cell_max, out=cells)
        return cells[:, ::-1]

    def close_extras(self, **kwargs) -> None:
        self.single.close()


def _read_only(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


def batch_refusal(**options: object) -> str | None:
    """Why `BounceVectorEnv` would refuse the `BounceEnv` keyword arguments ``options`` (the
    pymunk backend, actuation noise, tick steps, an unbatched task), or None when it takes
    them: what a caller that may fall back to separate copies asks first."""
    single = BounceEnv(None, **options)
    return _unbatchable(single.options, single.core.task)


def _unbatchable(opts, task) -> str | None:
    """Why these options cannot be batched, or None."""
    if task.name not in VECTOR_TASKS:
        return (f"task {task.name!r} is not batched (its filter keeps a set of candidate "
                "configurations per robot, updated by set operations one robot at a time)"
                if task.name == "localization" else f"task {task.name!r} is not batched")
    if opts.step_mode != "bounce":
        return ("step_mode 'tick' is not batched (a step is one tick of every robot: use "
                "step_mode='bounce')")
    if opts.backend == "pymunk" and opts.physics == "dynamic":
        return ("physics 'dynamic' steps rigid bodies through turns and drives on one shared "
                "clock, so its robots cannot each drive to their own contact (use "
                "physics='ideal' on backend 'kinematic')")
    if opts.backend == "pymunk":
        return ("the pymunk backend steps all bodies in one physics space on a shared clock, "
                "so its robots cannot each drive to their own contact")
    if not isinstance(opts.noise, Exact):
        return ("actuation noise is not batched (each env draws its noise from its own "
                "generator, one robot at a time)")
    return None
