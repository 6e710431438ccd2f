"""Chains that patrol towards one vertex (Alam 2018, thesis §4.4.1, Alg. 4.1,
MAECTtowardsVertices).

For target i, every other vertex j contributes its k shortest simple paths to i (Yen's algorithm
on the Euclidean edge lengths): each directed edge a -> b on such a path adds 1 to ``M[a, b]``.
The target's own row gets 1 for each of its edges, once. The rows are normalised. Every vertex
leads to i, but the chain is generally reducible: vertices that no path to i passes through are
never reached again, and their hitting times are ``inf`` (`markov.hitting_times`).

The thesis gives no k; the default is 3 (docs/choices/patrolling.md, "Alg. 4.1: k = 3 shortest paths" and
"Alg. 4.1: the target's row").
Paths use the edge attribute ``length`` (1 where missing); networkx's Yen implementation
(`shortest_simple_paths`) orders equally long paths. Matrices are row-stochastic over the
vertices in ``sorted(graph)`` order.
"""

from __future__ import annotations

import itertools
from collections.abc import Hashable

import networkx as nx
import numpy as np

from bounce_gym.errors import ConfigError

__all__ = ["DEFAULT_PATHS", "towards_vertex_chain", "towards_vertex_chains"]

#: k of Alg. 4.1: shortest simple paths per vertex towards the target.
DEFAULT_PATHS = 3


def _check(graph: nx.Graph, k: int) -> list:
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ConfigError(f"k: expected an integer number of paths >= 1, got {k!r}")
    if graph.is_directed() or graph.number_of_nodes() < 2 or not nx.is_connected(graph):
        raise ConfigError("graph: expected an undirected connected graph with at least 2 "
                          "vertices")
    return sorted(graph)


def _chain(graph: nx.Graph, nodes: list, target: Hashable, k: int) -> np.ndarray:
    index = {v: a for a, v in enumerate(nodes)}
    counts = np.zeros((len(nodes), len(nodes)))
    i = index[target]
    for b in graph[target]:
        counts[i, index[b]] += 1.0
    for j in nodes:
        if j == target:
            continue
        for path in itertools.islice(nx.shortest_simple_paths(graph, j, target, weight="length"),
                                     k):
            steps = [index[v] for v in path]
            np.add.at(counts, (steps[:-1], steps[1:]), 1.0)
    return counts / counts.sum(axis=1, keepdims=True)


def towards_vertex_chain(graph: nx.Graph, target: Hashable, k: int = DEFAULT_PATHS) -> np.ndarray:
    """The chain of Alg. 4.1 towards ``target``: (n, n), row-stochastic, over ``sorted(graph)``.

    Args:
        graph: an undirected connected graph; edge attribute ``length`` (1 where missing).
        target: the vertex to patrol towards.
        k: shortest simple paths per vertex (>= 1; fewer where fewer exist).
    """
    nodes = _check(graph, k)
    if target not in graph:
        raise ConfigError(f"target: vertex {target!r} is not in the graph")
    return _chain(graph, nodes, target, k)


def towards_vertex_chains(graph: nx.Graph, k: int = DEFAULT_PATHS) -> list[np.ndarray]:
    """Alg. 4.1 for every target: one chain per vertex, in ``sorted(graph)`` order."""
    nodes = _check(graph, k)
    return [_chain(graph, nodes, t, k) for t in nodes]
