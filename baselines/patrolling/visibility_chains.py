"""Patrol chains of the visibility policies (Alam 2018, thesis ch. 4, §4.3.3-4.3.4): one Markov
chain per robot, the solution of the subset problem 4.5 for the robot's subset Q_i.

Distributed policies (§4.3.3): Q_i is robot i's cover-centre cells of Alg. 4.3, and the problem
is solved on the whole cell graph, so every robot may walk everywhere. Centralised policies
(§4.3.4): Q_i is the cover cells of robot i's region plus its contact cell; the thesis solves on
the whole graph (Table 4.5: n = 188 for every policy), which is the default here; with the
plan's ``confine_to_region`` the problem is solved on the region's induced subgraph and the
chain is embedded in the whole graph's node order, so the robot never leaves its region.

Every chain is a row-stochastic matrix over ``sorted(graph)``, the order of
`markov.transition_matrix` with ``nodes=sorted(graph)`` and of ``Patrol-v0``'s ``strategy``.
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np
import scipy.sparse as sp

from baselines.patrolling.maect import MaectResult
from baselines.patrolling.markov import transition_matrix
from baselines.patrolling.subset import DEFAULT_CYCLE_SHARE, solve_subset_maect
from baselines.patrolling.visibility import CellVisibility
from baselines.patrolling.visibility_policies import CentralisedPlan, distributed_subsets
from bounce_gym.errors import ConfigError

__all__ = ["VisibilityChain", "centralised_chains", "distributed_chains", "remote_target"]


@dataclass(frozen=True, eq=False)
class VisibilityChain:
    """One robot's patrol chain.

    Attributes:
        subset: Q_i, the vertices problem 4.5 favours, in the plan's order.
        vertices: the vertices the problem was solved on (all of the graph, or the region),
            ascending.
        transition: (n, n) row-stochastic CSR over ``sorted(graph)``. With a confined chain the
            rows outside the region (never reached from it) are the graph's simple random walk.
        result: the solution of problem 4.5 (its own node order is ``result.nodes``).
    """

    subset: tuple[int, ...]
    vertices: tuple[int, ...]
    transition: sp.csr_array
    result: MaectResult


def _check_graph(graph: object) -> list:
    if not isinstance(graph, nx.Graph):
        raise ConfigError(f"graph: expected a networkx graph, got {type(graph).__name__}")
    if graph.number_of_nodes() < 2 or not nx.is_connected(graph):
        raise ConfigError("graph: expected a connected graph with at least 2 vertices")
    return sorted(graph)


def _chain(graph: nx.Graph, nodes: list, subset: tuple[int, ...], vertices: list, h: float,
           tol: float) -> VisibilityChain:
    """Problem 4.5 on the subgraph induced by ``vertices``, embedded in ``nodes``' order."""
    whole = len(vertices) == len(nodes)
    sub = graph if whole else graph.subgraph(vertices)
    result = solve_subset_maect(sub, subset, h=h, tol=tol)
    inside, _ = transition_matrix(sub, result.weights, nodes=vertices)
    if whole:
        return VisibilityChain(subset, tuple(vertices), inside, result)
    walk = transition_matrix(graph, nodes=nodes)[0].tocoo()
    position = {v: k for k, v in enumerate(nodes)}
    at = np.array([position[v] for v in vertices])
    outside = ~np.isin(walk.row, at)
    inside = inside.tocoo()
    matrix = sp.csr_array((np.concatenate([walk.data[outside], inside.data]),
                           (np.concatenate([walk.row[outside], at[inside.row]]),
                            np.concatenate([walk.col[outside], at[inside.col]]))),
                          shape=walk.shape)
    return VisibilityChain(subset, tuple(vertices), matrix, result)


def distributed_chains(graph: nx.Graph, visibility: CellVisibility, m: int,
                       h: float = DEFAULT_CYCLE_SHARE, tol: float = 1e-10) -> list[VisibilityChain]:
    """The chains of the distributed visibility policies (thesis §4.3.3, Fig. 4.9): for robot i,
    problem 4.5 on the whole ``graph`` with Q_i = the cover-centre cells of Alg. 4.3's i-th
    cover (`distributed_subsets`).

    Args:
        graph: the `cell_graph` of the map ``visibility`` was computed on.
        visibility: the cell visibility at the robots' range l.
        m: the number of robots.
        h: the cycle's share of problem 4.5.
        tol: the solver's certified relative duality gap.

    Raises:
        ConfigError: a bad argument (named), or a cover of a single cell (problem 4.5 needs two).
    """
    nodes = _check_graph(graph)
    if nodes != list(range(len(nodes))) or not isinstance(visibility, CellVisibility) \
            or len(visibility) != len(nodes):
        raise ConfigError("graph: expected the cell_graph of the map the visibility was "
                          "computed on (vertices 0..n-1, one per free cell)")
    return [_chain(graph, nodes, tuple(subset), nodes, h, tol)
            for subset in distributed_subsets(visibility, m)]


def centralised_chains(graph: nx.Graph, plan: CentralisedPlan, h: float = DEFAULT_CYCLE_SHARE,
                       tol: float = 1e-10) -> list[VisibilityChain]:
    """The chains of the centralised visibility policies (thesis §4.3.4, Fig. 4.13): for robot
    i, problem 4.5 with Q_i = its cover cells and contact cell (``plan.subsets[i]``), on the
    whole ``graph``, or on robot i's region when ``plan.confine_to_region``.

    Args:
        graph: the `cell_graph` the plan was made on.
        plan: the `centralised_plan`.
        h: the cycle's share of problem 4.5.
        tol: the solver's certified relative duality gap.

    Raises:
        ConfigError: a bad argument (named), or a confined region that is not connected.
    """
    nodes = _check_graph(graph)
    if not isinstance(plan, CentralisedPlan):
        raise ConfigError(f"plan: expected a CentralisedPlan, got {type(plan).__name__}")
    if len(plan.sectors) != len(nodes):
        raise ConfigError(f"graph: the plan has {len(plan.sectors)} cells, the graph "
                          f"{len(nodes)} vertices")
    vertices = [list(region) for region in plan.regions] if plan.confine_to_region \
        else [nodes] * plan.m
    for i, region in enumerate(vertices):
        if not nx.is_connected(graph.subgraph(region)):
            raise ConfigError(f"plan: robot {i}'s region is not connected in the graph, so it "
                              f"cannot be patrolled confined to itself (make the plan with "
                              f"confine_to_region=False)")
    return [_chain(graph, nodes, tuple(subset), region, h, tol)
            for subset, region in zip(plan.subsets, vertices, strict=True)]


def remote_target(graph: nx.Graph, chains: list[VisibilityChain]) -> int:
    """The target cell of the vulnerability tables here (thesis §4.3.5 shows its targets only in
    Figs 4.14 and 4.16): the vertex farthest, in shortest-path ``length``, from every robot's
    subset vertices, ties to the lowest index. The chains favour their subsets, so this is a
    cell they reach late; it depends on the map and the subsets only, not on the solver."""
    nodes = _check_graph(graph)
    if not chains or not all(isinstance(c, VisibilityChain) for c in chains):
        raise ConfigError("chains: expected a non-empty list of VisibilityChain")
    sources = {v for c in chains for v in c.subset}
    distance = nx.multi_source_dijkstra_path_length(graph, sources, weight="length")
    return max(nodes, key=lambda v: (distance[v], -v))
