"""The patroller's n + 2 pure strategies of the patrolling game and the game end to end (Alam
2018, thesis §4.4.2, Tables 4.2 and 4.3).

The strategies are, in the order of Table 4.2: the n chains towards each vertex (Alg. 4.1), the
MAECT chain over all vertices (problem 4.4) and the MAECT chain of the subset Q (the "clique",
problem 4.5). Each strategy ranks the vertices by its preferred hitting time h̄
(`game.preferred_towards`, `game.preferred_all`, `game.preferred_subset`), Alg. 4.2 turns the
ranks into the payoffs (P, Q) and the strong Stackelberg equilibrium mixes the strategies.
Everything is plain data over the vertices in ``sorted(graph)`` order.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from dataclasses import dataclass

import networkx as nx
import numpy as np

from baselines.patrolling.game import (
    StackelbergResult,
    payoff_matrices,
    preferred_all,
    preferred_subset,
    preferred_towards,
    stackelberg,
)
from baselines.patrolling.maect import solve_maect
from baselines.patrolling.markov import hitting_times, transition_matrix
from baselines.patrolling.subset import DEFAULT_CYCLE_SHARE, solve_subset_maect
from baselines.patrolling.towards import DEFAULT_PATHS, towards_vertex_chains

__all__ = ["PatrolGame", "StrategySet", "patrol_game", "strategy_set"]


@dataclass(frozen=True)
class StrategySet:
    """The n + 2 Markov chains of thesis §4.4.2 and their preferred hitting times."""

    names: list[str]  # "towards <v>" for each vertex, then "MAECT", "Clique"
    chains: list[np.ndarray]  # (n, n) row-stochastic, over `nodes`
    preferred: np.ndarray  # (n + 2, n): h̄ of every strategy (rows) for every vertex
    nodes: list  # sorted(graph)
    subset: list  # the clique Q, as vertices


@dataclass(frozen=True)
class PatrolGame:
    """The strategies, Alg. 4.2's payoff matrices and the strong Stackelberg equilibrium."""

    strategies: StrategySet
    P: np.ndarray  # (n + 2, n) patroller payoffs
    Q: np.ndarray  # (n + 2, n) adversary payoffs
    equilibrium: StackelbergResult


def strategy_set(graph: nx.Graph, subset: Sequence[Hashable], h: float = DEFAULT_CYCLE_SHARE,
                 k: int = DEFAULT_PATHS, solver: str = "gradient") -> StrategySet:
    """The towards-vertex chains (Alg. 4.1, ``k`` paths), MAECT over all vertices and MAECT over
    ``subset`` (share ``h``), with their preferred hitting times.

    Args:
        graph: an undirected connected graph; edge attribute ``length`` (1 where missing).
        subset: the clique Q of problem 4.5, at least two distinct vertices.
        h: the share of the weight on ShortestCycle(Q), in (0, 1].
        k: shortest simple paths per vertex in Alg. 4.1 (>= 1).
        solver: the MAECT solver, ``"gradient"`` or ``"cvxpy"``.
    """
    nodes = sorted(graph)
    subset = list(subset)
    clique = solve_subset_maect(graph, subset, h=h, solver=solver)  # checks subset and h
    towards = towards_vertex_chains(graph, k=k)
    everyone = solve_maect(graph, solver=solver)
    maect_chains = [transition_matrix(graph, result.weights, nodes)[0].toarray()
                    for result in (everyone, clique)]
    columns = [nodes.index(v) for v in subset]
    preferred = [preferred_towards(hitting_times(M, targets=[i]), 0)
                 for i, M in enumerate(towards)]
    preferred.append(preferred_all(hitting_times(maect_chains[0])))
    preferred.append(preferred_subset(hitting_times(maect_chains[1], targets=columns),
                                      range(len(columns))))
    return StrategySet(names=[f"towards {v}" for v in nodes] + ["MAECT", "Clique"],
                       chains=[*towards, *maect_chains], preferred=np.array(preferred),
                       nodes=nodes, subset=subset)


def patrol_game(graph: nx.Graph, subset: Sequence[Hashable], h: float = DEFAULT_CYCLE_SHARE,
                k: int = DEFAULT_PATHS, solver: str = "gradient",
                method: str = "lp") -> PatrolGame:
    """Thesis §4.4.2 end to end: `strategy_set`, Alg. 4.2 payoffs and the equilibrium
    (`game.stackelberg` with ``method`` ``"lp"`` or ``"dobss"``)."""
    strategies = strategy_set(graph, subset, h=h, k=k, solver=solver)
    P, Q = payoff_matrices(strategies.preferred)
    return PatrolGame(strategies=strategies, P=P, Q=Q,
                      equilibrium=stackelberg(P, Q, method=method))
