"""Reference policies for the patrol environment ``bounce_gym/Patrol-v0`` (Alam 2018, thesis
ch. 4): Markov-chain patrollers, perimeter patrols, the Stackelberg best-responding adversary,
and the joint policy the experiment runner runs (one patroller policy with one adversary policy).

Every patroller policy says what a Stackelberg adversary is told about it (`told`: a mixture of
row-stochastic chains over the graph's node order, thesis §4.4.2): for `MarkovPatrolPolicy` its
chains and their weights, exactly; for `PerimeterPatrolPolicy` the vertex chain its walk induces
(`induced_chain`), which is only an approximation, since the walk remembers its direction; for
trained patrollers (`LearnedPatrollers`) the chain their policy induces alone at each vertex.
The best response of `BestResponseAdversary` is exact against Markov chains and their mixtures
only. Each also ``announced``: the one chain the env is told (its ``strategy``, what a trained
adversary observes). docs/choices/patrolling.md, "The patrol evaluation", gives the reasons.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import networkx as nx
import numpy as np
import scipy.sparse as sp

from baselines.patrolling.perimeter import PRESETS
from baselines.policy import MultiPolicy, episode_rng
from bounce_gym import validate
from bounce_gym.envs.patrol import capture
from bounce_gym.errors import ConfigError

__all__ = ["ADVERSARY", "BestResponseAdversary", "JointPatrolPolicy", "LearnedAdversary",
           "LearnedPatrollers", "MarkovPatrolPolicy", "PerimeterPatrolPolicy", "induced_chain",
           "patrollers_of", "perimeter_walk", "policy_chains", "strategy_capture",
           "sub_seed"]

#: The adversary's agent name in ``Patrol-v0``.
ADVERSARY = "adversary"
#: The best-response modes: what the adversary knows when it picks its target.
MODES = ("strategy", "positions")


def patrollers_of(agents: Sequence[str]) -> list[str]:
    """The patroller agents of ``agents`` (every agent but the adversary), in order."""
    return [a for a in agents if a != ADVERSARY]


def sub_seed(seed: int, stream: int) -> int:
    """An independent seed for random stream ``stream`` of an episode seeded ``seed``."""
    return int(np.random.SeedSequence([int(seed), int(stream)]).generate_state(1)[0])


def _dense_chain(field: str, chain: object, n: int | None = None) -> np.ndarray:
    matrix = np.asarray(chain.toarray() if sp.issparse(chain) else chain, dtype=np.float64)
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1] or matrix.shape[0] == 0:
        raise ConfigError(f"{field}: expected a square transition matrix, got shape "
                          f"{matrix.shape}")
    if n is not None and matrix.shape[0] != n:
        raise ConfigError(f"{field}: expected {n} x {n} like the other chains, got "
                          f"{matrix.shape}")
    if (matrix < 0).any() or not np.allclose(matrix.sum(axis=1), 1.0, atol=1e-9):
        raise ConfigError(f"{field}: rows must be probabilities summing to 1")
    return matrix


class MarkovPatrolPolicy(MultiPolicy):
    """Patrollers that follow a Markov chain (thesis §4.4): at every episode one chain is drawn
    from the mixture ``weights`` (the Stackelberg α; default: equal weights), then every step
    each patroller samples its next vertex from its vertex's row of that chain and moves there
    with ``env.action_towards``. The adversary's actions are not its business.

    The random stream restarts at every episode from ``seed`` if given, else from the episode's
    seed (`baselines.policy.episode_rng`), so episodes are independent and reproducible.
    """

    def __init__(self, chains: Sequence[object], weights: Sequence[float] | None = None,
                 name: str = "markov", seed: int | None = None) -> None:
        if isinstance(chains, np.ndarray) and chains.ndim == 2 or sp.issparse(chains):
            chains = [chains]
        chains = list(chains)
        if not chains:
            raise ConfigError("chains: expected at least one transition matrix")
        first = _dense_chain("chains[0]", chains[0])
        self.chains = [first] + [_dense_chain(f"chains[{i}]", c, first.shape[0])
                                 for i, c in enumerate(chains[1:], start=1)]
        if weights is None:
            weights = np.full(len(self.chains), 1.0 / len(self.chains))
        weights = validate.numbers("weights", weights).ravel()
        if len(weights) != len(self.chains) or (weights < 0).any() or weights.sum() <= 0:
            raise ConfigError(f"weights: expected {len(self.chains)} non-negative numbers with a "
                              f"positive sum, got {weights.tolist()}")
        self.weights = weights / weights.sum()
        self.name = name
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.cumulative = [np.cumsum(c, axis=1) for c in self.chains]
        self.chain = 0
        self._mean: np.ndarray | None = None

    def told(self, env) -> list[tuple[float, np.ndarray]]:
        """What a Stackelberg adversary knows: every chain of positive weight, with its weight."""
        return [(float(w), c) for w, c in zip(self.weights, self.chains, strict=True) if w > 0]

    def announced(self, env) -> np.ndarray:
        """The one chain the env is told (``strategy``, what an RL adversary observes): the
        chain itself, or for a mixture its weighted mean, the mixture's one-step law."""
        if self._mean is None:
            self._mean = sum(w * c for w, c in self.told(env))
        return self._mean

    def start_options(self, env, seed: int) -> None:
        self.rng = episode_rng(self.seed, seed)
        return None

    def reset(self, env) -> None:
        self.env = env.unwrapped
        self.chain = int(self.rng.choice(len(self.chains), p=self.weights))

    def act(self, observations, infos):
        cumulative = self.cumulative[self.chain]
        out = {}
        for agent in patrollers_of(observations):
            v = int(infos[agent]["vertex"])
            row = cumulative[v]
            u = int(min(np.searchsorted(row, self.rng.random() * row[-1], side="right"),
                        len(row) - 1))
            out[agent] = self.env.action_towards(v, u)
        return out


def perimeter_walk(graph: nx.Graph) -> list:
    """A closed walk through every vertex of a connected ``graph`` along its edges: networkx's
    Christofides tour for the edge ``length`` (``traveling_salesman_problem(cycle=True)``, a
    3/2-approximation of the shortest such walk), without its repeated last vertex."""
    if graph.number_of_nodes() < 2 or not nx.is_connected(graph):
        raise ConfigError("graph: a perimeter walk needs a connected graph with at least 2 "
                          "vertices")
    tour = nx.approximation.traveling_salesman_problem(graph, weight="length", cycle=True)
    walk = [v for k, v in enumerate(tour[:-1]) if k == 0 or v != tour[k - 1]]
    return walk


def induced_chain(walk: Sequence[int], n: int) -> np.ndarray:
    """The vertex chain a perimeter walk induces, what its adversary is told: a robot at an
    occurrence of v on the walk, heading either way with equal probability, moves to the next or
    the previous vertex of the walk with probability 1/2 each — for every continue probability
    p, since both directions are equally likely — averaged over v's occurrences."""
    walk = [int(v) for v in walk]
    P = np.zeros((n, n))
    length = len(walk)
    for k, v in enumerate(walk):
        P[v, walk[(k + 1) % length]] += 0.5
        P[v, walk[k - 1]] += 0.5
    visits = P.sum(axis=1)
    if (visits == 0).any():
        raise ConfigError(f"walk: vertex {int(np.flatnonzero(visits == 0)[0])} is not on it")
    return P / visits[:, None]


class PerimeterPatrolPolicy(MultiPolicy):
    """Perimeter patrol after Agmon, Kraus & Kaminka (ICRA 2008), on a closed walk through every
    vertex (`perimeter_walk`) standing in for the cycle C_n of `baselines.patrolling.perimeter`:
    an **approximation** of the thesis's BMP/DCP/DNCP (Fig. 4.4, Table 4.1), which it never
    defines.

    The m patrollers start equally spaced along the walk (``reset(options={"start": ...})``) at a
    random offset, all heading one random way; at every step the team continues one vertex in its
    direction with probability ``p``, or every patroller turns around and moves one vertex back
    (the env has no action to stay, so a turn costs no extra step, unlike τ of `perimeter`).
    Moving together keeps the spacing. Presets (`perimeter.PRESETS`): ``deterministic`` (p = 1)
    and ``random_walk`` (p = 1/2). The adversary is told `induced_chain` of the walk.
    """

    def __init__(self, p: float | str, seed: int | None = None) -> None:
        if isinstance(p, str):
            if p not in PRESETS:
                raise ConfigError(f"p: expected a number in [0, 1] or one of {sorted(PRESETS)}, "
                                  f"got {p!r}")
            self.name = f"perimeter {p}"
            p = PRESETS[p]
        else:
            self.name = f"perimeter p={p:g}"
        self.p = validate.number("p", p, minimum=0.0)
        if self.p > 1:
            raise ConfigError(f"p: expected a number in [0, 1], got {p!r}")
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self._walks: dict[int, tuple[list, np.ndarray]] = {}
        self.index = np.zeros(0, dtype=np.int64)
        self.direction = 1

    def walk(self, env) -> list:
        """The env's perimeter walk (computed once per env)."""
        return self._walk_and_chain(env)[0]

    def _walk_and_chain(self, env) -> tuple[list, np.ndarray]:
        inner = env.unwrapped
        if id(inner) not in self._walks:
            walk = perimeter_walk(inner.graph)
            self._walks[id(inner)] = (walk, induced_chain(walk, inner.n_vertices))
        return self._walks[id(inner)]

    def told(self, env) -> list[tuple[float, np.ndarray]]:
        return [(1.0, self._walk_and_chain(env)[1])]

    def announced(self, env) -> np.ndarray:
        return self._walk_and_chain(env)[1]

    def start_options(self, env, seed: int) -> dict:
        self.rng = episode_rng(self.seed, seed)
        walk = self.walk(env)
        m = len(patrollers_of(env.possible_agents))
        length = len(walk)
        offset = int(self.rng.integers(length))
        self.index = (offset + np.round(np.arange(m) * length / m).astype(np.int64)) % length
        self.direction = int(self.rng.choice([-1, 1]))
        return {"start": [int(walk[k]) for k in self.index]}

    def reset(self, env) -> None:
        self.env = env.unwrapped
        self.current = self.walk(env)

    def act(self, observations, infos):
        if self.rng.random() >= self.p:
            self.direction = -self.direction
        walk, length = self.current, len(self.current)
        out = {}
        for i, agent in enumerate(patrollers_of(self.env.possible_agents)):
            here = walk[self.index[i]]
            self.index[i] = (self.index[i] + self.direction) % length
            if agent in observations:
                out[agent] = self.env.action_towards(here, walk[self.index[i]])
        return out


class BestResponseAdversary(MultiPolicy):
    """The Stackelberg follower (thesis §4.4.2) against the capture rule of §4.3.5: at step 0 it
    attacks the target of least capture probability, ties to the lowest index, and then waits
    for the attack's end.

    It acts on what it is told (``told``, a mixture of chains, set by `JointPatrolPolicy`;
    default: the env's ``strategy``) and computes what `PatrolEnv.capture_probabilities` computes
    (`bounce_gym.envs.patrol.capture`), for a mixture ``sum_k α_k p_k``. ``mode="strategy"``: it
    does not know where the patrollers stand, only that they start on distinct uniformly random
    vertices (the env's placement); ``mode="positions"``: it also sees where they stand at step
    0. The best response is exact against Markov chains and their mixtures; against a patrol
    that is not a Markov chain on the vertices it is a best response to what it is told.
    """

    def __init__(self, mode: str = "strategy") -> None:
        if mode not in MODES:
            raise ConfigError(f"mode: expected one of {MODES}, got {mode!r}")
        self.mode = mode
        self.name = f"best response ({mode})"
        self.told: list[tuple[float, np.ndarray]] | None = None
        self.target: int | None = None
        self.predicted: float | None = None
        self._survival: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _survival_of(self, inner, chain: np.ndarray) -> np.ndarray:
        key = id(chain)
        if key not in self._survival or self._survival[key][0] is not chain:
            self._survival[key] = (chain, capture.survival(chain, inner.board.seen,
                                                           inner.attack_time))
        return self._survival[key][1]

    def capture_probabilities(self, env) -> np.ndarray:
        """The per-target capture probabilities of an attack started now, as told."""
        inner = env.unwrapped
        told = self.told if self.told is not None else [(1.0, inner.strategy)]
        total = np.zeros(inner.n_vertices)
        for weight, chain in told:
            S = self._survival_of(inner, chain)
            total += weight * (capture.capture_from(S, inner.positions())
                               if self.mode == "positions"
                               else capture.capture_from_distinct_uniform(S, inner.n_patrollers))
        return total

    def reset(self, env) -> None:
        probabilities = self.capture_probabilities(env)
        self.target = int(np.argmin(probabilities))  # argmin: the lowest index of the ties
        self.predicted = float(probabilities[self.target])
        self.started = False

    def act(self, observations, infos):
        if ADVERSARY not in observations:
            return {}
        action = 0 if self.started else 1 + self.target
        self.started = True
        return {ADVERSARY: action}


class JointPatrolPolicy(MultiPolicy):
    """One patroller policy and one adversary policy as the one policy the runner runs.

    Per episode: the patrollers' reset options (e.g. their start vertices) with the strategy the
    env tells the adversary (``{"strategy": P}``, the patrollers' ``announced`` chain — what an
    RL adversary observes; a `BestResponseAdversary` is given what the patrollers' ``told``
    says, e.g. a mixture itself). The two policies draw from independent random streams of the
    episode's seed (`sub_seed`).
    """

    def __init__(self, patrollers: MultiPolicy, adversary: MultiPolicy) -> None:
        self.patrollers, self.adversary = patrollers, adversary
        self.name = f"{patrollers.name} vs {adversary.name}"

    def start_options(self, env, seed: int) -> dict:
        options = dict(self.patrollers.start_options(env, sub_seed(seed, 0)) or {})
        options.update(self.adversary.start_options(env, sub_seed(seed, 1)) or {})
        if isinstance(self.adversary, BestResponseAdversary):
            self.adversary.told = self.patrollers.told(env)
        options["strategy"] = self.patrollers.announced(env)
        return options

    def reset(self, env) -> None:
        self.patrollers.reset(env)
        self.adversary.reset(env)

    @property
    def predicted_capture(self) -> float | None:
        """The capture probability the best-responding adversary expects (``None`` for others)."""
        return getattr(self.adversary, "predicted", None)

    def act(self, observations, infos):
        mine = patrollers_of(observations)
        theirs = [a for a in observations if a == ADVERSARY]
        return {**self.patrollers.act({a: observations[a] for a in mine},
                                      {a: infos[a] for a in mine}),
                **self.adversary.act({a: observations[a] for a in theirs},
                                     {a: infos[a] for a in theirs})}


class LearnedPatrollers(MultiPolicy):
    """Patrollers of a trained shared model (`baselines.rl.policies.PatrollerSB3Policy`, its
    actions sampled) with what a Stackelberg adversary is told about them.

    ``told``: the chain the policy induces at each vertex — its action distribution for the
    observation of a patroller alone at v (one-hot v, no other patroller in sight), a move along
    the edge in each direction, a direction without an edge a stay at v (the env's no-op). The
    patrol is memoryless, but it also reacts to the patrollers it sees, so the best response to
    this chain is exact only while they stay out of each other's sight. ``announced`` (the env's
    ``strategy``, which must move along an edge every step): the same chain conditioned on
    moving.
    """

    def __init__(self, policy: MultiPolicy) -> None:
        self.policy = policy
        self.name = policy.name
        self._chains: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _induced(self, env) -> tuple[np.ndarray, np.ndarray]:
        inner = env.unwrapped
        if id(inner) not in self._chains:
            self._chains[id(inner)] = policy_chains(
                inner, lambda alone: action_probabilities(self.policy.model, alone))
        return self._chains[id(inner)]

    def told(self, env) -> list[tuple[float, np.ndarray]]:
        return [(1.0, self._induced(env)[0])]

    def announced(self, env) -> np.ndarray:
        return self._induced(env)[1]

    def start_options(self, env, seed: int):
        return self.policy.start_options(env, seed)

    def reset(self, env) -> None:
        self.policy.reset(env)

    def act(self, observations, infos):
        return self.policy.act(observations, infos)


def policy_chains(env, probabilities_of: Callable[[np.ndarray], np.ndarray]
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The chains a shared patroller policy induces on a Patrol-v0 env (`LearnedPatrollers`):
    ``(told, moving)``, both (n, n) over the graph's node order. ``probabilities_of`` maps
    (k, 2n) observations to (k, actions) action distributions (`action_probabilities` of a
    model); it is asked about the n observations of a patroller alone at each vertex (one-hot v,
    no other patroller in sight). ``told``: a move along an edge in each direction, a direction
    without an edge a stay at v (the env's no-op). ``moving``: ``told`` conditioned on moving (a
    vertex where the policy never moves: the uniform walk, the env's default strategy)."""
    inner = env.unwrapped
    n = inner.n_vertices
    alone = np.zeros((n, 2 * n), dtype=np.float32)
    alone[np.arange(n), np.arange(n)] = 1.0
    probs = np.asarray(probabilities_of(alone), dtype=np.float64)
    neighbours = inner.neighbour_table
    legal = neighbours >= 0
    told = np.zeros((n, n))
    rows, dirs = np.nonzero(legal)
    np.add.at(told, (rows, neighbours[rows, dirs]), probs[rows, dirs])
    told[np.arange(n), np.arange(n)] += np.where(legal, 0.0, probs).sum(axis=1)
    moving = told.copy()
    np.fill_diagonal(moving, 0.0)
    mass = moving.sum(axis=1, keepdims=True)
    moving = np.where(mass > 0, moving / np.where(mass > 0, mass, 1.0),
                      inner.board.uniform_walk())
    return told, moving


def strategy_capture(env, chain: np.ndarray) -> np.ndarray:
    """(n,) capture probability of an attack on each target started at step 0 against m
    patrollers following ``chain`` from distinct uniformly random vertices (the env's
    placement): what `BestResponseAdversary` in ``"strategy"`` mode minimises over targets."""
    inner = env.unwrapped
    S = capture.survival(chain, inner.board.seen, inner.attack_time)
    return capture.capture_from_distinct_uniform(S, inner.n_patrollers)


def action_probabilities(model, observations: np.ndarray) -> np.ndarray:
    """(k, actions): a Stable-Baselines3 model's action distribution for each observation."""
    import torch

    batch, _ = model.policy.obs_to_tensor(observations)
    with torch.no_grad():
        return model.policy.get_distribution(batch).distribution.probs.numpy().astype(np.float64)


class LearnedAdversary(MultiPolicy):
    """An adversary of a trained model (`baselines.rl.policies.AdversarySB3Policy`: its action
    on its own observation, sampled from the stream of the seed it is given, or greedy)."""

    def __init__(self, policy) -> None:
        self.policy = policy
        self.name = policy.name

    def start_options(self, env, seed: int):
        return self.policy.start_options(env, seed)

    def reset(self, env) -> None:
        self.policy.reset(env)

    def act(self, observations, infos):
        if ADVERSARY not in observations:
            return {}
        return {ADVERSARY: int(self.policy.act(observations[ADVERSARY], infos[ADVERSARY]))}
