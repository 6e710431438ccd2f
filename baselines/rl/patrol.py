"""The patrol game of ``bounce_gym/Patrol-v0`` (Alam 2018, thesis ch. 4) as two training problems:
one side learns while the other plays a fixed policy inside a wrapper.

* `PatrollersEnv` — the patrollers learn (one policy shared by all of them, trained through
  `baselines.rl.parallel_vec_env.ParallelToVecEnv`); the adversary inside is

  - ``"random"`` (default): it attacks a uniformly random target at a uniformly random step of
    ``0 … max_cycles − t_a``, the steps at which the env lets an attack start (never
    "deterred"). Non-strategic on purpose: the
    patrollers see neither the target nor the clock, so what they can learn is a memoryless,
    stochastic patrol — a Markov chain — and against this adversary its return is the capture
    probability averaged over targets and over the (nearly stationary) state the patrol is in
    when the attack starts: the patrol minimises average vulnerability.
  - ``"best_response"``: the Stackelberg best response of §4.4.2 — at step 0, the vertex of
    least ``env.capture_probabilities()`` (ties to the lowest index). That probability is
    computed from the chain the env *announces* (``strategy``; default the uniform random walk),
    not from the policy being learned, which announces none: the target is the same every
    episode and the patrollers learn to guard one vertex. Hence not the default.
  - ``"fictitious_play"`` and ``"softmin"``: the Stackelberg adversary of the evaluation
    (`baselines.patrolling.policies.BestResponseAdversary`, strategy mode) played against the
    policy being learned itself. Before every rollout, `response_callback` (added to the
    training by `training_callbacks`) tells the env the policy's action distributions, from
    which `PatrollersEnv.respond` builds the chain the policy induces when a patroller is alone
    at each vertex (`baselines.patrolling.policies.policy_chains`, what the evaluation tells
    its adversary about learned patrollers) and its exact capture probability of an attack on
    each target at step 0 from distinct uniform starts (`policy_capture`). Every episode then
    attacks at step 0; the target is drawn

    - ``fictitious_play``: from the history of best responses (fictitious play, Brown 1951):
      each `respond` adds one to the count of the target of least capture probability, and
      the target is drawn in proportion to the counts — the adversary's empirical mixed
      strategy, which a pure best response (a new argmin each rollout) would make cycle;
    - ``softmin``: with probability ∝ exp(−(c_z − min c) / ``temperature``) over the current
      capture probabilities c (a smoothed best response: ``temperature`` → 0 is the argmin).

    Before the first `respond` (the first episode) the target is uniformly random. A fraction
    ``random_fraction`` of the episodes (default 0) attack a uniformly random target at step 0
    instead, so that no target goes untrained.

* `AdversaryEnv` — the adversary learns; the patrollers follow a Markov chain drawn per episode,
  uniformly, from ``strategies`` (default MAECT, §4.4.1, and the uniform random walk), and the
  env is told the chain (``reset(options={"strategy": P})``), so the adversary's observation —
  the per-target capture probabilities — says which one it faces, as the Stackelberg model
  assumes the adversary knows the strategy (§4.4.2). Its best response is the target of least
  capture probability, at once.

Both report ``info["is_success"]`` for the side that learns (patrollers: capture or deterred;
adversary: success), which the training monitor logs (`baselines.rl.train_env.MONITOR_KEYS`).
Illegal patroller moves are the env's documented no-op (``illegal_action="stay"``): plain PPO,
no action masks (docs/choices/rl_training.md, "Patrol game: plain PPO without action masks").

Seeding: ``reset(seed=s)`` resets the env with s and restarts the wrapper's own stream (the
adversary's plan, the patrollers' draws) from ``[s, STREAM]``, a stream apart from the env's.
"""

from __future__ import annotations

from collections.abc import Sequence

import gymnasium as gym
import numpy as np
from pettingzoo import ParallelEnv

from bounce_gym import validate
from bounce_gym.errors import ConfigError

PATROL_ID = "bounce_gym/Patrol-v0"
ADVERSARY = "adversary"
#: What a training configuration of Patrol-v0 trains (``role``): the wrapper of each.
ROLES = ("patrollers", "adversary")
#: The adversaries `PatrollersEnv` can play against.
ADVERSARIES = ("random", "best_response", "fictitious_play", "softmin")
#: Those of `ADVERSARIES` that best-respond to the policy being learned (`PatrollersEnv.respond`).
RESPONDING = ("fictitious_play", "softmin")
#: The chains `AdversaryEnv` can draw for the patrollers.
STRATEGIES = ("maect", "random_walk")
#: Second entropy word of the wrappers' random stream, so it differs from the env's.
STREAM = 0x9A701
#: Outcomes that count as the patrollers' win.
PATROLLER_WINS = ("capture", "deterred")


def patrol_env(**patrol_kwargs):
    """A Patrol-v0 parallel env (its own `ConfigError` for bad arguments)."""
    import pettingzoo

    import bounce_gym  # noqa: F401  (registers the environments)

    return pettingzoo.make("parallel", PATROL_ID, **patrol_kwargs)


def _stream(seed: int | None) -> np.random.Generator:
    return np.random.default_rng(None if seed is None else [seed, STREAM])


def role_env(role: str, env_kwargs: dict):
    """The training env of ``role`` (`ROLES`) with ``env_kwargs``."""
    if role == "patrollers":
        return PatrollersEnv(**env_kwargs)
    return AdversaryEnv(**env_kwargs)


class PatrollersEnv(ParallelEnv):
    """The patrollers of Patrol-v0 as a PettingZoo parallel env, the adversary played inside
    (module docstring). Spaces, observations, rewards and infos are the env's; the infos add
    ``is_success`` (the patrollers won)."""

    metadata = {"name": "patrol_patrollers_v0", "render_modes": ["rgb_array"]}

    def __init__(self, adversary: str = "random", temperature: float = 0.02,
                 random_fraction: float = 0.0, **patrol_kwargs) -> None:
        if adversary not in ADVERSARIES:
            raise ConfigError(f"adversary: expected one of {ADVERSARIES}, got {adversary!r}")
        self.adversary = adversary
        self.temperature = validate.number("temperature", temperature, minimum=0.0, strict=True)
        self.random_fraction = validate.number("random_fraction", random_fraction, minimum=0.0,
                                               maximum=1.0)
        #: The adversary's weights over the targets (`respond`); None: not told yet.
        self.weights: np.ndarray | None = None
        #: The capture probabilities of the last `respond`.
        self.capture: np.ndarray | None = None
        self.env = patrol_env(**patrol_kwargs)
        self.possible_agents = [a for a in self.env.possible_agents if a != ADVERSARY]
        self.agents: list[str] = []
        self.render_mode = self.env.render_mode
        self.rng = _stream(None)
        self.target, self.start, self.clock = -1, -1, 0

    def observation_space(self, agent):
        return self.env.observation_space(agent)

    def action_space(self, agent):
        return self.env.action_space(agent)

    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is not None:
            self.rng = _stream(seed)
        observations, infos = self.env.reset(seed=seed, options=options)
        inner = self.env.unwrapped
        if self.adversary == "random":
            self.target = int(self.rng.integers(inner.n_vertices))
            self.start = int(self.rng.integers(inner.max_cycles - inner.attack_time + 1))
        elif self.adversary == "best_response":
            self.target, self.start = int(np.argmin(inner.capture_probabilities())), 0
        else:
            self.target, self.start = self._draw_target(inner.n_vertices), 0
        self.clock = 0
        self.agents = [a for a in self.env.agents if a != ADVERSARY]
        return self._ours(observations), self._infos(infos)

    def step(self, actions: dict):
        attack = 1 + self.target if self.clock == self.start else 0
        out = self.env.step({**actions, ADVERSARY: attack})
        self.clock += 1
        self.agents = [a for a in self.env.agents if a != ADVERSARY]
        observations, rewards, terminations, truncations, infos = out
        return (self._ours(observations), self._ours(rewards), self._ours(terminations),
                self._ours(truncations), self._infos(infos))

    def respond(self, probabilities_of) -> np.ndarray:
        """Best-respond to a patroller policy (module docstring; adversaries `RESPONDING`):
        ``probabilities_of`` maps (k, 2n) observations to (k, actions) action distributions
        (`baselines.patrolling.policies.action_probabilities` of the model). Updates the
        adversary's target weights; returns the per-target capture probabilities."""
        probabilities = policy_capture(self.env, probabilities_of)
        if self.adversary == "fictitious_play":
            if self.weights is None:
                self.weights = np.zeros(len(probabilities))
            self.weights[int(np.argmin(probabilities))] += 1.0
        else:
            self.weights = np.exp(-(probabilities - probabilities.min()) / self.temperature)
        self.capture = probabilities
        return probabilities

    def _draw_target(self, n: int) -> int:
        if self.weights is None or self.rng.random() < self.random_fraction:
            return int(self.rng.integers(n))
        cumulative = np.cumsum(self.weights)
        return int(min(np.searchsorted(cumulative, self.rng.random() * cumulative[-1],
                                       side="right"), n - 1))

    def render(self):
        return self.env.render()

    def close(self) -> None:
        self.env.close()

    def _ours(self, values: dict) -> dict:
        return {a: values[a] for a in self.possible_agents if a in values}

    def _infos(self, infos: dict) -> dict:
        return {a: {**info, "is_success": info["outcome"] in PATROLLER_WINS}
                for a, info in self._ours(infos).items()}


def policy_capture(env, probabilities_of) -> np.ndarray:
    """(n,) exact capture probability of an attack on each target of a Patrol-v0 ``env`` at step
    0, the patrollers starting on distinct uniform vertices and following the chain a policy
    induces alone at each vertex (``probabilities_of``: `PatrollersEnv.respond`) — what the
    evaluation's best response (strategy mode) minimises against learned patrollers."""
    from baselines.patrolling.policies import policy_chains, strategy_capture

    return strategy_capture(env, policy_chains(env, probabilities_of)[0])


def training_callbacks(config) -> list:
    """The SB3 callbacks a validated training configuration of Patrol-v0 needs: the
    `response_callback` when its patrollers learn against an adversary that responds to them
    (`RESPONDING`). (The policy sees the raw observations: the shared multi-robot policy trains
    without frame stacking and normalisation, `baselines.rl.train_config`.)"""
    if config.get("env") != PATROL_ID or config.get("role") != "patrollers" or \
            config["env_kwargs"].get("adversary") not in RESPONDING:
        return []
    return [response_callback()]


def response_callback():
    """An SB3 callback that, before every rollout, tells the `PatrollersEnv` under the training
    VecEnv the current policy (`PatrollersEnv.respond`) and keeps the least capture probability
    of each rollout in ``least`` (the policy's exact value against the best response)."""
    from stable_baselines3.common.callbacks import BaseCallback

    from baselines.patrolling.policies import action_probabilities

    class PolicyResponse(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.least: list[float] = []

        def _on_rollout_start(self) -> None:
            model = self.model
            probabilities = self.training_env.env_method(
                "respond", lambda obs: action_probabilities(model, obs), indices=[0])[0]
            self.least.append(float(probabilities.min()))
            self.logger.record("patrol/least_capture", self.least[-1])

        def _on_step(self) -> bool:
            return True

    return PolicyResponse()


def strategy_chain(name: str, graph) -> np.ndarray:
    """The dense transition matrix of strategy ``name`` (`STRATEGIES`) on ``graph``, over
    ``list(graph)``: MAECT's optimal walk (§4.4.1, `baselines.patrolling.maect.solve_maect`;
    solved once per graph and process, about 3 s for the 188 cells of patrol_15x15) or the
    uniform random walk."""
    from baselines.patrolling.markov import transition_matrix

    if name == "random_walk":
        return transition_matrix(graph)[0].toarray()
    key = (tuple(graph.nodes), tuple(graph.edges))
    if key not in _MAECT:
        from baselines.patrolling.maect import solve_maect

        _MAECT[key] = solve_maect(graph).transition.toarray()
    return _MAECT[key].copy()


_MAECT: dict[tuple, np.ndarray] = {}


def _check_strategies(strategies: object) -> tuple[str, ...]:
    if isinstance(strategies, str) or not isinstance(strategies, Sequence) or not strategies \
            or any(s not in STRATEGIES for s in strategies) \
            or len(set(strategies)) != len(strategies):
        raise ConfigError(f"strategies: expected a non-empty list of distinct names from "
                          f"{STRATEGIES}, got {strategies!r}")
    return tuple(strategies)


class AdversaryEnv(gym.Env):
    """The adversary of Patrol-v0 as a Gymnasium env, the patrollers following a Markov chain
    drawn per episode from ``strategies`` (module docstring). Spaces, observation and reward are
    the adversary's in the env; the info adds ``strategy`` (the chain's name),
    ``patroller_actions`` (the patrollers' moves of the step) and ``is_success`` (the attack
    succeeded)."""

    metadata = {"render_modes": ["rgb_array"]}

    def __init__(self, strategies: Sequence[str] = STRATEGIES, **patrol_kwargs) -> None:
        self.strategies = _check_strategies(strategies)
        self.env = patrol_env(**patrol_kwargs)
        inner = self.env.unwrapped
        self.patrollers = [a for a in self.env.possible_agents if a != ADVERSARY]
        self.observation_space = self.env.observation_space(ADVERSARY)
        self.action_space = self.env.action_space(ADVERSARY)
        self.render_mode = self.env.render_mode
        self.chains = [strategy_chain(name, inner.graph) for name in self.strategies]
        self._cumulative = [np.cumsum(chain, axis=1) for chain in self.chains]
        self.rng = _stream(None)
        self.index = 0

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if seed is not None:
            self.rng = _stream(seed)
        if options and "strategy" in options:
            raise ConfigError("options.strategy: the adversary's env draws the patrollers' "
                              f"strategy itself, from {self.strategies}")
        self.index = int(self.rng.integers(len(self.chains)))
        observations, infos = self.env.reset(
            seed=seed, options={**(options or {}), "strategy": self.chains[self.index]})
        return observations[ADVERSARY], self._info(infos[ADVERSARY], None)

    def step(self, action):
        inner = self.env.unwrapped
        moves = {}
        for agent, v in zip(self.patrollers, inner.positions(), strict=True):
            row = self._cumulative[self.index][v]
            u = int(np.searchsorted(row, self.rng.random() * row[-1], side="right"))
            moves[agent] = inner.action_towards(int(v), u)
        out = self.env.step({**moves, ADVERSARY: int(action)})
        observations, rewards, terminations, truncations, infos = out
        return (observations[ADVERSARY], float(rewards[ADVERSARY]), bool(terminations[ADVERSARY]),
                bool(truncations[ADVERSARY]), self._info(infos[ADVERSARY], moves))

    def render(self):
        return self.env.render()

    def close(self) -> None:
        self.env.close()

    def _info(self, info: dict, moves: dict | None) -> dict:
        actions = np.array([moves[a] for a in self.patrollers] if moves else [], dtype=np.int64)
        return {**info, "strategy": self.strategies[self.index], "patroller_actions": actions,
                "is_success": info["outcome"] == "success"}
