"""Several bouncing robots as a PettingZoo environment (parallel and AEC forms).

| | |
|---|---|
| Import | ``from bounce_gym.envs import multi_bounce_v0`` (``parallel_env()``, ``env()``) or ``pettingzoo.make("parallel", "bounce_gym/MultiBounce-v0")`` |
| Agents | ``robot_0`` … ``robot_{m-1}`` |

## Description

m robots with contact sensors and clocks in one world. Robots bump into walls and — with
``robot_collisions="bounce"`` — into each other (both robots of a head-on contact turn; thesis
Eq. 3.9). **Parallel form** (`MultiBounceEnv`): every step all robots submit an angle; robots that
are blocked use it, the others drive on. In ``step_mode="bounce"`` a step runs until some robot
is blocked again. **AEC form** (`MultiBounceAEC`): event-driven — the agent to act is the next
robot that bumps; once every blocked robot has chosen, the world runs until the next bump.

## Action Space

Per robot: ``action_type="discrete"`` — ``Discrete(len(Φ_i) + len(turn_angles))``, the index of
an angle of the robot's own set Φ_i, then the turn commands; ``action_type="continuous"`` —
``Box(-1, 1, (1,), float32)``, mapped linearly onto the robot's ``angle_range``.

**Turn commands** (parallel form, discrete actions): with ``turn_angles=[45, -45]`` each robot
has ``len(turn_angles)`` extra actions after its angles — index ``len(Φ_i) + j`` is a
clock-timed turn in place by ``turn_angles[j]`` degrees (CCW positive), the one-robot ±Δθ
"neighbour jump" of Alam & Bobadilla's Algorithm 1 (2020, §4.1; docs/choices/multirobot.md, "A neighbour jump
is a timed turn"). If any robot picks a turn,
the step is one *command tick*: the robots that picked a turn turn, every other robot waits in
place (`bounce_gym.dynamics.BounceDynamics.turn`); no bump happens and every clock advances by
one. Otherwise the step is an ordinary one.

## Observation Space

Per robot, a flat ``Box`` of float32: ``contact`` (bump sensor pressed; left out only for a
lone robot in bounce mode without turn commands, which is always in contact), ``clock`` (ticks
since its last bump / max_clock), then the optional ``history``, ``privileged`` pose, its index
one-hot (``agent_id``) and the task's features (monitoring: its region with
``observe_region``); `bounce_gym.envs.core` has the layout. ``state()`` is every robot's true
pose (x, y scaled to [0, 1], cos θ, sin θ), for centralised critics.

## Rewards

From the task: ``free`` (0), ``coverage`` (shared: new cells and distance to the target, split
evenly), ``monitoring`` (time in the robot's own region minus a penalty per robot contact).

## Starting State

Every robot at a uniformly random point of the free space with a uniformly random heading;
robots that collide are placed one after another so that none overlaps another (on the cell
backend: distinct free cells, ``min_sep_cells`` + 1 apart), unless
``reset(options={"start": ...})`` gives the poses. In bounce mode the robots then drive until
one of them is blocked.

## Episode End

No task terminates early. Parallel: all robots are truncated after ``max_cycles`` steps.
AEC: each robot is truncated after ``max_cycles`` decisions of its own.

## Arguments

``max_cycles`` (default 500) and ``render_mode``, then every keyword argument declared in
`bounce_gym.envs.options.EnvOptions` — those of `BounceEnv` plus ``n_robots``,
``robot_collisions``, ``turn_angles`` and ``min_sep_cells`` (docs/choices/multirobot.md, "Robot–robot
conflicts on the grid") — with this env's own defaults (`_MultiBase.option_defaults`: the
``grid_15x15`` world, 4 robots of radius 0.3, collisions on); each argument's type, default and
meaning are in the signature of the class and the "Arguments" table of its docs page. Planners
get the env's discrete model from ``env.unwrapped.cell_model()``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from pettingzoo import AECEnv, ParallelEnv

from bounce_gym.envs.actions import action_space, to_angle
from bounce_gym.envs.aec_actions import check_dead_action
from bounce_gym.envs.base import EnvBase
from bounce_gym.envs.parallel_step import check_parallel_actions, finish_parallel_step
from bounce_gym.errors import ConfigError
from bounce_gym.validate import integer

MULTI_ROBOT_TASKS = ("free", "coverage", "monitoring")


#: info entries with one row per robot; each agent's info holds its own row
PER_ROBOT_INFO = ("position", "heading", "cell", "clock", "bumps", "contact_edge",
                  "contact_robot")



class _MultiBase(EnvBase):
    """Construction, spaces and per-agent bookkeeping shared by both forms."""

    metadata = {**EnvBase.metadata, "name": "multi_bounce_v0", "is_parallelizable": True}
    #: the multi-robot envs' own defaults of the arguments of `bounce_gym.envs.options.EnvOptions`
    option_defaults = {"world": "grid_15x15", "n_robots": 4, "robot_radius": 0.3,
                       "robot_collisions": "bounce"}

    def __init__(self, max_cycles: int = 500, render_mode: str | None = None,
                 **options: object) -> None:
        max_cycles = integer("max_cycles", max_cycles, 1)
        self._build(options, render_mode, MULTI_ROBOT_TASKS)
        self.max_cycles = int(max_cycles)
        self.possible_agents = [f"robot_{i}" for i in range(self.options.n_robots)]
        self.agent_index = {a: i for i, a in enumerate(self.possible_agents)}
        self._obs_space = spaces.Box(self.core.obs_low, self.core.obs_high, dtype=np.float32)
        #: per robot, what its action indices select: Φ_i, then the turn commands
        self._choices = [np.concatenate((phi, self.options.turn_angles))
                         for phi in self.options.angles]
        self._discrete = self.options.action_type == "discrete"
        self._action_spaces = {
            a: action_space(self.options.action_type, len(self._choices[i]))
            for a, i in self.agent_index.items()
        }
        m = self.options.n_robots
        self.state_space = spaces.Box(
            np.tile([0.0, 0.0, -1.0, -1.0], m).astype(np.float32),
            np.ones(4 * m, dtype=np.float32), dtype=np.float32,
        )
        self.np_random: np.random.Generator | None = None
        self.np_random_seed: int | None = None
        self._check_form()

    def _check_form(self) -> None:
        """Refuse the arguments this form cannot run (the AEC form's checks)."""

    def observation_space(self, agent: str) -> spaces.Space:
        """The same (shared) space object on every call, as PettingZoo's API test requires."""
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space:
        return self._action_spaces[agent]

    def _seed(self, seed: int | None) -> np.random.Generator:
        """The episode's generator: a new one when ``seed`` is given or none exists yet."""
        if seed is not None or self.np_random is None:
            self.np_random, self.np_random_seed = seeding.np_random(seed)
        return self.np_random

    def _angle(self, agent: str, action: object) -> float:
        """The radians an action selects: a bounce angle of Φ_i or, past Φ_i, a turn command."""
        i = self.agent_index[agent]
        choices = self._choices[i]
        if self._discrete and isinstance(action, int | np.integer) \
                and not isinstance(action, bool) and 0 <= action < len(choices):
            return float(choices[action])  # a plain index: what to_angle would return, sooner
        return to_angle(action, self.options.action_type, choices,
                        self.options.angle_range[i], who=f"action of {agent}")

    def _agent_infos(self, info: dict, agents) -> dict[str, dict]:
        """Each agent's info: the shared entries, and its own row of every per-robot entry.

        One copy per per-robot entry, then each agent gets a row of it (a view, or a numpy
        scalar): no per-agent copies, and no agent's row can change another's or the env's data.
        """
        shared = {k: v for k, v in info.items() if k not in PER_ROBOT_INFO}
        rows = list(zip(*(list(np.array(info[k])) for k in PER_ROBOT_INFO), strict=True))
        index = self.agent_index
        return {a: {**shared, **dict(zip(PER_ROBOT_INFO, rows[index[a]], strict=True))}
                for a in agents}

    def state(self) -> np.ndarray:
        st = self.core.state
        xmin, ymin, xmax, ymax = self.options.world.bounds
        pos = (st.position - (xmin, ymin)) / (xmax - xmin, ymax - ymin)
        flat = np.concatenate((pos, st.direction), axis=1).ravel().astype(np.float32)
        return np.clip(flat, self.state_space.low, self.state_space.high)


class MultiBounceEnv(_MultiBase, ParallelEnv):
    """The parallel form; see the module docstring."""

    def reset(self, seed: int | None = None, options: dict | None = None):
        obs, info = self.core.reset(self._seed(seed), options, strict=False)
        self.agents = list(self.possible_agents)
        self.cycles = 0
        if self.render_mode == "human":
            self.render()
        return self._per_agent(obs), self._agent_infos(info, self.agents)

    def _per_agent(self, obs: np.ndarray) -> dict[str, np.ndarray]:
        return {a: obs[self.agent_index[a]] for a in self.agents}

    def step(self, actions: Mapping):
        check_parallel_actions(self, actions)
        angles = np.array([self._angle(a, actions[a]) for a in self.possible_agents])
        turns = None
        if len(self.options.turn_angles):  # discrete: the actions are valid indices by now
            commanded = np.array([int(np.asarray(actions[a]).reshape(())) >= len(phi)
                                  for a, phi in zip(self.possible_agents, self.options.angles,
                                                    strict=True)])
            turns = np.where(commanded, angles, np.nan)
            # a turn step uses no bounce angle; keep a valid one in the unused slots
            angles = np.where(commanded, [phi[0] for phi in self.options.angles], angles)
        obs, rewards, terminated, info = self.core.step(angles, turns)
        return finish_parallel_step(self, obs, rewards, terminated, info)


class MultiBounceAEC(_MultiBase, AECEnv):
    """The event-driven AEC form: the next robot to bump is the next agent to act.

    Decisions are collected from every blocked robot (lowest index first); then the world runs
    until some robot bumps again. A bad action raises `ActionError` (naming the agent and what
    is allowed) before anything changes; a done robot's only action is None. A robot is truncated after ``max_cycles`` decisions; a truncated
    robot that bumps keeps its last angle. Requires ``step_mode="bounce"``.
    """

    def _check_form(self) -> None:
        if self.options.step_mode != "bounce":
            raise ConfigError("step_mode: the AEC form is event-driven and needs 'bounce'; use "
                              "the parallel form for tick stepping")
        if len(self.options.turn_angles):
            raise ConfigError("turn_angles: turn commands need the parallel form (the AEC form "
                              "asks only robots that bump)")

    def reset(self, seed: int | None = None, options: dict | None = None) -> None:
        obs, info = self.core.reset(self._seed(seed), options, strict=False)
        self._obs = obs
        self.agents = list(self.possible_agents)
        self.rewards = dict.fromkeys(self.agents, 0.0)
        self._cumulative_rewards = dict.fromkeys(self.agents, 0.0)
        self.terminations = dict.fromkeys(self.agents, False)
        self.truncations = dict.fromkeys(self.agents, False)
        self.infos = self._agent_infos(info, self.agents)
        self.decisions = dict.fromkeys(self.agents, 0)
        self._pending: dict[str, float] = {}
        self._last_angle = np.array([a[0] for a in self.options.angles])
        self.agent_selection = self._next_agent()
        if self.render_mode == "human":
            self.render()

    def observe(self, agent: str) -> np.ndarray:
        return self._obs[self.agent_index[agent]].copy()

    def _next_agent(self) -> str:
        """The lowest-index live robot that is blocked and has not chosen yet."""
        blocked = self.core.state.blocked
        for agent in self.agents:
            if blocked[self.agent_index[agent]] and agent not in self._pending:
                return agent
        raise RuntimeError("no live robot is waiting for a decision")

    def step(self, action) -> None:
        agent = self.agent_selection
        if self.terminations[agent] or self.truncations[agent]:
            check_dead_action(agent, action)
            self._was_dead_step(action)
            if self.agents and not self._deads_waiting():
                self.agent_selection = self._advance()
            return
        self._pending[agent] = self._angle(agent, action)
        self.decisions[agent] += 1
        self._cumulative_rewards[agent] = 0.0
        if self.decisions[agent] >= self.max_cycles:
            self.truncations[agent] = True
        waiting = [a for a in self.agents if self.core.state.blocked[self.agent_index[a]]
                   and a not in self._pending and not self.truncations[a]]
        if waiting:
            self.agent_selection = waiting[0]
            self._clear_rewards()
        else:
            self.agent_selection = self._advance()
        if self.render_mode == "human":
            self.render()

    def _deads_waiting(self) -> bool:
        return any(self.terminations[a] or self.truncations[a] for a in self.agents)

    def _advance(self) -> str:
        """Run the world until a live robot must decide; returns the next agent to select."""
        while True:
            if self._deads_waiting():
                # PettingZoo: finished agents are stepped once with None before they leave
                self._clear_rewards()
                return next(a for a in self.agents if self.terminations[a] or self.truncations[a])
            angles = self._last_angle.copy()
            for agent, angle in self._pending.items():
                angles[self.agent_index[agent]] = angle
            self._pending = {}
            bumping = self.core.state.blocked.copy()
            self._last_angle[bumping] = angles[bumping]
            obs, rewards, terminated, info = self.core.step(angles)
            self._obs = obs
            self.rewards = {a: float(rewards[self.agent_index[a]]) for a in self.agents}
            self._accumulate_rewards()
            for a in self.agents:
                self.terminations[a] = bool(terminated[self.agent_index[a]])
            self.infos = self._agent_infos(info, self.agents)
            if self._deads_waiting():
                continue
            blocked = self.core.state.blocked
            live = [a for a in self.agents if blocked[self.agent_index[a]]]
            if live:
                return live[0]

    def _clear_rewards(self) -> None:
        self.rewards = dict.fromkeys(self.agents, 0.0)
