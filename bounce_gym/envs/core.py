"""The simulation core shared by `BounceEnv` and `MultiBounceEnv`: m robots, a task, sensing.

Per robot the observation is what the robot senses (all values in [0, 1] unless noted):

* ``contact`` — 1 if the bump sensor is pressed now (the robot touches what it faces, so its next
  tick is a bump and the angle it is given will be used), else 0. Offered only where it can be
  0 at the start of a step: in tick mode, with several robots (a bounce-mode step ends when one
  of them needs an angle; the others may be driving) and with turn commands. A lone robot in
  bounce mode ends every step against a wall, so there the observation starts with ``clock``
  (`BounceCore.observes_contact`);
* ``clock`` — ticks since its last bump, divided by `EnvOptions.max_clock` (at most 1: a bound
  on the ticks between bumps; under ``physics="dynamic"`` a robot pushed or sliding for longer
  reads 1);
* with ``history = k``: the k most recent (segment ticks / max_clock, angle / 360°) pairs, newest
  first, zero-padded — one pair per bump: the clock reading just before it and the angle used;
* with ``privileged=True``: the true pose (x, y scaled to [0, 1], cos θ, sin θ in [-1, 1]);
* with ``agent_id=True`` (several robots): the robot's index, one-hot (``n_robots`` values);
* the task's features, in [-1, 1] (e.g. navigation's start and goal poses).

The true state goes to ``info`` only.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping

import numpy as np

from bounce_gym.cells import CellModel
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.sampled_model import DEFAULT_SAMPLES, SampledModel, sampled_model
from bounce_gym.envs.options import EnvOptions
from bounce_gym.envs.reset_options import checked_reset_options
from bounce_gym.envs.tasks.base import StepEvents, Task, pose_option

TRAIL_LENGTH = 64


class BounceCore:
    """Robots, their sensing history and the task, stepped in bounce or tick mode."""

    def __init__(self, options: EnvOptions, task: Task) -> None:
        self.options = options
        self.task = task
        self.dynamics = BounceDynamics(
            options.world, options.n_robots, backend=options.backend, rule=options.bounce_rule,
            noise=options.noise, radius=options.robot_radius, step_length=options.step_length,
            robot_collisions=options.robot_collisions, backend_options=options.backend_options,
        )
        self._cell_models: dict[tuple[int, str], CellModel] = {}
        task.configure(self)
        #: whether the observation starts with ``contact``: not for a lone robot in bounce mode
        #: without turn commands, whose every step ends in contact (it would always read 1)
        self.observes_contact = (options.step_mode == "tick" or options.n_robots > 1
                                 or len(options.turn_angles) > 0)
        layout = _observation_layout(options, task, self.observes_contact)
        #: what each index of a robot's observation is (the module docstring), its bounds
        self.obs_labels = tuple(label for label, _, _ in layout)
        self.obs_low = np.array([low for _, low, _ in layout], dtype=np.float32)
        self.obs_high = np.array([high for _, _, high in layout], dtype=np.float32)
        self.option_keys = frozenset({"start"}) | task.option_keys
        #: whether the task's step does anything (the free task's does not: reward 0, no end,
        #: no info), so whether a step needs `StepEvents`
        self._task_steps = type(task).step is not Task.step
        #: whether steps extend the trails (set by an env that renders; only drawings read them)
        self.keep_trails = True
        xmin, ymin, xmax, ymax = options.world.bounds
        #: largest (col, row) of the step-length grid of `World.occupancy` that ``info["cell"]``
        #: reports: a robot touching the right or top wall (or a hair outside by rounding) still
        #: reports a cell of the grid
        self.cell_max = np.array([
            max(int(np.ceil((xmax - xmin) / options.step_length - 1e-9)) - 1, 0),
            max(int(np.ceil((ymax - ymin) / options.step_length - 1e-9)) - 1, 0),
        ])

    @property
    def state(self):
        return self.dynamics.state

    def cell_model(self, n_bins: int | None = None, corner_rule: str | None = None) -> CellModel:
        """The discrete model of the robot's motion that planners and tasks work on.

        On the ``cell`` backend it is the backend's own `CellModel` — the model the robot steps,
        so it is returned whatever the arguments say. On the continuous backends it is a model
        at cell size = ``step_length`` for the robot radius with ``n_bins`` orientation bins and
        ``corner_rule`` (None: the env's ``cell_bins`` and ``corner_rule``), built on the first
        call and cached; planners that discretise more finely than the env pass their own bins.
        """
        if self.options.backend == "cell":
            return self.dynamics.backend.model
        key = (self.options.cell_bins if n_bins is None else n_bins,
               self.options.corner_rule if corner_rule is None else corner_rule)
        if key not in self._cell_models:
            self._cell_models[key] = CellModel(self.options.world, self.options.step_length,
                                               key[0], self.options.robot_radius, key[1])
        return self._cell_models[key]

    def sampled_model(self, samples: int = DEFAULT_SAMPLES, seed: int = 0,
                      heading_offset: float | None = None, n_bins: int | None = None,
                      corner_rule: str | None = None, cell_size: float | None = None,
                      cache=None) -> SampledModel:
        """The generalized cell mapping of this env estimated from its own dynamics
        (`bounce_gym.dynamics.sampled_model`): over the decision states of `cell_model`
        (``n_bins``, ``corner_rule``) at bumps and robot 0's angles Φ, ``samples`` sample points
        per state and angle from generator ``seed``; ``heading_offset`` (radians) fixes every
        sampled heading at a bin's centre plus it; ``cell_size`` (default ``step_length``) the
        side of the decision states' cells, finer than the robot's step to tell apart where on a
        wall it bumped; ``cache``: a folder, None (the default folder) or False. Built once per
        argument set and kept."""
        key = ("sampled", samples, seed, heading_offset, n_bins, corner_rule, cell_size, cache)
        if key not in self._cell_models:
            options = self.options
            model = self.cell_model(n_bins, corner_rule)
            if cell_size is not None and options.backend != "cell":
                model = CellModel(options.world, cell_size, model.n_bins, options.robot_radius,
                                  model.corner_rule)
            self._cell_models[key] = sampled_model(model, options.robot_dynamics,
                                                   options.angles[0], samples,
                                                   seed, heading_offset, cache=cache)
        return self._cell_models[key]

    # -- episode ----------------------------------------------------------------------------
    def reset(self, rng: np.random.Generator, options: Mapping | None,
              strict: bool = True) -> tuple[np.ndarray, dict]:
        """Place the robots and start an episode.

        Unknown option keys raise `ConfigError`; with ``strict=False`` (PettingZoo, whose API
        test passes arbitrary options) they only warn.
        """
        options = checked_reset_options(options, self.option_keys, strict)
        m = self.options.n_robots
        state = self.dynamics.reset(rng, *self.draw_start(rng, options))
        if self.options.step_mode == "bounce":
            self.dynamics.drive_to_contact()
        self.history = np.zeros((m, self.options.history, 2), dtype=np.float32)
        self.last_angle = np.full(m, math.nan)
        self.trails = [deque([p.copy()], maxlen=TRAIL_LENGTH) for p in state.position]
        info = self.task.reset(state, rng, options)
        return self.observation(), self._info(info)

    def draw_start(self, rng: np.random.Generator, options: Mapping
                   ) -> tuple[np.ndarray, np.ndarray]:
        """The start positions (m, 2) and headings (m,) of an episode with the (checked) reset
        ``options``, drawn from ``rng`` exactly as `reset` draws them: the task's poses (the
        task keeps what else it drew, e.g. a goal), else the ``start`` option, else random."""
        poses = (self.task.start_poses(rng, options)
                 or pose_option(options, "start", self.options.n_robots))
        return self.dynamics.draw_poses(rng, *(poses if poses is not None else (None, None)))

    def step(self, angles: np.ndarray, turns: np.ndarray | None = None
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
        """Advance one env step with bounce angles (m,) in radians.

        With ``turns`` (m,) radians, NaN = none, and some robot commanded: the step is one
        command tick instead (`BounceDynamics.turn`: those robots turn in place, the others
        wait; no bumps, so ``angles`` are unused), in either step mode.
        """
        state = self.dynamics.state
        start = state.position.copy()
        bumping = state.blocked.copy()
        clock_before = state.clock.copy()
        bumps_before = state.bumps.copy()
        if turns is not None and not np.all(np.isnan(turns)):
            ticks_before = state.ticks
            self.dynamics.turn(turns)  # one tick, or as many as the turns take (dynamic)
            bumping[:] = False
            ticks = state.ticks - ticks_before
        elif self.options.step_mode == "bounce":
            ticks = self.dynamics.bounce(angles)
        else:
            self.dynamics.tick(angles)
            ticks = 1
        changed = bumping & ~np.isnan(self.last_angle) & (angles != self.last_angle)
        self.last_angle[bumping] = angles[bumping]
        if self.options.history and bumping.any():
            self._remember(np.flatnonzero(bumping), clock_before, angles)
        self._extend_trails()
        rewards, terminated, info = self.task.step(
            state, self._events(ticks, start, bumps_before, bumping, angles, changed))
        info = self._info(info)
        info["step_ticks"] = int(ticks)
        return self.observation(), rewards.astype(np.float64), terminated, info

    def step_one(self, angle: float) -> tuple[np.ndarray, float, bool, dict]:
        """`step` of a lone robot with bounce angle ``angle`` (radians) and no turn, unpacked
        as `BounceEnv` returns it: observation (d,), reward, terminated and the robot's info.

        The single-robot hot path: the same numbers as `step`, in plain Python scalars, with
        `StepEvents` built only for a task that reads them.
        """
        state = self.dynamics.state
        bumping = bool(state.blocked[0])
        clock_before = int(state.clock[0])
        if self._task_steps:
            start, bumps_before = state.position.copy(), state.bumps.copy()
        if self.options.step_mode == "bounce":
            ticks = self.dynamics.bounce(angle)
        else:
            self.dynamics.tick(angle)
            ticks = 1
        last = float(self.last_angle[0])
        changed = bumping and last == last and angle != last  # last == last: not NaN
        if bumping:
            self.last_angle[0] = angle
            if self.options.history:
                self._remember(np.zeros(1, dtype=np.int64), np.array([clock_before]),
                               np.array([angle]))
        self._extend_trails()
        reward, terminated, task_info = 0.0, False, {}
        if self._task_steps:
            rewards, ends, task_info = self.task.step(state, self._events(
                ticks, start, bumps_before, np.array([bumping]), np.array([angle]),
                np.array([changed])))
            reward, terminated = float(rewards[0]), bool(ends[0])
        info = self._info_one(task_info)
        info["step_ticks"] = int(ticks)
        return self._observation_one(), reward, terminated, info

    def _remember(self, rows: np.ndarray, clock_before: np.ndarray, angles: np.ndarray) -> None:
        """Push (clock before the bump, angle) onto the sensing history of the robots ``rows``
        that bumped (``clock_before`` and ``angles`` indexed by robot)."""
        self.history[rows, 1:] = self.history[rows, :-1]
        self.history[rows, 0, 0] = np.minimum(clock_before[rows] / self.options.max_clock, 1.0)
        self.history[rows, 0, 1] = np.mod(angles[rows], 2 * np.pi) / (2 * np.pi)

    def _extend_trails(self) -> None:
        if self.keep_trails:
            for trail, p in zip(self.trails, self.dynamics.state.position, strict=True):
                trail.append(p.copy())

    def _events(self, ticks: int, start: np.ndarray, bumps_before: np.ndarray,
                bumping: np.ndarray, angles: np.ndarray, changed: np.ndarray) -> StepEvents:
        state = self.dynamics.state
        return StepEvents(
            ticks=int(ticks), start=start, end=state.position.copy(), heading=state.heading.copy(),
            bumps=state.bumps - bumps_before, angles=np.where(bumping, angles, math.nan),
            angle_changed=changed, robot_contact=state.blocked & (state.contact_robot >= 0),
        )

    # -- sensing ----------------------------------------------------------------------------
    def observation(self) -> np.ndarray:
        """(m, d) float32 observations, a fresh array every call."""
        state = self.dynamics.state
        opts = self.options
        parts = [np.minimum(state.clock / opts.max_clock, 1.0)[:, None]]
        if self.observes_contact:
            parts.insert(0, state.blocked[:, None].astype(np.float32))
        if opts.history:
            parts.append(self.history.reshape(opts.n_robots, -1))
        if opts.privileged:
            xmin, ymin, xmax, ymax = opts.world.bounds
            parts.append((state.position - (xmin, ymin)) / (xmax - xmin, ymax - ymin))
            parts.append(state.direction)
        if opts.agent_id:
            parts.append(np.eye(opts.n_robots))
        if self.task.observation_size:
            parts.append(self.task.observation(state))
        obs = np.concatenate(parts, axis=1, dtype=np.float32)
        if opts.privileged or self.task.observation_size:
            # a pose on the boundary can round a hair outside [0, 1] / [-1, 1]; contact, clock
            # and history are in range by construction (max_clock bounds every drive)
            np.clip(obs, self.obs_low, self.obs_high, out=obs)
        return obs

    def _observation_one(self) -> np.ndarray:
        """`observation` of a lone robot, (d,); contact, clock and history without numpy calls."""
        opts = self.options
        if opts.privileged or self.task.observation_size:
            return self.observation()[0]
        state = self.dynamics.state
        values = [min(int(state.clock[0]) / opts.max_clock, 1.0)]
        if self.observes_contact:
            values.insert(0, float(state.blocked[0]))
        if opts.history:
            values += self.history[0].ravel().tolist()
        return np.array(values, dtype=np.float32)

    def _info_one(self, task_info: dict) -> dict:
        """`_info` of a lone robot, unpacked to Python scalars (as `BounceEnv` reports it)."""
        state = self.dynamics.state
        xmin, ymin = self.options.world.bounds[:2]
        step = self.options.step_length
        position = state.position[0].copy()
        x, y = position.tolist()
        col_max, row_max = self.cell_max.tolist()
        info = {
            "ticks": int(state.ticks),
            "position": position,
            "heading": float(state.heading[0]),
            "cell": (min(max(math.floor((y - ymin) / step), 0), row_max),
                     min(max(math.floor((x - xmin) / step), 0), col_max)),
            "clock": int(state.clock[0]),
            "bumps": int(state.bumps[0]),
            "contact_edge": int(state.contact_edge[0]),
        }
        info.update(task_info)
        return info

    def _info(self, task_info: dict) -> dict:
        """The true state for evaluation (never part of the observation)."""
        state = self.dynamics.state
        xmin, ymin = self.options.world.bounds[:2]
        cells = np.floor((state.position - (xmin, ymin)) / self.options.step_length).astype(int)
        cells = np.clip(cells, 0, self.cell_max)
        info = {
            "ticks": int(state.ticks),
            "position": state.position.copy(),
            "heading": state.heading.copy(),
            "cell": cells[:, ::-1].copy(),  # (row, col) at cell size = step length
            "clock": state.clock.copy(),
            "bumps": state.bumps.copy(),
            "contact_edge": state.contact_edge.copy(),
            "contact_robot": state.contact_robot.copy(),
        }
        info.update(task_info)
        return info


def _observation_layout(options: EnvOptions, task: Task, observes_contact: bool
                        ) -> list[tuple[str, float, float]]:
    """(label, low, high) of each index of a robot's observation, in order."""
    layout = [("contact", 0.0, 1.0)] if observes_contact else []
    layout.append(("clock: ticks since the last bump / max_clock", 0.0, 1.0))
    for k in range(1, options.history + 1):
        layout += [(f"history, bump {k} back: segment ticks / max_clock", 0.0, 1.0),
                   (f"history, bump {k} back: angle / 360°", 0.0, 1.0)]
    if options.privileged:
        layout += [("pose (privileged): x scaled to [0, 1]", 0.0, 1.0),
                   ("pose (privileged): y scaled to [0, 1]", 0.0, 1.0),
                   ("pose (privileged): cos θ", -1.0, 1.0),
                   ("pose (privileged): sin θ", -1.0, 1.0)]
    if options.agent_id:
        layout += [("the robot's index, one-hot", 0.0, 1.0)] * options.n_robots
    return layout + [(f"task: {label}", -1.0, 1.0) for label in task.observation_labels]
