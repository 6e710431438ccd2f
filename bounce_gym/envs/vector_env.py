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

from bounce_gym.cells.geodesic import GridGeodesic
from bounce_gym.dynamics import BounceDynamics, RobotState
from bounce_gym.dynamics.backends.kinematic import KinematicBackend
from bounce_gym.dynamics.noise import Exact
from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.reset_options import checked_reset_options
from bounce_gym.envs.tasks import CoverageTask, NavigationTask
from bounce_gym.envs.tasks.base import StepEvents, path_samples, tick_length
from bounce_gym.envs.tasks.coverage import CoverageHistograms
from bounce_gym.envs.vector_cells import CellRobots
from bounce_gym.errors import ActionError, ConfigError
from bounce_gym.validate import integer

#: the single-robot tasks this env batches
VECTOR_TASKS = ("free", "navigation", "coverage")
#: the fields of a `RobotState` row that a reset writes
#: every env's rows of an array
_EVERY = slice(None)
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
        self.task = _BATCHED[task.name](task, n, model,
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

    def _positions(self) -> np.ndarray | None:
        """(N,) each robot's position index on the cell backend; None on the kinematic one."""
        return self.cell_robots.p if self.cell_robots else None

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
        self.task.start(rows, self.state, self._ticks, self._positions())
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
        bumping = state.blocked.copy()
        every = bumping.all()  # always on the cell backend: each step and reset ends in contact
        if opts.history:
            rows = _EVERY if every else np.flatnonzero(bumping)
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
            for j in range(opts.history - 1, 0, -1):  # one pair at a time: no overlapping copy
                history[rows, j] = history[rows, j - 1]
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
                                                        self._positions())
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
        values["cell"] = self._info_cells(values["position"], _EVERY if rows is None else rows)
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
        read-only all-True array as its mask.
        """
        infos = {}
        for key, value in self._robot_values().items():
            infos[key] = value
            infos[f"_{key}"] = self._all_true
        reset = self.task.info(self.state, resetting) if len(resetting) else {}
        stepped = None
        if len(resetting):
            stepped = np.ones(self.num_envs, dtype=bool)
            stepped[resetting] = False
        for key, value in values.items():
            present = self._all_true
            if isinstance(value, tuple):  # (values, mask): a key only some envs report
                value, present = value
                if stepped is not None:
                    present = present & stepped
            elif key not in reset and stepped is not None:
                present = stepped.copy()
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

    def _info_cells(self, position: np.ndarray, rows: np.ndarray | slice = _EVERY) -> np.ndarray:
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


# -- batched tasks ----------------------------------------------------------------------------

class _FreeBatch:
    """No reward, never terminates.

    ``model``: the `CellModel` of the cell backend, else None. ``bounds``: (low, high), the
    observation bounds of the task's features, which the batch clips them to when drawn (as
    the single env clips its observation). ``positions`` (`start`, `step`): each robot's
    position index in that model, else None.
    """

    #: whether `draw_cells` draws the episodes (without reset options)
    draws_cells = False

    def __init__(self, task, n: int, model=None, bounds=None) -> None:
        self.n = n

    def draw_cells(self, rngs: list, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The start cells (position indices, bins) of envs ``rows``, each drawn from its
        generator in ``rngs`` with what else the task draws, as the single-robot task draws
        them (where `draws_cells`)."""
        raise NotImplementedError

    def drawn(self, i: int, task) -> None:
        """Take what the single-robot ``task`` drew for env ``i``'s new episode (its goal)."""


    def start(self, rows: np.ndarray, state, ticks: np.ndarray,
              positions: np.ndarray | None = None) -> None:
        """Start the episodes of envs ``rows``, whose robots (``state``) were placed and drove
        ``ticks`` to their first contact, as the single-robot task's reset starts one."""

    def info(self, state, rows: np.ndarray | slice = _EVERY) -> dict:
        """Task info of envs ``rows`` (default: every env), for the robots' ``state``."""
        return {}

    def observation(self) -> np.ndarray | None:
        return None

    def step(self, state, events: StepEvents, ticks: np.ndarray,
             positions: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
        return np.zeros(self.n), np.zeros(self.n, dtype=bool), {}


class _NavigationBatch(_FreeBatch):
    """`NavigationTask` for N robots: goals, arrival, the rewards (`NavigationTask.step_rewards`,
    every ``reward`` option) and the plan cost."""

    def __init__(self, task: NavigationTask, n: int, model=None, bounds=None) -> None:
        super().__init__(task, n)
        self.single = task
        self.model = model
        self.low, self.high = bounds
        self.draws_cells = model is not None and task.random_cells
        if self.draws_cells and task.observe_task:
            # every cell's features as the start's and as the goal's pose, cast and clipped
            p, k = model.decode(np.arange(model.n_cells))
            pose = task.pose_features(model.centres[p], k * model.bin_width).astype(np.float32)
            half = pose.shape[1]
            self.start_features, self.goal_features = (
                self._bounded(pose, self.low[part], self.high[part])
                for part in (slice(None, half), slice(half, None)))
        self.goal_position = np.zeros((n, 2))
        self.goal_heading = np.zeros(n)
        self.goal_wrapped = np.zeros(n)  # the goal headings in [0, 2π)
        self.reached = np.zeros(n, dtype=bool)
        self.plan_cost = np.zeros(n)
        self.features = np.zeros((n, task.observation_size), dtype=np.float32)
        self.rows = np.arange(n)
        if task.geodesic is not None:  # the progress reward: Φ of every grid node, per env
            self.potentials = np.zeros((n, task.geodesic.n_nodes))
            self.potential_now = np.zeros(n)
            self.goal_node = np.zeros(n, dtype=np.int64)  # the grid node of each env's goal
            #: the grid node of each position index of the cell model
            self.node_of_position = (task.geodesic.node_of(model.centres)
                                     if model is not None else None)

    def draw_cells(self, rngs, rows):
        single, model = self.single, self.model
        # per env: the start's position index and bin, then the goal's
        drawn = np.array([single.random_cell(rng) + single.random_cell(rng) for rng in rngs],
                         dtype=np.int64).reshape(-1, 4)
        p, k, goal_p, goal_k = drawn.T
        self.goal_position[rows] = model.centres.take(goal_p, axis=0)
        self.goal_heading[rows] = goal_k * model.bin_width
        if single.geodesic is not None:
            self.goal_node[rows] = self.node_of_position.take(goal_p)
        if single.observe_task:
            self.features[rows] = np.concatenate(
                (self.start_features.take(model.cell_id(p, k), axis=0),
                 self.goal_features.take(model.cell_id(goal_p, goal_k), axis=0)), axis=1)
        return p, k

    def _potentials_at(self, rows: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """Φ of envs ``rows`` at grid nodes ``nodes`` (``self.potentials[rows, nodes]``, gathered
        from the flat array: several times faster than two-axis fancy indexing)."""
        return self.potentials.reshape(-1).take(rows * self.potentials.shape[1] + nodes)

    def _nodes(self, geodesic: GridGeodesic, position: np.ndarray,
               positions: np.ndarray | None) -> np.ndarray:
        """The grid nodes of robots at ``position``, or at position indices ``positions``."""
        if positions is None or self.node_of_position is None:
            return geodesic.node_of(position)
        return self.node_of_position.take(positions)

    def drawn(self, i, task):
        goal = task.goal[0][0]
        self.goal_position[i] = goal
        self.goal_heading[i] = task.goal[1][0]
        if task.geodesic is not None:
            self.goal_node[i] = task.geodesic.node_at(*goal.tolist())
        if task.observe_task:
            self.features[i] = self._bounded(task.observation(None)[0], self.low, self.high)

    def start(self, rows, state, ticks, positions=None):
        single = self.single
        self.reached[rows] = False
        self.goal_wrapped[rows] = np.mod(self.goal_heading[rows], 2 * np.pi)
        self.plan_cost[rows] = single.w1 * ticks[rows]  # the drive of a bounce-mode reset
        if single.geodesic is not None:
            self.potentials[rows] = [single.goal_potentials(goal)
                                     for goal in self.goal_node[rows].tolist()]
            self.potential_now[rows] = self._potentials_at(rows, self._nodes(
                single.geodesic, state.position[rows], None if positions is None else positions[rows]))

    def info(self, state, rows=_EVERY):
        goal = self.goal_position[rows]  # a copy where ``rows`` is an array
        gap = state.position[rows] - goal
        return {"goal_position": goal.copy() if rows is _EVERY else goal,
                "goal_heading": self.goal_heading[rows].copy(),
                "distance_to_goal": np.hypot(gap[:, 0], gap[:, 1]),
                "is_success": self.reached[rows].copy(),
                "plan_cost": self.plan_cost[rows].copy()}

    @staticmethod
    def _bounded(features: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        """``features`` clipped to [``low``, ``high``] (np.clip's arithmetic)."""
        return np.minimum(np.maximum(features, low), high)

    def observation(self):
        return self.features if self.single.observe_task else None

    def step(self, state, events, ticks, positions=None):
        single = self.single
        hits, arrivals = [], []  # the envs whose robot reached its goal, and at which tick
        # the exact test of a lone robot, run only where the heading is about within tolerance
        # (headings and wrapped goal headings lie in [0, 2π], so their gap needs no wrapping;
        # the margin lies far above rounding) and the path passes near the goal
        gap = np.abs(events.heading - self.goal_wrapped)
        tolerance = single.heading_tolerance + 1e-9
        aligned = np.flatnonzero((gap <= tolerance) | (gap >= 2 * np.pi - tolerance))
        for i in aligned[self._near_goal(events, aligned)].tolist():
            one = StepEvents(ticks=int(events.ticks[i]), start=events.start[i:i + 1],
                             end=events.end[i:i + 1], heading=events.heading[i:i + 1],
                             bumps=events.bumps[i:i + 1], angles=events.angles[i:i + 1],
                             angle_changed=events.angle_changed[i:i + 1],
                             robot_contact=events.robot_contact[i:i + 1])
            found = single.ticks_to_goal(
                one, (self.goal_position[i:i + 1], self.goal_heading[i:i + 1]))
            if found is not None:
                hits.append(i)
                arrivals.append(found)
        hits, arrivals = np.array(hits, dtype=np.int64), np.array(arrivals)
        hit = np.zeros(self.n, dtype=bool)
        hit[hits] = True
        changed = events.angle_changed
        spent = events.ticks.astype(np.float64)
        hit_ticks = events.ticks[hits]
        spent[hits] = np.minimum(hit_ticks, arrivals)
        before = after = None
        if single.geodesic is not None:
            before = self.potential_now
            after = self._potentials_at(self.rows, self._nodes(single.geodesic, events.end,
                                                                    positions))
            self.potential_now = np.where(hit, 0.0, after)
        reward = single.step_rewards(spent, changed, hit, before, after)
        self.plan_cost = self.plan_cost + single.plan_cost_of(spent, changed)
        self.reached |= hit
        info = self.info(state)
        info["angle_changed"] = changed
        if len(hits):
            to_goal = np.zeros(self.n, dtype=np.int64)
            to_goal[hits] = ticks[hits] - hit_ticks + arrivals
            info["ticks_to_goal"] = (to_goal, hit)
        return reward, self.reached.copy(), info

    def _near_goal(self, events: StepEvents, rows: np.ndarray) -> np.ndarray:
        """(len(rows),) bool: the step's segment of envs ``rows`` comes within the goal radius
        (plus a margin far above rounding) of the goal — a superset of the robots the exact
        disk test can accept."""
        start = events.start.take(rows, axis=0).T
        sx, sy = events.end.take(rows, axis=0).T - start
        rx, ry = self.goal_position.take(rows, axis=0).T - start
        length2 = sx * sx + sy * sy
        along = np.clip((rx * sx + ry * sy) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
        gx, gy = rx - along * sx, ry - along * sy
        return gx * gx + gy * gy <= (self.single.goal_radius + 1e-6) ** 2

class _CoverageBatch(_FreeBatch):
    """`CoverageTask` for N robots: one visit histogram and visited grid per env
    (`CoverageHistograms`)."""

    def __init__(self, task: CoverageTask, n: int, model=None, bounds=None) -> None:
        super().__init__(task, n)
        self.single = task
        self.histograms = CoverageHistograms(task, n)

    def start(self, rows, state, ticks, positions=None):
        h = self.histograms
        h.visits[rows] = 0.0
        h.visited[rows] = False
        row, col = self.single.cells(state.position[rows])
        h.visited[rows, row, col] = True
        h.distance[rows] = self.single.initial_distance

    def info(self, state, rows=_EVERY):
        return self.histograms.info(rows)

    def step(self, state, events, ticks, positions=None):
        task = self.single
        robot, points, spent = path_samples(events, tick_length(task.options, events.heading),
                                            task.cell_size / 4)
        reward, info = self.histograms.visit(robot, points, spent)
        return reward, np.zeros(self.n, dtype=bool), info


_BATCHED = {"free": _FreeBatch, "navigation": _NavigationBatch, "coverage": _CoverageBatch}
