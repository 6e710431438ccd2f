"""The n + 2 strategies of the patrolling game end to end (Alam 2018, thesis §4.4.2): Table 4.2's
MAECT and Clique rows from our own chains on the small graph of thesis §4.5.2."""

import networkx as nx
import numpy as np
import pytest

from baselines.patrolling.strategies import patrol_game, strategy_set
from bounce_gym.errors import ConfigError

P_VALUES = [8, 3.5625, 1.59375, 0.734375, 0.3671875, 0.21484375, 0.154296875, 0.1318359375]
Q_VALUES = [1, 1.0625, 0.84375, 0.609375, 0.4296875, 0.30859375, 0.232421875, 0.1865234375]


@pytest.fixture(scope="module")
def small_game(cvx_small_graph):
    return patrol_game(cvx_small_graph, [2, 5, 8])


def test_maect_and_clique_rows_of_table_4_2(small_game, table_4_2):
    P_table, Q_table = table_4_2
    assert small_game.strategies.names[-2:] == ["MAECT", "Clique"]
    np.testing.assert_allclose(small_game.P[-2:], P_table[-2:], atol=5e-5)
    np.testing.assert_allclose(small_game.Q[-2:], Q_table[-2:], atol=5e-5)


def test_the_clique_row_holds_for_h_075(cvx_small_graph, table_4_2):
    P_table, _ = table_4_2
    game = patrol_game(cvx_small_graph, [2, 5, 8], h=0.75)
    np.testing.assert_allclose(game.P[-1], P_table[-1], atol=5e-5)


def test_every_row_is_a_ranking(small_game):
    strategies = small_game.strategies
    assert strategies.nodes == list(range(1, 9)) and strategies.subset == [2, 5, 8]
    assert strategies.names[:8] == [f"towards {v}" for v in range(1, 9)]
    assert len(strategies.chains) == small_game.P.shape[0] == 10
    for P_row, Q_row in zip(small_game.P, small_game.Q, strict=True):
        np.testing.assert_allclose(sorted(P_row, reverse=True), P_VALUES)
        np.testing.assert_allclose(Q_row[np.argsort(-P_row)], Q_VALUES)
    # the chain towards v_i ranks v_i first: it is the only vertex reached at once
    np.testing.assert_array_equal(np.argmax(small_game.P[:8], axis=1), np.arange(8))
    for M in strategies.chains:
        np.testing.assert_allclose(M.sum(axis=1), 1.0, rtol=1e-12)


def test_equilibrium_of_our_own_game(small_game):
    equilibrium = small_game.equilibrium
    # some strategy ranks the attacked vertex first: the leader gets the top payoff
    assert equilibrium.value == pytest.approx(8.0, abs=1e-6)
    assert equilibrium.mixture.sum() == pytest.approx(1.0)
    follower = equilibrium.mixture @ small_game.Q
    assert follower[equilibrium.attack] >= follower.max() - 1e-9


def test_a_grid_game_with_a_five_vertex_clique():
    grid = nx.convert_node_labels_to_integers(nx.grid_2d_graph(4, 4))
    nx.set_edge_attributes(grid, 1.0, "length")
    game = patrol_game(grid, [0, 3, 15, 12, 5], k=2, method="dobss")
    assert game.P.shape == (18, 16)
    assert np.isfinite(game.strategies.preferred).all()
    lp = patrol_game(grid, [0, 3, 15, 12, 5], k=2)
    assert game.equilibrium.value == pytest.approx(lp.equilibrium.value, abs=1e-7)


def test_strategy_set_passes_bad_arguments_on(cvx_small_graph):
    with pytest.raises(ConfigError, match="h"):
        strategy_set(cvx_small_graph, [2, 5, 8], h=0.0)
    with pytest.raises(ConfigError, match="k"):
        strategy_set(cvx_small_graph, [2, 5, 8], k=0)
    with pytest.raises(ConfigError, match="subset"):
        strategy_set(cvx_small_graph, [2, 50])
