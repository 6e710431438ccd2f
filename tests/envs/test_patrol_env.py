"""`bounce_gym/Patrol-v0` (Alam 2018 thesis ch. 4): PettingZoo's test kit (parallel, AEC through
parallel_to_aec, seeds), the capture rule of §4.3.5 and its exact probabilities against Monte
Carlo runs of the env itself, rewards and episode ends, illegal actions, bad arguments, seeding,
pickling and rendering."""

import itertools
import pickle
import warnings

import numpy as np
import pettingzoo
import pytest
from gymnasium.utils.env_checker import data_equivalence
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.patrolling.markov import transition_matrix
from bounce_gym.envs.patrol import patrol_v0
from bounce_gym.envs.patrol.env import PatrolEnv
from bounce_gym.envs.registration import is_pettingzoo_id
from bounce_gym.errors import ActionError, ConfigError
from bounce_gym.worlds.grid import parse_ascii, world_from_grid

#: 5 x 6 cells, two blocked: 28 vertices
TINY = world_from_grid(parse_ascii(["......",
                                    "..#...",
                                    "......",
                                    "...#..",
                                    "......"]), name="patrol_tiny")
#: with range 1, a cell sees only itself: T_z = {z}
BLIND = dict(world=TINY, sensor_range=1.0)
P0, P1, ADV = "patroller_0", "patroller_1", "adversary"


@pytest.fixture(autouse=True)
def _quiet_test_kit_warnings():
    # the test kit resets with options={"options": 1} (the env warns about the unknown key),
    # patrollers and adversary observe different shapes, and "adversary" has no number
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="reset options: unknown keys")
        warnings.filterwarnings("ignore", message="Observations are different shapes")
        warnings.filterwarnings("ignore", message="Agents have different observation space")
        warnings.filterwarnings("ignore", message="We recommend agents to be named")
        yield


def vertex(env, row, col):
    cells = env.visibility.cells.tolist()
    return cells.index([row, col])


def wait(env, **moves):
    """Actions: the given patroller moves (direction indices), every other agent action 0."""
    return {a: moves.get(a, 0) for a in env.agents}


# -- PettingZoo's test kit and registration ----------------------------------------------------

@pytest.mark.parametrize("kwargs", [dict(), dict(world=TINY, n_patrollers=3, attack_time=3,
                                                 adversary_observes="positions")],
                         ids=["default", "tiny"])
def test_parallel_and_aec_api(kwargs):
    parallel_api_test(patrol_v0.parallel_env(**kwargs), num_cycles=200)
    api_test(patrol_v0.env(**kwargs), num_cycles=200)


def test_aec_api_with_illegal_actions_as_errors():
    # api_test samples from info["action_mask"], so no illegal action reaches the env
    api_test(patrol_v0.env(world=TINY, illegal_action="error", attack_time=5), num_cycles=200)


def test_parallel_seed_test():
    parallel_seed_test(lambda: patrol_v0.parallel_env(world=TINY, attack_time=5), num_cycles=50)


def test_registered_ids():
    assert is_pettingzoo_id("bounce_gym/Patrol-v0")
    parallel = pettingzoo.make("parallel", "bounce_gym/Patrol-v0")
    assert isinstance(parallel, PatrolEnv) and parallel.max_cycles == 500
    assert parallel.n_vertices == 188 and parallel.board.world.name == "patrol_15x15"
    aec = pettingzoo.make("aec", "bounce_gym/Patrol-v0", world=TINY, n_patrollers=1)
    aec.reset(seed=0)
    assert aec.agents == [P0, ADV]


# -- the board ----------------------------------------------------------------------------------

def test_board_numbering_neighbours_and_uniform_walk():
    env = PatrolEnv(world=TINY)
    cells = np.array([env.graph.nodes[v]["cell"] for v in range(env.n_vertices)])
    np.testing.assert_array_equal(cells, env.visibility.cells)
    table = env.neighbour_table
    assert table.shape == (28, 8) and not table.flags.writeable
    for v, k in zip(*np.nonzero(table >= 0), strict=True):
        u = table[v, k]
        assert env.graph.has_edge(v, u) and env.action_towards(v, u) == k
    assert (table >= 0).sum() == 2 * env.graph.number_of_edges()
    # north is one row up (y up), east one column right
    v = vertex(env, 0, 0)
    assert table[v, 0] == vertex(env, 1, 0) and table[v, 2] == vertex(env, 0, 1)
    assert table[v, 4] == table[v, 6] == -1
    P, _ = transition_matrix(env.graph, nodes=range(env.n_vertices))
    np.testing.assert_allclose(env.strategy, P.toarray())
    watch = env.watch_regions
    assert len(watch) == 28 and all(z in T for z, T in enumerate(watch))


def test_action_towards_refuses_a_non_neighbour():
    env = PatrolEnv(world=TINY)
    with pytest.raises(ConfigError, match="u: vertex 27 is not a neighbour of vertex 0"):
        env.action_towards(0, 27)
    with pytest.raises(ConfigError, match="v:"):
        env.action_towards(28, 0)


# -- capture probabilities ----------------------------------------------------------------------

def test_distinct_uniform_start_is_the_mean_over_subsets():
    env = PatrolEnv(world=TINY, n_patrollers=3, sensor_range=2.0, attack_time=4)
    subsets = list(itertools.combinations(range(env.n_vertices), 3))
    mean = np.mean([env.capture_probabilities(list(c)) for c in subsets], axis=0)
    np.testing.assert_allclose(env.capture_probabilities(), mean, atol=1e-12)


def test_capture_probabilities_from_positions_by_hand():
    env = PatrolEnv(**BLIND, n_patrollers=1, attack_time=1)
    v = vertex(env, 0, 0)  # corner with 3 neighbours: N, NE, E
    p = env.capture_probabilities([v])
    assert p[v] == 1.0  # already in T_v = {v}
    for k in (0, 1, 2):
        assert p[env.neighbour_table[v, k]] == pytest.approx(1 / 3)
    assert p[vertex(env, 4, 5)] == 0.0


def test_one_patroller_by_enumerating_its_walks():
    env = PatrolEnv(world=TINY, n_patrollers=1, sensor_range=2.0, attack_time=3)
    seen, P = env.visibility.seen.toarray(), env.strategy
    for v in (0, 13, 27):
        escape = np.zeros(env.n_vertices)  # Pr[the walk from v never enters T_z], per z

        def walk(path, prob):
            if len(path) == 4:  # times 0..3
                escape[~seen[:, path].any(axis=1)] += prob  # noqa: B023
                return
            for u in np.flatnonzero(P[path[-1]]):
                walk([*path, u], prob * P[path[-1], u])  # noqa: B023

        walk([v], 1.0)
        np.testing.assert_allclose(env.capture_probabilities([v]), 1 - escape, atol=1e-12)


def test_capture_probabilities_match_monte_carlo_of_the_env():
    # two random-walk patrollers placed by the env, the adversary attacks a uniformly random
    # target at step 0; without the check at the attack's start the mean would be 0.049 lower
    env = PatrolEnv(world=TINY, n_patrollers=2, sensor_range=2.0, attack_time=3)
    exact = env.capture_probabilities()
    rng = np.random.default_rng(7)
    legal = [np.flatnonzero(row >= 0) for row in env.neighbour_table]
    runs = 4000
    attacks, caught = np.zeros(env.n_vertices), np.zeros(env.n_vertices)
    env.reset(seed=3)
    for _ in range(runs):
        _, infos = env.reset()
        z = int(rng.integers(env.n_vertices))
        actions = {ADV: z + 1}
        while env.agents:
            for a in (P0, P1):
                moves = legal[infos[a]["vertex"]]
                actions[a] = int(moves[rng.integers(len(moves))])
            _, rewards, _, _, infos = env.step(actions)
            assert sum(rewards.values()) == pytest.approx(0.0, abs=1e-12)
            actions[ADV] = 0
        attacks[z] += 1
        caught[z] += infos[ADV]["outcome"] == "capture"
    mean = exact @ attacks / runs
    assert abs(caught.sum() / runs - mean) < 4 * np.sqrt(mean * (1 - mean) / runs)
    se = np.sqrt(exact * (1 - exact) / attacks)
    assert np.all(np.abs(caught / attacks - exact) < 4 * se)


def test_reset_strategy_option_replaces_the_strategy_for_one_episode():
    env = PatrolEnv(**BLIND, n_patrollers=1, attack_time=2, start=[0])
    uniform = env.capture_probabilities()
    # a walker that always goes east along the bottom row when it can, else north
    P = np.zeros((28, 28))
    for v, row in enumerate(env.neighbour_table):
        P[v, row[2] if row[2] >= 0 else row[row >= 0][0]] = 1.0
    env.reset(options={"strategy": P})
    np.testing.assert_array_equal(env.strategy, P)
    caught = env.capture_probabilities()
    assert set(np.flatnonzero(caught == 1.0)) == {0, 1, 2}
    env.reset()
    np.testing.assert_array_equal(env.capture_probabilities(), uniform)


@pytest.mark.parametrize(("strategy", "match"), [
    (np.eye(28), r"options.strategy: P\[0, 0\] = 1.0 > 0 but \(0, 0\) is not an edge"),
    (np.full((28, 28), 1 / 28), "options.strategy: P.* is not an edge"),
    (np.zeros((28, 28)), "options.strategy: every row must sum to 1"),
    (np.ones((3, 3)) / 3, r"options.strategy: expected an 28x28 matrix.*shape \(3, 3\)"),
    ("uniform", "options.strategy: expected an 28x28 matrix"),
])
def test_reset_with_a_bad_strategy_is_a_config_error(strategy, match):
    env = PatrolEnv(world=TINY)
    with pytest.raises(ConfigError, match=match):
        env.reset(options={"strategy": strategy})


# -- the capture rule, rewards and episode ends -------------------------------------------------

def test_capture_at_start_although_the_patroller_walks_away():
    env = PatrolEnv(**BLIND, start=[0, 27])
    env.reset(seed=0)
    _, rewards, terms, truncs, infos = env.step(wait(env, patroller_0=0) | {ADV: 1})
    assert env.positions()[0] != 0  # gone from T_0 = {0} after the step
    assert infos[ADV]["outcome"] == "capture" and infos[ADV]["attack_target"] == 0
    assert infos[ADV]["attack_started"] == 0 and infos[ADV]["attack_elapsed"] == 1
    assert rewards == {P0: 0.5, P1: 0.5, ADV: -1.0}
    assert all(terms.values()) and not any(truncs.values()) and env.agents == []


def test_capture_when_a_patroller_walks_in():
    env = PatrolEnv(**BLIND, n_patrollers=1, start=[vertex(PatrolEnv(**BLIND), 0, 1)])
    env.reset(seed=0)
    target = vertex(env, 0, 3)
    _, rewards, _, _, infos = env.step({P0: 2, ADV: target + 1})
    assert infos[P0]["outcome"] is None and rewards[ADV] == 0.0
    _, rewards, _, _, infos = env.step({P0: 2, ADV: 0})
    assert infos[P0]["vertex"] == target and infos[P0]["outcome"] == "capture"
    assert rewards == {P0: 1.0, ADV: -1.0}


def test_success_after_exactly_attack_time_steps():
    env = PatrolEnv(**BLIND, attack_time=3, start=[0, 1])
    env.reset(seed=0)
    target = env.n_vertices - 1
    actions = {P0: 0, P1: 0, ADV: target + 1}
    for step in range(1, 4):
        _, rewards, terms, _, infos = env.step(actions)
        actions = {P0: 4 if step % 2 else 0, P1: 4 if step % 2 else 0, ADV: 0}
        assert infos[ADV]["attack_elapsed"] == step and infos[ADV]["step"] == step
        if step < 3:
            assert infos[ADV]["outcome"] is None and not any(terms.values())
            assert rewards == {P0: 0.0, P1: 0.0, ADV: 0.0}
    assert infos[ADV]["outcome"] == "success" and all(terms.values())
    assert rewards == {P0: -0.5, P1: -0.5, ADV: 1.0}
    assert env.agents == []


def test_deterred_when_the_adversary_waits_too_long():
    env = PatrolEnv(**BLIND, attack_time=4, max_cycles=10, start=[0, 1])
    env.reset(seed=0)
    for step in range(1, 8):
        _, rewards, terms, _, infos = env.step({P0: 0 if step % 2 else 4, P1: 0 if step % 2
                                                else 4, ADV: 0})
        assert (infos[ADV]["outcome"] == "deterred") == (step == 7)
    assert rewards == {P0: 0.5, P1: 0.5, ADV: -1.0} and all(terms.values())


def test_the_last_attack_start_ends_at_max_cycles():
    env = PatrolEnv(**BLIND, attack_time=4, max_cycles=10, start=[0, 1])
    env.reset(seed=0)
    for step in range(1, 11):
        up = 0 if step % 2 else 4
        _, rewards, _, truncs, infos = env.step({P0: up, P1: up,
                                                 ADV: env.n_vertices if step == 7 else 0})
        assert not any(truncs.values())
    assert infos[ADV]["outcome"] == "success" and infos[ADV]["attack_started"] == 6
    assert infos[ADV]["step"] == 10 == env.max_cycles


# -- observations and state ---------------------------------------------------------------------

def test_observations_and_state():
    probe = PatrolEnv(world=TINY)
    a, b, far = vertex(probe, 0, 0), vertex(probe, 0, 2), vertex(probe, 4, 5)
    env = PatrolEnv(world=TINY, sensor_range=3.0, n_patrollers=3, start=[a, b, far],
                    adversary_observes="positions", attack_time=5, max_cycles=20)
    obs, infos = env.reset(seed=0)
    n = env.n_vertices
    assert env.visibility.seen[a, b] and env.visibility.seen[b, a]
    assert not env.visibility.seen[a, far] and not env.visibility.seen[far, a]
    assert np.flatnonzero(obs[P0]).tolist() == [a, n + b]
    assert np.flatnonzero(obs[P1]).tolist() == [b, n + a]
    assert np.flatnonzero(obs["patroller_2"]).tolist() == [far]
    adv = obs[ADV]
    assert adv.shape == (2 * n + 3,) and adv.dtype == np.float32
    np.testing.assert_allclose(adv[:n], env.capture_probabilities(), rtol=1e-6)
    assert adv[n:n + 3].tolist() == [0.0, 0.0, 0.0]
    assert np.flatnonzero(adv[n + 3:]).tolist() == sorted([a, b, far])
    obs, *_ = env.step(wait(env) | {ADV: far + 1})
    assert obs[ADV][n:n + 3].tolist() == pytest.approx([1.0, 1 / 5, 1 / 20])
    state = env.state()
    assert env.state_space.contains(state)
    assert np.flatnonzero(state).tolist()[:4] == [env.positions()[0], n + env.positions()[1],
                                                  2 * n + env.positions()[2], 3 * n + far]
    assert infos[P0]["vertex"] == a and infos[ADV]["attack_target"] == -1


# -- illegal actions ----------------------------------------------------------------------------

def test_illegal_moves_stay_and_are_flagged():
    env = PatrolEnv(**BLIND, start=[0, 5])
    _, infos = env.reset(seed=0)
    assert infos[P0]["action_mask"].tolist() == [1, 1, 1, 0, 0, 0, 0, 0]
    np.testing.assert_array_equal(env.action_mask(P0), infos[P0]["action_mask"])
    _, _, _, _, infos = env.step({P0: 4, P1: 0, ADV: 3})
    assert infos[P0]["illegal_action"] and infos[P0]["vertex"] == 0
    assert not infos[P1]["illegal_action"] and infos[P1]["vertex"] != 5
    assert infos[ADV]["action_mask"].tolist() == [1] + [0] * 28
    _, _, _, _, infos = env.step({P0: 0, P1: 4, ADV: 7})  # a second start is a wait
    assert infos[ADV]["illegal_action"] and infos[ADV]["attack_target"] == 2


def test_illegal_actions_as_errors_name_the_agent_and_change_nothing():
    env = PatrolEnv(**BLIND, start=[0, 5], illegal_action="error")
    env.reset(seed=0)
    with pytest.raises(ActionError, match=r"action of patroller_0: 4 \(S\) is illegal at vertex "
                                          r"0.*legal actions are \['0 \(N\)', '1 \(NE\)', "
                                          r"'2 \(E\)'\]"):
        env.step({P0: 4, P1: 0, ADV: 3})
    assert env.positions().tolist() == [0, 5] and env.state()[-3] == 0.0
    env.step({P0: 0, P1: 0, ADV: 3})
    with pytest.raises(ActionError, match=r"action of adversary: 7 is illegal, the attack "
                                          r"started at step 0; the only legal action is \[0\]"):
        env.step({P0: 4, P1: 0, ADV: 7})


@pytest.mark.parametrize("action", [8, -1, 1.0, True, np.array([1])])
def test_actions_outside_the_space_are_action_errors(action):
    env = PatrolEnv(world=TINY)
    env.reset(seed=0)
    with pytest.raises(ActionError, match=r"action of patroller_1: expected an integer in "
                                          r"\[0, 7\]"):
        env.step({P0: 0, P1: action, ADV: 0})
    with pytest.raises(ActionError, match="action of adversary"):
        env.step({P0: 0, P1: 0, ADV: 29})


def test_step_before_reset_and_after_the_end():
    env = PatrolEnv(**BLIND, start=[0, 27])
    with pytest.raises(ConfigError, match="call reset"):
        env.step({P0: 0, P1: 0, ADV: 0})
    env.reset(seed=0)
    env.step({P0: 0, P1: 0, ADV: 1})
    with pytest.raises(ConfigError, match="call reset"):
        env.step({P0: 0, P1: 0, ADV: 0})


# -- bad arguments ------------------------------------------------------------------------------

@pytest.mark.parametrize(("kwargs", "field"), [
    (dict(world=3), "world"),
    (dict(world="no_such_map"), "world"),
    (dict(cell_size=0), "cell_size"),
    (dict(corner_rule="loose"), "corner_rule"),
    (dict(n_patrollers=0), "n_patrollers"),
    (dict(n_patrollers=True), "n_patrollers"),
    (dict(n_patrollers=29), "n_patrollers"),
    (dict(sensor_range=-1.0), "sensor_range"),
    (dict(sensor_range="6"), "sensor_range"),
    (dict(visibility_rule="rays"), "visibility_rule"),
    (dict(attack_time=0), "attack_time"),
    (dict(attack_time=501), "attack_time"),
    (dict(attack_time=11, max_cycles=10), "attack_time"),
    (dict(adversary_observes="everything"), "adversary_observes"),
    (dict(strategy=np.eye(28)), "strategy"),
    (dict(strategy=np.ones((28, 28))), "strategy"),
    (dict(start=[0], n_patrollers=2), "start"),
    (dict(start=[0, 28]), r"start\[1\]"),
    (dict(start=5), "start"),
    (dict(max_cycles=0), "max_cycles"),
    (dict(illegal_action="ignore"), "illegal_action"),
    (dict(render_mode="ansi"), "render_mode"),
])
def test_bad_arguments_are_config_errors_naming_the_argument(kwargs, field):
    with pytest.raises(ConfigError, match=rf"^{field}:"):
        PatrolEnv(**{"world": TINY, **kwargs})


def test_unknown_arguments_are_type_errors():
    with pytest.raises(TypeError, match="n_robots"):
        PatrolEnv(world=TINY, n_robots=2)


def test_start_sets_the_number_of_patrollers():
    env = PatrolEnv(world=TINY, start=[3, 3, 4])
    obs, _ = env.reset(seed=0)
    assert env.possible_agents == [P0, P1, "patroller_2", ADV]
    assert env.positions().tolist() == [3, 3, 4]


# -- seeding, pickling, rendering ---------------------------------------------------------------

def rollout(env, seed, steps, rng_seed):
    obs, infos = env.reset(seed=seed)
    record = [(obs, infos)]
    rng = np.random.default_rng(rng_seed)
    for _ in range(steps):
        if not env.agents:
            record.append(env.reset())
            continue
        actions = {a: int(rng.choice(np.flatnonzero(infos[a]["action_mask"])))
                   for a in env.agents}
        actions[ADV] = int(rng.integers(env.n_vertices + 1)) if rng.random() < 0.1 else 0
        obs, rewards, terms, truncs, infos = env.step(actions)
        record.append((obs, rewards, terms, truncs, infos))
    return record


def test_same_seed_and_actions_give_the_same_episodes():
    kwargs = dict(world=TINY, n_patrollers=3, attack_time=4, max_cycles=30)
    first = rollout(PatrolEnv(**kwargs), 5, 120, 0)
    assert data_equivalence(first, rollout(PatrolEnv(**kwargs), 5, 120, 0), exact=True)
    other = rollout(PatrolEnv(**kwargs), 6, 120, 0)
    assert not data_equivalence(first, other)


def test_pickling_mid_episode_continues_identically():
    env = PatrolEnv(**BLIND, attack_time=6, start=[0, 20], render_mode="rgb_array")
    env.reset(seed=4)
    env.render()
    env.step({P0: 0, P1: 4, ADV: 28})
    env.step({P0: 0, P1: 0, ADV: 0})
    copy = pickle.loads(pickle.dumps(env))
    for actions in ({P0: 2, P1: 4, ADV: 0}, {P0: 6, P1: 0, ADV: 0}):
        a, b = env.step(actions), copy.step(actions)
        assert data_equivalence(a, b, exact=True)
    np.testing.assert_array_equal(env.render(), copy.render())


def test_rendering_shows_a_moving_patroller():
    env = PatrolEnv(world=TINY, start=[0, 20], render_mode="rgb_array")
    env.reset(seed=0)
    before = env.render()
    assert before.ndim == 3 and before.shape[2] == 3 and before.dtype == np.uint8
    env.step({P0: 0, P1: 0, ADV: 0})
    after = env.render()
    assert after.shape == before.shape and not np.array_equal(before, after)
    env.step({P0: 0, P1: 0, ADV: 10})
    assert not np.array_equal(after, env.render())  # the attacked cell
    env.close()
    with pytest.warns(UserWarning, match="render_mode=None"):
        assert PatrolEnv(world=TINY).render() is None


def test_reset_start_option_places_the_patrollers_for_one_episode():
    env = PatrolEnv(**BLIND, attack_time=1)
    _, infos = env.reset(seed=0, options={"start": [4, 9]})
    assert env.positions().tolist() == [4, 9] and infos[P1]["vertex"] == 9
    p = env.capture_probabilities()
    np.testing.assert_array_equal(p, env.capture_probabilities([4, 9]))
    assert p[4] == p[9] == 1.0
    env.reset(options={"start": np.array([0, 0]), "strategy": env.strategy.copy()})
    assert env.positions().tolist() == [0, 0]
    env.reset()
    assert not np.array_equal(env.capture_probabilities(), p)  # distinct uniform again
    with pytest.raises(ConfigError, match=r"options.start: expected 2 vertex indices"):
        env.reset(options={"start": [1]})
    with pytest.raises(ConfigError, match=r"options.start\[0\]: expected an integer in "
                                          r"\[0, 27\]"):
        env.reset(options={"start": [28, 0], "strategy": env.strategy.copy()})
    with pytest.warns(UserWarning, match="reset options: unknown keys"):
        env.reset(options={"deploy": [1, 2]})
