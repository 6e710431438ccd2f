"""`TeamVectorEnv`: B independent teams of m bouncing robots, stepped together in numpy arrays.

The batched form of the PettingZoo parallel env `MultiBounceEnv` for the configurations it is
trained on: the ``cell`` backend in ``step_mode="tick"``. Every team is one `MultiBounceEnv`
episode; a step is one tick of every robot of every team (`bounce_gym.envs.team_cells`: a table
lookup per robot and ONE `bounce_gym.cells.resolve_moves` call for all teams' robot–robot
conflicts), and the task's reward and info are array formulas over the teams
(`bounce_gym.envs.team_tasks`).

**Batched**: tasks ``free``, ``coverage`` and ``monitoring`` (every task_kwargs, monitoring's
``observe_region`` included), discrete actions with turn commands (``turn_angles``),
``robot_collisions`` ``"bounce"`` (with ``min_sep_cells``) and ``"ignore"``, per-robot angle
sets, ``agent_id``, ``history`` and ``privileged``. **Refused** (a one-line `ConfigError` that
points to the PettingZoo env): other backends, ``step_mode="bounce"``, actuation noise,
``render_mode`` and a `Task` instance of another class than the named tasks'.

**Equality**: step for step the same numbers as B separate ``MultiBounceEnv(**kwargs)`` with the
same actions: ``reset(seed=s)`` seeds team i with s + i and resets it with the env's own core
(`BounceCore.reset`, so the start is drawn from the team's generator by the env's code, and the
reset's observation and task state are the env's), and an autoreset continues that generator, as
``env.reset()`` does. Observations (B, m, d) float32, rewards (B, m) float64, terminations and
truncations (B, m) bool are equal exactly; so are the infos.

**Autoreset** is ``NEXT_STEP``, as in Gymnasium 1.x vector envs: the step that truncates returns
the episode's last observation with ``truncations`` True; the next `step` ignores its actions,
resets every team and returns the reset observations, rewards 0, flags False and the reset's
infos. No batched task terminates, and every team's episode lasts ``max_cycles`` steps, so the
teams stay in lockstep: they are truncated, and reset, together.

**Infos** are one dict of arrays over the teams: the per-robot entries of `MultiBounceEnv`
(``position`` (B, m, 2), ``heading``, ``cell`` (B, m, 2) as (row, col), ``clock``, ``bumps``,
``contact_edge``, ``contact_robot``, each (B, m)) and ``ticks`` (B,); on a step ``step_ticks``
(B,) and the task's step entries (coverage: ``coverage``, ``distance``, ``tv_distance`` (B,);
monitoring: ``in_region_fraction`` (B, m), ``robot_contacts`` and ``encounters`` (B,)); on a
reset the task's reset entries (coverage's three; monitoring: ``in_region`` (B, m) bool).
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode

from bounce_gym.dynamics.noise import Exact
from bounce_gym.envs.multi_bounce_env import PER_ROBOT_INFO, MultiBounceEnv
from bounce_gym.envs.tasks import TASKS
from bounce_gym.envs.team_cells import TeamCells
from bounce_gym.envs.team_tasks import TEAM_TASKS
from bounce_gym.errors import ActionError, ConfigError
from bounce_gym.validate import integer


class TeamVectorEnv:
    """B teams of `MultiBounceEnv` episodes in numpy arrays (see the module docstring).

    Args:
        num_envs: B, the number of teams.
        max_cycles: steps per episode (the PettingZoo env's, default 500).
        render_mode: only None.
        **options: the keyword arguments of `MultiBounceEnv` (one set, shared by the teams).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int, max_cycles: int = 500, render_mode: str | None = None,
                 **options: object) -> None:
        num_envs = integer("num_envs", num_envs, 1)
        if render_mode is not None:
            raise ConfigError("TeamVectorEnv: render_mode is not batched; use the PettingZoo env "
                              "(multi_bounce_v0.parallel_env) to render")
        #: one env of the configuration: it validates the options, and its core resets teams
        self.single = MultiBounceEnv(max_cycles=max_cycles, **options)
        opts = self.options = self.single.options
        core = self.single.core
        reason = _unbatchable(opts, core.task)
        if reason:
            raise ConfigError(f"TeamVectorEnv: {reason}; use the PettingZoo env "
                              "(multi_bounce_v0.parallel_env)")
        self.num_envs = n = int(num_envs)
        self.n_robots = m = opts.n_robots
        self.max_cycles = self.single.max_cycles
        self.possible_agents = list(self.single.possible_agents)
        choices = [np.concatenate((phi, opts.turn_angles)) for phi in opts.angles]
        self.cells = TeamCells(core.dynamics, choices, len(opts.turn_angles), n)
        model = self.cells.model
        self.task = TEAM_TASKS[core.task.name](core.task, n, m, model)
        self.single_observation_space = self.single.observation_space(self.possible_agents[0])
        self.observation_space = spaces.Box(
            np.broadcast_to(core.obs_low, (n, m, len(core.obs_low))),
            np.broadcast_to(core.obs_high, (n, m, len(core.obs_high))), dtype=np.float32)
        self.action_space = spaces.MultiDiscrete(np.tile(self.cells.n_choices, (n, 1)))
        self._rngs: list[np.random.Generator | None] = [None] * n
        self._started = False
        self._autoreset = False
        self._cycles = 0
        self._ticks = np.zeros(n, dtype=np.int64)
        #: every observation column, as the last reset left it: each step writes the contact,
        #: the clock, the history and any privileged pose; the robot ids and the task's
        #: features stay those of the reset's observation
        self._kept_obs = np.zeros((n, m, len(core.obs_low)), dtype=np.float32)
        self._history = np.zeros((n, m, opts.history, 2), dtype=np.float32)
        width = max(self.cells.n_choices)
        #: per robot and action, the angle as the history records it (a fraction of a turn)
        self._history_turns = np.concatenate(
            [np.pad(np.mod(c, 2 * np.pi) / (2 * np.pi), (0, width - len(c))) for c in choices])
        xmin, ymin, xmax, ymax = opts.world.bounds
        #: per position cell: its centre scaled to [0, 1]² (privileged pose, `state`), and
        #: ``info["cell"]`` by `BounceCore`'s arithmetic
        self._scaled = (model.centres - (xmin, ymin)) / (xmax - xmin, ymax - ymin)
        cells = np.floor((model.centres - (xmin, ymin)) / opts.step_length).astype(int)
        self._cell_rc = np.clip(cells, 0, core.cell_max)[:, ::-1].copy()
        bins = np.arange(model.n_bins)
        #: per bin: its heading (bin · width, as the backend snaps headings) and direction
        self._bin_heading = bins * model.bin_width
        self._bin_direction = np.empty((model.n_bins, 2))  # `RobotState.direction`'s arithmetic
        np.cos(self._bin_heading, out=self._bin_direction[:, 0])
        np.sin(self._bin_heading, out=self._bin_direction[:, 1])
        self._pose_columns = slice(2 + 2 * opts.history, 6 + 2 * opts.history)

    # -- episodes ---------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Reset every team; ``seed`` s seeds team i with s + i (None: each team goes on with
        its generator, a fresh one the first time). ``options`` go to every team's reset.
        Returns observations (B, m, d) and infos."""
        if seed is not None:
            seed = integer("seed", seed, 0)
        for i in range(self.num_envs):
            if seed is not None or self._rngs[i] is None:
                self._rngs[i] = seeding.np_random(None if seed is None else seed + i)[0]
        return self._reset_teams(options)

    def _reset_teams(self, options: dict | None) -> tuple[np.ndarray, dict]:
        """Start a new episode in every team: each with the single env's core, from the team's
        generator (`BounceCore.reset`, as `MultiBounceEnv.reset` runs it); the batch takes over
        the cells, the observation and the task state it placed."""
        core, model = self.single.core, self.cells.model
        n, m = self.num_envs, self.n_robots
        p, k = np.empty((n, m), dtype=np.int64), np.empty((n, m), dtype=np.int64)
        task_infos = []
        for i, rng in enumerate(self._rngs):
            obs, info = core.reset(rng, options, strict=False)
            p[i], k[i] = model.decode(model.cell_of(core.state.position, core.state.heading))
            self._kept_obs[i] = obs
            self.task.start(i, core.task)
            task_infos.append({key: value for key, value in info.items()
                               if key not in PER_ROBOT_INFO and key != "ticks"})
        self.cells.place(slice(None), p, k)
        self._ticks[:] = 0
        self._history[:] = 0.0
        self._cycles = 0
        self._started = True
        self._autoreset = False
        infos = self._robot_infos()
        for key in task_infos[0]:
            infos[key] = np.array([info[key] for info in task_infos])
        return self._observation(), infos

    def step(self, actions):
        """One step of every team with ``actions`` (B, m) (action indices, robot i's in column
        i). Returns observations (B, m, d), rewards (B, m), terminations (B, m), truncations
        (B, m) and infos; after a truncation the step resets every team (``NEXT_STEP``)."""
        if not self._started:
            raise ConfigError("step() called before reset()")
        n, m = self.num_envs, self.n_robots
        if self._autoreset:
            obs, infos = self._reset_teams(None)
            done = np.zeros((n, m), dtype=bool)
            return obs, np.zeros((n, m)), done, done.copy(), infos
        actions = self._checked(actions)
        cells = self.cells
        start_p, start_k, clock_before = cells.p, cells.k, cells.clock
        command = cells.commanded(actions).any(axis=1) if len(self.options.turn_angles) else None
        drive, bump = cells.tick(actions, command)
        if self.options.history:
            self._remember(bump, clock_before, actions)
        rewards, task_info = self.task.step(start_p, start_k, drive, bump, cells)
        self._ticks += 1
        self._cycles += 1
        self._autoreset = self._cycles >= self.max_cycles
        infos = self._robot_infos()
        infos.update(task_info)
        infos["step_ticks"] = np.ones(n, dtype=np.int64)
        return (self._observation(), rewards, np.zeros((n, m), dtype=bool),
                np.full((n, m), self._autoreset), infos)

    def _checked(self, actions) -> np.ndarray:
        """``actions`` as a (B, m) int array of valid indices, else `ActionError`."""
        raw = np.asarray(actions)
        shape = (self.num_envs, self.n_robots)
        if raw.shape != shape or raw.dtype.kind not in "iu":
            raise ActionError(f"actions: expected {shape} integer indices, got dtype "
                              f"{raw.dtype}, shape {raw.shape}")
        limit = self.cells.n_choices
        bad = (raw < 0) | (raw >= limit)
        if bad.any():
            b, i = np.argwhere(bad)[0].tolist()
            raise ActionError(f"actions[{b}, {i}]: index {int(raw[b, i])} of robot_{i} is out "
                              f"of range [0, {int(limit[i])})")
        return raw.astype(np.int64, copy=False)

    def _remember(self, bump: np.ndarray, clock_before: np.ndarray, actions: np.ndarray) -> None:
        """Push (clock before the bump, angle) onto the history of the robots that bumped
        (`BounceCore`'s sensing history)."""
        history = self._history
        history[bump, 1:] = history[bump, :-1]
        history[bump, 0, 0] = np.minimum(clock_before[bump] / self.options.max_clock, 1.0)
        turns = self._history_turns.take(self.cells.action_base + actions)
        history[bump, 0, 1] = turns[bump]

    # -- sensing ----------------------------------------------------------------------------
    def _observation(self) -> np.ndarray:
        """(B, m, d) float32 observations in one fresh array: `BounceCore.observation`'s
        values, cast the same way."""
        opts, cells = self.options, self.cells
        obs = self._kept_obs.copy()
        obs[:, :, 0] = cells.blocked
        obs[:, :, 1] = np.minimum(cells.clock / opts.max_clock, 1.0)
        if opts.history:
            obs[:, :, 2:2 + 2 * opts.history] = self._history.reshape(*cells.p.shape, -1)
        if opts.privileged:
            pose = obs[:, :, self._pose_columns]
            pose[..., :2] = self._scaled.take(cells.p, axis=0)
            pose[..., 2:] = self._bin_direction.take(cells.k, axis=0)
            core = self.single.core  # a pose on the boundary can round a hair out of range
            np.clip(pose, core.obs_low[self._pose_columns], core.obs_high[self._pose_columns],
                    out=pose)
        return obs

    def _robot_infos(self) -> dict:
        """The per-robot info entries and ``ticks``, fresh arrays."""
        cells = self.cells
        return {"ticks": self._ticks.copy(),
                "position": self.cells.model.centres.take(cells.p, axis=0),
                "heading": self._bin_heading.take(cells.k),
                "cell": self._cell_rc.take(cells.p, axis=0),
                "clock": cells.clock.copy(), "bumps": cells.bumps.copy(),
                "contact_edge": np.full(cells.p.shape, -1, dtype=np.int64),
                "contact_robot": cells.contact_robot.copy()}

    def state(self) -> np.ndarray:
        """(B, 4m) float32: every team's `MultiBounceEnv.state` (each robot's x, y scaled to
        [0, 1], cos θ, sin θ)."""
        if not self._started:
            raise ConfigError("state() called before reset()")
        cells = self.cells
        pose = np.concatenate((self._scaled.take(cells.p, axis=0),
                               self._bin_direction.take(cells.k, axis=0)), axis=2)
        space = self.single.state_space
        return np.clip(pose.reshape(self.num_envs, -1).astype(np.float32), space.low, space.high)


def _unbatchable(opts, task) -> str | None:
    """Why these options cannot be batched, or None."""
    if opts.backend != "cell":
        return (f"backend {opts.backend!r} is not batched (only the cell backend's robots "
                "step by table lookups)")
    if opts.step_mode != "tick":
        return (f"step_mode {opts.step_mode!r} is not batched (a team's step runs until one of "
                "its robots bumps: use step_mode='tick')")
    if not isinstance(opts.noise, Exact):
        return ("actuation noise is not batched (each team draws its noise from its own "
                "generator, robot by robot)")
    if type(task) is not TASKS.get(task.name):
        return f"task {type(task).__name__} is not batched (only the named tasks are)"
    return None
