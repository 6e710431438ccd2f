"""The patrollers' Stackelberg mixture over a reduced strategy set (Alam 2018, thesis §4.4.2).

The thesis mixes n + 2 chains: MAECT over all vertices, MAECT over a subset (the "clique",
problem 4.5) and the n towards-vertex chains of Alg. 4.1, ranks the targets of each by its
preferred hitting time, builds Alg. 4.2's payoffs and solves the strong Stackelberg equilibrium.
On a map of 188 cells the n towards chains cost n Yen searches over every vertex each; this
module keeps the set the game is about — the chains that guard the targets the adversary would
pick — and takes the towards chains of a given list of targets only (the family passes the
targets of least capture probability under MAECT). Everything else is the thesis's: the same
payoffs (`game.payoff_matrices`) over all n targets, and the same equilibrium (`game.stackelberg`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import networkx as nx
import numpy as np

from baselines.patrolling.game import (
    payoff_matrices,
    preferred_all,
    preferred_subset,
    preferred_towards,
    stackelberg,
)
from baselines.patrolling.markov import hitting_times
from baselines.patrolling.subset import DEFAULT_CYCLE_SHARE, solve_subset_maect
from baselines.patrolling.towards import DEFAULT_PATHS, towards_vertex_chain
from bounce_gym.errors import ConfigError

__all__ = ["EquilibriumStrategy", "equilibrium_strategy"]


@dataclass(frozen=True, eq=False)
class EquilibriumStrategy:
    """The strategy set, its Stackelberg mixture and the game's prediction.

    Attributes:
        names: one name per strategy (``MAECT-all``, ``MAECT-subset``, ``towards <v>``).
        chains: (n, n) row-stochastic chains over ``sorted(graph)``, one per strategy.
        mixture: the leader's probabilities over the strategies (α).
        attack: the target vertex of the follower's response in the game of Alg. 4.2.
        value: the leader's expected payoff.
    """

    names: list[str]
    chains: list[np.ndarray]
    mixture: np.ndarray
    attack: int
    value: float


def equilibrium_strategy(graph: nx.Graph, maect_chain, subset: Sequence[int],
                         targets: Sequence[int], h: float = DEFAULT_CYCLE_SHARE,
                         k: int = DEFAULT_PATHS, tol: float = 1e-8) -> EquilibriumStrategy:
    """The Stackelberg mixture of MAECT over all vertices (``maect_chain``, over
    ``sorted(graph)``), MAECT over ``subset`` (problem 4.5 with share ``h``, solved to the
    relative tolerance ``tol``: on 188 vertices 1e-8 takes half the iterations of the solver's
    default 1e-12 for an objective within 1e-6 of it) and the Alg. 4.1 chains towards each of ``targets`` (``k``
    shortest paths).

    Raises:
        ConfigError: an empty or unknown target list, or a bad subset, ``h`` or ``k``.
    """
    nodes = sorted(graph)
    targets = [int(t) for t in targets]
    if not targets or any(t not in graph for t in targets) or len(set(targets)) != len(targets):
        raise ConfigError(f"targets: expected distinct vertices of the graph, got {targets!r}")
    all_chain = np.asarray(maect_chain.toarray() if hasattr(maect_chain, "toarray")
                           else maect_chain, dtype=np.float64)
    clique = solve_subset_maect(graph, list(subset), h=h, tol=tol)
    clique_chain = _ordered(clique.transition.toarray(), clique.nodes, nodes)
    index = {v: a for a, v in enumerate(nodes)}
    chains = [all_chain, clique_chain]
    preferred = [preferred_all(hitting_times(all_chain)),
                 preferred_subset(hitting_times(clique_chain, [index[v] for v in subset]),
                                  range(len(subset)))]
    for t in targets:
        chain = towards_vertex_chain(graph, t, k=k)
        chains.append(chain)
        column = hitting_times(chain, [index[t]])
        preferred.append(preferred_towards(column, 0))
    P, Q = payoff_matrices(np.array(preferred))
    result = stackelberg(P, Q)
    names = ["MAECT-all", "MAECT-subset", *(f"towards {t}" for t in targets)]
    return EquilibriumStrategy(names=names, chains=chains, mixture=result.mixture,
                               attack=int(nodes[result.attack]), value=result.value)


def _ordered(matrix: np.ndarray, order: Sequence, nodes: Sequence) -> np.ndarray:
    """``matrix`` over ``order`` re-indexed over ``nodes``."""
    at = [list(order).index(v) for v in nodes]
    return matrix[np.ix_(at, at)]
