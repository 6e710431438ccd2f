"""Stochastic multi-robot patrolling (Alam 2018, thesis ch. 4): the cell graph of a World, random
walks with their hitting and commute times, MAECT strategies over all vertices and over a subset
(`subset`, problem 4.5), and the patrolling game (Alg. 4.2 payoffs, strong Stackelberg
equilibrium), limited-range visibility covers (Alg. 4.3), detection times with the generalised
lambda distribution, and perimeter-patrol baselines (`visibility`, `vulnerability`, `perimeter`).
Every planner takes a networkx graph and returns plain data (edge -> weight, a transition matrix
with its node order)."""

from baselines.patrolling.game import (
    StackelbergResult,
    payoff_matrices,
    preferred_all,
    preferred_subset,
    preferred_towards,
    stackelberg,
)
from baselines.patrolling.graphs import DEFAULT_CORNER_RULE, cell_graph
from baselines.patrolling.maect import (
    SOLVERS,
    MaectResult,
    incidence,
    laplacian,
    maect_objective,
    project_simplex,
    solve_maect,
)
from baselines.patrolling.markov import (
    commute_times,
    hitting_times,
    mean_commute_time,
    transition_matrix,
)
from baselines.patrolling.subset import (
    DEFAULT_CYCLE_SHARE,
    cycle_order,
    project_subset_simplex,
    solve_subset_maect,
    subset_cycle_edges,
)

__all__ = ["DEFAULT_CORNER_RULE", "DEFAULT_CYCLE_SHARE", "SOLVERS", "MaectResult",
           "StackelbergResult", "cell_graph", "commute_times", "cycle_order", "hitting_times",
           "incidence", "laplacian", "maect_objective", "mean_commute_time", "payoff_matrices",
           "preferred_all", "preferred_subset", "preferred_towards", "project_simplex",
           "project_subset_simplex", "solve_maect", "solve_subset_maect", "stackelberg",
           "subset_cycle_edges", "transition_matrix"]
