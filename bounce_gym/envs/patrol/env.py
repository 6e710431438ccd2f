"""Stochastic multi-robot patrolling against an adversary (Alam 2018, PhD thesis, ch. 4), as a
PettingZoo parallel environment.

| | |
|---|---|
| Import | ``pettingzoo.make("parallel", "bounce_gym/Patrol-v0")`` or ``from bounce_gym.envs.patrol import patrol_v0`` (``parallel_env()``, ``env()``) |
| Agents | ``patroller_0`` … ``patroller_{m-1}``, ``adversary`` |

## Description

The free cells of a World are the vertices of an 8-neighbour graph (thesis §4.3; n vertices,
no corner cutting by default). m patrollers walk on it, one edge per step; a patroller knows
only its vertex and tells its outgoing edges apart in a fixed clockwise order, as a robot
without localisation can (§4.3). Each carries an omnidirectional sensor of range l
(``sensor_range``, in cells): it sees the cells of the limited visibility polygon V(x_v) of
Eq. 4.1 (`bounce_gym.cells.visibility`). The adversary chooses a target vertex z and when to
start; it needs t_a (``attack_time``) steps undetected. The patrollers' strategy is a Markov
chain P on the graph (``strategy``; the uniform random walk by default), which the adversary
is told, as in the Stackelberg model of §4.4; the env does not make the patrollers follow it.

**Capture rule** (§4.3.5): the attack on z is caught if some patroller stands in T, the cells
seen from z, when the attack starts (the positions at the beginning of the step in which the
adversary starts it) or at the end of any of the t_a steps that follow (the start step is the
first); otherwise it succeeds at the end of the t_a-th step. `capture_probabilities` gives
p_d(t_a) = Pr[T_detect ≤ t_a] exactly from P (`bounce_gym.envs.patrol.capture`).

The **AEC form** (``env()``) is PettingZoo's ``parallel_to_aec`` conversion: the agents choose
in turn and the world moves once all have chosen; each action is checked (`check_action`) as it
is given.

## Action Space

Patroller: ``Discrete(8)``, move along the edge in direction k clockwise from north (0 N, 1 NE,
2 E, 3 SE, 4 S, 5 SW, 6 W, 7 NW); a direction without an edge from the patroller's vertex is
illegal (``action_mask``) and leaves it where it is. Adversary: ``Discrete(n + 1)``, 0 wait,
1 + z start the attack on vertex z; once the attack has started only 0 is legal.

## Observation Space

Patroller: ``Box(0, 1, (2n,))``, a one-hot of its vertex, then the vertices of the other
patrollers its sensor sees. Adversary: ``Box(0, 1, (n + 3,))``, `capture_probabilities()` for
an attack that starts at the episode's start (n), attack started (1), attack progress
elapsed / t_a (1), clock steps / ``max_cycles`` (1); with ``adversary_observes="positions"``
also which vertices a patroller occupies (n more). ``state()``: each patroller's one-hot
vertex, the one-hot attack target, attack started, attack progress, clock; Box [0, 1]^(mn + n
+ 3).

## Rewards

Zero-sum, paid in the step the episode ends: capture (or deterred) gives each patroller +1/m and
the adversary −1; success gives each patroller −1/m and the adversary +1; every other step 0.

## Starting State

The patrollers on distinct vertices drawn uniformly, unless ``start`` (or
``reset(options={"start": [...]})``) gives them; the adversary has not chosen a target yet.

## Episode End

Every agent terminates when the attack is caught or succeeds, or as "deterred" when the
adversary has not started by step ``max_cycles − t_a`` (0-based; an attack started then ends at
step ``max_cycles``). Nothing is truncated: every episode ends by ``max_cycles`` steps.

## Arguments

``render_mode`` (None, "rgb_array", "human"), then the keyword arguments declared in
`bounce_gym.envs.patrol.options.PatrolOptions` (type, default and meaning of each: the model,
the signature of `PatrolEnv` and the "Arguments" table of its docs page); ``strategy`` and
``start`` also per episode, with ``reset(options={"strategy": P, "start": [...]})``, else the
constructor's. Each agent's info holds ``outcome`` (None,
"capture", "success", "deterred"), ``attack_target`` (-1 before the attack),
``attack_started`` (its step, or -1), ``attack_elapsed``, ``step``, ``action_mask`` (int8) and
``illegal_action``; a patroller's also its ``vertex``.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping

import numpy as np
from gymnasium import logger, spaces
from gymnasium.utils import seeding
from pettingzoo import ParallelEnv

from bounce_gym import validate
from bounce_gym.envs.arguments import TakesArguments, parse
from bounce_gym.envs.parallel_step import check_parallel_actions
from bounce_gym.envs.patrol import capture
from bounce_gym.envs.patrol.board import DIRECTIONS
from bounce_gym.envs.patrol.options import PatrolOptions, check_start, check_strategy
from bounce_gym.envs.render.owner import RENDER_MODES, RendererOwner, checked_render_mode
from bounce_gym.envs.reset_options import checked_reset_options
from bounce_gym.errors import ActionError, ConfigError

ADVERSARY = "adversary"
RESET_OPTIONS = frozenset({"strategy", "start"})
#: how many strategies' capture probabilities are kept
CACHE_SIZE = 16


class PatrolEnv(TakesArguments[PatrolOptions], RendererOwner, ParallelEnv):
    """The parallel form; see the module docstring."""

    metadata = {"render_modes": RENDER_MODES, "render_fps": 4, "name": "patrol_v0",
                "is_parallelizable": True}
    options_model = PatrolOptions

    def __init__(self, render_mode: str | None = None, **options: object) -> None:
        self.render_mode = checked_render_mode(render_mode)
        self.options: PatrolOptions = parse(type(self), options)
        self.board = self.options.board
        self.max_cycles = self.options.max_cycles
        self.attack_time = self.options.attack_time
        m, n = self.options.n_patrollers, self.board.n
        self.n_patrollers = m
        self.possible_agents = [f"patroller_{i}" for i in range(m)] + [ADVERSARY]
        self.agent_index = {a: k for k, a in enumerate(self.possible_agents)}
        self._patroller_obs = spaces.Box(0.0, 1.0, (2 * n,), dtype=np.float32)
        watch_positions = self.options.adversary_observes == "positions"
        self._adversary_obs = spaces.Box(0.0, 1.0, (n + 3 + n * watch_positions,),
                                         dtype=np.float32)
        self._move = spaces.Discrete(len(DIRECTIONS))
        self._attack = spaces.Discrete(n + 1)
        self.state_space = spaces.Box(0.0, 1.0, (m * n + n + 3,), dtype=np.float32)
        self.agents: list[str] = []
        self.np_random: np.random.Generator | None = None
        self.np_random_seed: int | None = None
        self._strategy = self.options.walk
        self._capture: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}
        self._pos = np.zeros(m, dtype=np.int64)
        self._episode_start = self.options.start_vertices
        self._start_capture = np.zeros(n)
        self._new_episode()

    # -- read-only views ------------------------------------------------------------------------
    @property
    def graph(self):
        """The networkx cell graph (vertices 0..n-1 with ``pos``, ``cell``; edge ``length``)."""
        return self.board.graph

    @property
    def n_vertices(self) -> int:
        return self.board.n

    @property
    def visibility(self):
        """The `CellVisibility` at ``sensor_range``."""
        return self.board.visibility

    @property
    def strategy(self) -> np.ndarray:
        """The current patrol strategy, (n, n) row-stochastic (read-only)."""
        return self._strategy

    @property
    def neighbour_table(self) -> np.ndarray:
        """(n, 8) int: the neighbour of each vertex in direction k, or -1 (read-only)."""
        return self.board.neighbours

    @property
    def watch_regions(self) -> list[np.ndarray]:
        """T of every target vertex z: the vertices seen from z, ascending (§4.3.5)."""
        return [np.flatnonzero(row) for row in self.board.seen]

    def positions(self) -> np.ndarray:
        """(m,) int64, the patrollers' vertices now."""
        return self._pos.copy()

    def action_towards(self, v: int, u: int) -> int:
        """The patroller action (direction index) that moves from vertex ``v`` to ``u``."""
        v = validate.integer("v", v, 0, self.board.n - 1)
        u = validate.integer("u", u, 0, self.board.n - 1)
        row = self.board.neighbours[v]
        hits = np.flatnonzero(row == u)
        if len(hits) == 0:
            raise ConfigError(f"u: vertex {u} is not a neighbour of vertex {v}; its neighbours "
                              f"are {row[row >= 0].tolist()}")
        return int(hits[0])

    def capture_probabilities(self, positions: object = None) -> np.ndarray:
        """(n,) probability that an attack on each vertex, started now, is caught (§4.3.5).

        Args:
            positions: None for the patrollers placed as the env places them at reset (the
                episode's ``start``, or distinct uniform vertices); else one vertex per
                patroller.
        """
        S, uniform = self._cached()
        if positions is not None:
            where = check_start(positions, self.board.n, self.n_patrollers, "positions")
            return capture.capture_from(S, where)
        if self._episode_start is not None:
            return capture.capture_from(S, self._episode_start)
        return uniform.copy()

    def _cached(self) -> tuple[np.ndarray, np.ndarray]:
        """The survival matrix of the current strategy and its capture probabilities from
        distinct uniform start vertices, computed once per strategy."""
        key = hashlib.blake2b(self._strategy.tobytes(), digest_size=16).digest()
        if key not in self._capture:
            if len(self._capture) >= CACHE_SIZE:
                self._capture.pop(next(iter(self._capture)))
            S = capture.survival(self._strategy, self.board.seen, self.attack_time)
            self._capture[key] = (S, capture.capture_from_distinct_uniform(S, self.n_patrollers))
        return self._capture[key]

    # -- PettingZoo API ---------------------------------------------------------------------------
    def observation_space(self, agent: str) -> spaces.Space:
        """The same (shared) space object on every call, as PettingZoo's API test requires."""
        return self._adversary_obs if agent == ADVERSARY else self._patroller_obs

    def action_space(self, agent: str) -> spaces.Discrete:
        return self._attack if agent == ADVERSARY else self._move

    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is not None or self.np_random is None:
            self.np_random, self.np_random_seed = seeding.np_random(seed)
        given = checked_reset_options(options, RESET_OPTIONS, strict=False)
        strategy = (check_strategy(given["strategy"], self.board, "options.strategy")
                    if "strategy" in given else self.options.walk)
        start = (check_start(given["start"], self.board.n, self.n_patrollers, "options.start")
                 if "start" in given else self.options.start_vertices)
        self._strategy, self._episode_start = strategy, start
        if self._episode_start is not None:
            self._pos = self._episode_start.copy()
        else:
            self._pos = self.np_random.choice(self.board.n, self.n_patrollers, replace=False)
        self._start_capture = self.capture_probabilities()
        self._new_episode()
        self.agents = list(self.possible_agents)
        if self.render_mode == "human":
            self.render()
        illegal = np.zeros(len(self.possible_agents), dtype=bool)
        return self._observations(), self._infos(illegal)

    def _new_episode(self) -> None:
        self.cycles = 0
        self._target = -1
        self._started = -1
        self._elapsed = 0
        self._outcome: str | None = None

    def step(self, actions: Mapping):
        check_parallel_actions(self, actions)
        codes = np.array([self.check_action(a, actions[a]) for a in self.possible_agents])
        m = self.n_patrollers
        moves = self.board.neighbours[self._pos, codes[:m]]
        illegal = np.append(moves < 0, self._target >= 0 and codes[m] != 0)
        caught = False
        if codes[m] > 0 and not illegal[m]:
            self._target, self._started = int(codes[m]) - 1, self.cycles
            caught = bool(self.board.seen[self._target, self._pos].any())
        self._pos = np.where(moves < 0, self._pos, moves)
        self.cycles += 1
        if self._target >= 0:
            self._elapsed += 1
            caught = caught or bool(self.board.seen[self._target, self._pos].any())
            if caught:
                self._outcome = "capture"
            elif self._elapsed == self.attack_time:
                self._outcome = "success"
        elif self.cycles > self.max_cycles - self.attack_time:
            self._outcome = "deterred"
        rewards = self._rewards()
        live = list(self.agents)
        done = self._outcome is not None
        result = (self._observations(), {a: float(rewards[self.agent_index[a]]) for a in live},
                  dict.fromkeys(live, done), dict.fromkeys(live, False), self._infos(illegal))
        if done:
            self.agents = []
        if self.render_mode == "human":
            self.render()
        return result

    def check_action(self, agent: str, action: object) -> int:
        """The action code of ``agent``; `ActionError` naming the agent and what is allowed for
        anything but an integer of its action space, and with ``illegal_action="error"`` for an
        action that is illegal now. The AEC form checks each action with it as it is given."""
        size = self.action_space(agent).n
        value = np.asarray(action)
        if value.shape != () or value.dtype.kind not in "iu" or not 0 <= int(value) < size:
            raise ActionError(f"action of {agent}: expected an integer in [0, {size - 1}], got "
                              f"{action!r}")
        code = int(value)
        if self.options.illegal_action == "error" and not self.action_mask(agent)[code]:
            self._refuse(agent, code)
        return code

    def _refuse(self, agent: str, code: int) -> None:
        legal = np.flatnonzero(self.action_mask(agent)).tolist()
        if agent == ADVERSARY:
            raise ActionError(f"action of {agent}: {code} is illegal, the attack started at "
                              f"step {self._started}; the only legal action is {legal}")
        names = [f"{d} ({DIRECTIONS[d]})" for d in legal]
        vertex = self._pos[self.agent_index[agent]]
        raise ActionError(f"action of {agent}: {code} ({DIRECTIONS[code]}) is illegal at vertex "
                          f"{vertex} (no edge); legal actions are {names}")

    def _rewards(self) -> np.ndarray:
        """Per agent (patrollers, then the adversary); zero-sum."""
        sign = {None: 0.0, "capture": 1.0, "deterred": 1.0, "success": -1.0}[self._outcome]
        rewards = np.full(len(self.possible_agents), sign / self.n_patrollers)
        rewards[-1] = -sign
        return rewards

    def action_mask(self, agent: str) -> np.ndarray:
        """int8, the legal actions of ``agent`` now: (8,) for a patroller, (n + 1,) for the
        adversary (only 0 once the attack started)."""
        if agent == ADVERSARY:
            mask = np.ones(self.board.n + 1, dtype=np.int8)
            if self._target >= 0:
                mask[1:] = 0
            return mask
        return (self.board.neighbours[self._pos[self.agent_index[agent]]] >= 0).astype(np.int8)

    def action_labels(self, agent: str) -> tuple[str, ...]:
        """What each action of ``agent`` is."""
        if agent != ADVERSARY:
            return tuple(f"move {direction}" for direction in DIRECTIONS)
        return ("wait", *("start the attack on vertex action − 1",) * self.board.n)

    def observation_labels(self, agent: str) -> tuple[str, ...]:
        """What each index of ``agent``'s observation is (`_observations`)."""
        n = self.board.n
        if agent != ADVERSARY:
            return ("own vertex, one-hot",) * n + ("another patroller seen at the vertex",) * n
        labels = (("capture probability of an attack on the vertex started at step 0",) * n
                  + ("attack started", "attack progress: steps elapsed / attack_time",
                     "clock: steps / max_cycles"))
        if self.options.adversary_observes == "positions":
            labels += ("a patroller at the vertex",) * n
        return labels

    def _observations(self) -> dict[str, np.ndarray]:
        m, n = self.n_patrollers, self.board.n
        pos = self._pos
        patrol = np.zeros((m, 2 * n), dtype=np.float32)
        patrol[np.arange(m), pos] = 1.0
        sees = self.board.seen[pos[:, None], pos[None, :]]
        np.fill_diagonal(sees, False)
        i, j = np.nonzero(sees)
        patrol[i, n + pos[j]] = 1.0
        obs = {a: patrol[self.agent_index[a]] for a in self.agents if a != ADVERSARY}
        if ADVERSARY in self.agents:
            obs[ADVERSARY] = self._adversary_observation()
        return obs

    def _adversary_observation(self) -> np.ndarray:
        attack = np.array([float(self._target >= 0), self._elapsed / self.attack_time,
                           self.cycles / self.max_cycles])
        parts = [self._start_capture, attack]
        if self.options.adversary_observes == "positions":
            occupied = np.zeros(self.board.n)
            occupied[self._pos] = 1.0
            parts.append(occupied)
        return np.clip(np.concatenate(parts), 0.0, 1.0).astype(np.float32)

    def _infos(self, illegal: np.ndarray) -> dict[str, dict]:
        shared = {"outcome": self._outcome, "attack_target": self._target,
                  "attack_started": self._started, "attack_elapsed": self._elapsed,
                  "step": self.cycles}
        infos = {}
        for a in self.agents:
            k = self.agent_index[a]
            info = {**shared, "action_mask": self.action_mask(a),
                    "illegal_action": bool(illegal[k])}
            if a != ADVERSARY:
                info["vertex"] = int(self._pos[k])
            infos[a] = info
        return infos

    def state(self) -> np.ndarray:
        m, n = self.n_patrollers, self.board.n
        state = np.zeros(m * n + n + 3, dtype=np.float32)
        state[np.arange(m) * n + self._pos] = 1.0
        if self._target >= 0:
            state[m * n + self._target] = 1.0
        state[-3:] = (float(self._target >= 0), self._elapsed / self.attack_time,
                      self.cycles / self.max_cycles)
        return state

    def render(self):
        if self.render_mode is None:
            logger.warn("render() called with render_mode=None; pass render_mode to the env")
            return None
        from bounce_gym.envs.patrol.render import PatrolRenderer

        if self._renderer is None:
            self._renderer = PatrolRenderer(self.board)
        labels = [f"{self.board.world.name}  step {self.cycles}"]
        if self._target >= 0:
            labels.append(f"attack on {self._target}: {self._elapsed}/{self.attack_time}")
        if self._outcome is not None:
            labels.append(self._outcome)
        frame = self._renderer.draw_patrol(self._pos, self._target,
                                           self._elapsed / self.attack_time, labels)
        if self.render_mode == "human":
            self._renderer.show(frame, self.metadata["render_fps"])
            return None
        return frame
