"""The equilibrium mixture over a reduced strategy set (baselines.patrolling.equilibrium)."""

import networkx as nx
import numpy as np
import pytest

from baselines.patrolling import solve_maect
from baselines.patrolling.equilibrium import equilibrium_strategy
from baselines.patrolling.strategies import patrol_game
from bounce_gym.errors import ConfigError


@pytest.fixture(scope="module")
def grid() -> nx.Graph:
    graph = nx.convert_node_labels_to_integers(nx.grid_2d_graph(4, 4))
    nx.set_edge_attributes(graph, 1.0, "length")
    return graph


def test_with_every_target_it_is_the_games_equilibrium(grid):
    """Towards chains for all 16 targets: the n + 2 strategies of §4.4.2, in another order,
    so the equilibrium value and the adversary's response are those of `patrol_game`."""
    subset = [0, 3, 15, 12, 5]
    game = patrol_game(grid, subset, k=2)
    maect = solve_maect(grid).transition
    mine = equilibrium_strategy(grid, maect, subset, range(16), k=2)
    assert mine.names[:3] == ["MAECT-all", "MAECT-subset", "towards 0"]
    assert len(mine.chains) == 18
    assert mine.value == pytest.approx(game.equilibrium.value, abs=1e-6)
    assert mine.attack == game.equilibrium.attack
    assert mine.mixture.sum() == pytest.approx(1.0) and (mine.mixture >= 0).all()
    for chain in mine.chains:
        np.testing.assert_allclose(chain.sum(axis=1), 1.0, rtol=1e-12)


def test_a_reduced_set_mixes_its_own_strategies(grid):
    mine = equilibrium_strategy(grid, solve_maect(grid).transition, [0, 15], [5, 10])
    assert mine.names == ["MAECT-all", "MAECT-subset", "towards 5", "towards 10"]
    assert mine.mixture.shape == (4,)
    with pytest.raises(ConfigError, match="targets: expected distinct vertices"):
        equilibrium_strategy(grid, solve_maect(grid).transition, [0, 15], [5, 5])
    with pytest.raises(ConfigError, match="targets: expected distinct vertices"):
        equilibrium_strategy(grid, solve_maect(grid).transition, [0, 15], [])
