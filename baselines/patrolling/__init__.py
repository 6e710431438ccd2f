"""Stochastic multi-robot patrolling (Alam 2018, thesis ch. 4): the cell graph of a World, random
walks with their hitting and commute times, MAECT strategies over all vertices and over a subset
(`subset`, problem 4.5), the chains towards one vertex (`towards`, Alg. 4.1), the patrolling game
(Alg. 4.2 payoffs, strong Stackelberg equilibrium by LPs or DOBSS) and its n + 2 strategies end
to end (`strategies`), the visibility policies' subsets and chains (`visibility_policies`,
`visibility_chains`, §4.3.3-4.3.4), limited-range visibility covers (Alg. 4.3), detection times
with the generalised lambda distribution, and perimeter-patrol baselines (`visibility`, `vulnerability`,
`perimeter`). Every planner takes a networkx graph and returns plain data (edge -> weight, a
transition matrix with its node order)."""

from baselines.patrolling.game import (
    STACKELBERG_METHODS,
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
from baselines.patrolling.strategies import PatrolGame, StrategySet, patrol_game, strategy_set
from baselines.patrolling.subset import (
    DEFAULT_CYCLE_SHARE,
    cycle_order,
    project_subset_simplex,
    solve_subset_maect,
    subset_cycle_edges,
)
from baselines.patrolling.towards import (
    DEFAULT_PATHS,
    towards_vertex_chain,
    towards_vertex_chains,
)
from baselines.patrolling.visibility_chains import (
    VisibilityChain,
    centralised_chains,
    distributed_chains,
    remote_target,
)
from baselines.patrolling.visibility_policies import (
    CentralisedPlan,
    centralised_plan,
    centralised_starts,
    distributed_subsets,
)

__all__ = ["DEFAULT_CORNER_RULE", "DEFAULT_CYCLE_SHARE", "DEFAULT_PATHS", "SOLVERS",
           "STACKELBERG_METHODS", "MaectResult", "PatrolGame", "StackelbergResult", "StrategySet",
           "cell_graph", "commute_times", "cycle_order", "hitting_times", "incidence", "laplacian",
           "maect_objective", "mean_commute_time", "patrol_game", "payoff_matrices",
           "preferred_all", "preferred_subset", "preferred_towards", "project_simplex",
           "project_subset_simplex", "solve_maect", "solve_subset_maect", "stackelberg",
           "strategy_set", "subset_cycle_edges", "towards_vertex_chain", "towards_vertex_chains",
           "transition_matrix", "CentralisedPlan", "VisibilityChain", "centralised_chains",
           "centralised_plan", "centralised_starts", "distributed_chains", "distributed_subsets",
           "remote_target"]
