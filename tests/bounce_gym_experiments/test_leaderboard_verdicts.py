"""The leaderboard's "Who wins": probability of improvement with its interval, per experiment,
sampled agents with enough seeds only, and experiments that do not discriminate left out."""

import numpy as np
import pytest

from bounce_gym_experiments import stats
from bounce_gym_experiments.families.coverage import FAMILY as COVERAGE
from bounce_gym_experiments.families.navigation import FAMILY as NAVIGATION
from bounce_gym_experiments.leaderboard import (
    WHO_WINS_WIDTH,
    headline_markdown,
    kind,
    runs_of,
    verdict_rows,
    verdicts,
    who_wins_text,
    winners,
)
from bounce_gym_experiments.report import table_rows


def test_kinds_of_rows():
    assert [kind(p) for p in ("rl dqn", "rl ppo (greedy)", "random", "fixed 45°",
                              "oracle: best fixed angle per episode (hindsight)",
                              "roadmap planner", "random layer", "always drift",
                              "value iteration", "rl dqn (pose observed) (greedy)",
                              "random deployment", "Alg. 5.2 deployment")] == [
        "rl", "greedy", "random", "fixed", "oracle", "planner", "random", "fixed", "planner",
        "greedy", "random", "planner"]


def _episodes(experiment, policy, outcomes, group=None, score="success"):
    return [{"experiment": experiment, "policy": policy, "seed": 10_000 + i, score: v,
             **({"group": group} if group else {})} for i, v in enumerate(outcomes)]


def _bernoulli(rng, p, n):
    return [bool(x) for x in rng.random(n) < p]


def _experiment(rng, name, planner, agent, random, seeds=5, n=200):
    episodes = _episodes(name, "roadmap planner", _bernoulli(rng, planner, n))
    episodes += _episodes(name, "random", _bernoulli(rng, random, n))
    for k in range(seeds):
        episodes += _episodes(name, f"rl dqn_seed{k}", _bernoulli(rng, agent, n), "rl dqn")
        episodes += _episodes(name, f"rl dqn_seed{k} (greedy)", _bernoulli(rng, 0.1, n),
                              "rl dqn (greedy)")
    return episodes


def test_verdicts_by_probability_of_improvement():
    rng = np.random.default_rng(0)
    episodes = _experiment(rng, "a", 1.0, 0.99, 0.36) + _experiment(rng, "b", 1.0, 0.4, 0.36)
    summary, _ = table_rows(episodes, {"a": NAVIGATION, "b": NAVIGATION})
    a, b = verdicts(summary, episodes, {"a": NAVIGATION, "b": NAVIGATION})
    assert a["rl"]["policy"] == "rl dqn"  # the greedy twin is not the agent compared
    assert a["rl_vs_random"]["winner"] == "rl dqn" and a["rl_vs_random"]["p_lo"] > 0.5
    assert a["planner_vs_random"]["winner"] == "roadmap planner"
    assert b["rl_vs_planner"]["winner"] == "roadmap planner" and b["rl_vs_planner"]["p_hi"] < 0.5
    assert b["rl_vs_random"]["winner"] is None  # 0.40 vs 0.36: not apart
    assert a["discriminates"] and b["discriminates"]
    # P(X > Y) of two rates is 1/2 + (p_x - p_y) / 2
    p = b["planner_vs_random"]
    random_rate = np.mean([e["success"] for e in episodes
                           if e["experiment"] == "b" and e["policy"] == "random"])
    assert p["p"] == pytest.approx(0.5 + (1.0 - random_rate) / 2)
    text = verdict_rows([b])[0]
    assert text["rl_vs_random"].endswith(": no difference") and text["rl_vs_random"][:2] == "P="


def test_rows_that_tie_at_the_ceiling_are_left_out_of_the_headline():
    rng = np.random.default_rng(1)
    episodes = _experiment(rng, "tie", 1.0, 1.0, 1.0) + _experiment(rng, "apart", 1.0, 0.9, 0.3)
    families = {"tie": NAVIGATION, "apart": NAVIGATION}
    summary, _ = table_rows(episodes, families)
    tie, apart = verdicts(summary, episodes, families)
    assert not tie["discriminates"] and tie["rl_vs_random"]["p"] == 0.5
    assert (tie["rl_vs_random"]["p_lo"], tie["rl_vs_random"]["p_hi"]) == (0.5, 0.5)
    assert apart["discriminates"]
    table = "\n".join(headline_markdown(verdict_rows([tie, apart])))
    assert "| apart |" in table and "| tie |" not in table
    assert table.endswith("on the score: tie.")


def test_a_learner_with_fewer_than_five_seeds_gets_no_verdict():
    rng = np.random.default_rng(2)
    episodes = _experiment(rng, "few", 1.0, 0.99, 0.3, seeds=2)
    summary, _ = table_rows(episodes, {"few": NAVIGATION})
    (v,) = verdicts(summary, episodes, {"few": NAVIGATION})
    assert v["rl"]["seeds"] == 2 and v["rl_vs_random"] is None and v["rl_vs_planner"] is None
    row = verdict_rows([v])[0]
    assert row["rl"].startswith("rl dqn [2 seeds < 5]: ") and row["rl_vs_random"] == "-"


def test_lower_is_better_scores_and_missing_agents():
    rng = np.random.default_rng(3)
    score = COVERAGE.score
    assert not COVERAGE.higher_is_better
    episodes = _episodes("c", "mixture α", list(0.119 + 0.001 * rng.random(200)), score=score)
    episodes += _episodes("c", "random", list(0.25 + 0.01 * rng.random(200)), score=score)
    for k in range(5):
        episodes += _episodes("c", f"rl ppo_seed{k}", list(0.15 + 0.01 * rng.random(200)),
                              "rl ppo", score)
    summary, _ = table_rows(episodes, {"c": COVERAGE})
    (c,) = verdicts(summary, episodes, {"c": COVERAGE})
    assert c["rl_vs_planner"]["winner"] == "mixture α" and c["rl_vs_planner"]["p"] == 0.0
    assert c["rl_vs_random"]["winner"] == "rl ppo" and c["rl_vs_random"]["p"] == 1.0
    (d,) = verdicts([r for r in summary if r["policy"] == "mixture α"], episodes,
                    {"c": COVERAGE})
    assert d["rl"] is None and d["rl_vs_planner"] is None and not d["discriminates"]


def test_runs_of_a_row_are_its_models():
    episodes = _episodes("e", "rl a_seed0", [True, False], "rl a") + _episodes(
        "e", "rl a_seed1", [True], "rl a") + _episodes("e", "random", [False])
    assert runs_of(episodes, "e", {"policy": "rl a"}, "success") == [[1.0, 0.0], [1.0]]
    assert runs_of(episodes, "e", {"policy": "random"}, "success") == [[0.0]]


# The protocol on synthetic data with known answers (issue 34): 5 training seeds x 200
# episodes per learner, each seed's true rate drawn around the learner's, against each other.
SYNTHETIC_DATASETS = 200
SYNTHETIC_RESAMPLES = 1000


def _learner(rng, rate, seeds=5, n=200, spread=0.02):
    return [rng.random(n) < np.clip(rng.normal(rate, spread), 0, 1) for _ in range(seeds)]


def test_two_equal_policies_get_no_win_in_at_least_95_percent_of_datasets():
    rng = np.random.default_rng(10)
    wins = [stats.verdict(stats.improvement(_learner(rng, 0.7), _learner(rng, 0.7),
                                            n_resamples=SYNTHETIC_RESAMPLES, seed=k))
            for k in range(SYNTHETIC_DATASETS)]
    assert wins.count(1) <= 0.05 * SYNTHETIC_DATASETS  # X never better in >= 95%
    assert wins.count(-1) <= 0.05 * SYNTHETIC_DATASETS  # nor Y


def test_a_gap_of_five_points_over_200_episodes_and_5_seeds_is_found():
    rng = np.random.default_rng(11)
    found = [stats.verdict(stats.improvement(_learner(rng, 0.90, spread=0.0),
                                             _learner(rng, 0.85, spread=0.0),
                                             n_resamples=SYNTHETIC_RESAMPLES, seed=k))
             for k in range(SYNTHETIC_DATASETS // 2)]
    assert found.count(-1) == 0  # never the wrong way round
    # measured power 0.80 (docs/benchmark.md gives it for other rates and seed spreads): the
    # two-level bootstrap is conservative, it counts episode noise at both levels
    assert found.count(1) >= 0.7 * len(found)


def test_who_wins_names_the_rows_none_beats_in_100_columns():
    """The summary `evaluate` prints: the winner of each experiment by its comparisons, every
    compared row's value with its interval and count, no line wider than 100 characters."""
    rng = np.random.default_rng(2)
    names = ("a-long-experiment-name-of-forty-letters-", "planner-and-rl", "none", "alone")
    episodes = (_experiment(rng, names[0], 0.4, 0.99, 0.3)
                + _experiment(rng, names[1], 1.0, 1.0, 0.3)
                + _experiment(rng, names[2], 1.0, 1.0, 1.0)
                + _episodes(names[3], "roadmap planner", _bernoulli(rng, 0.5, 50)))
    families = dict.fromkeys(names, NAVIGATION)
    summary, _ = table_rows(episodes, families)
    decided = verdicts(summary, episodes, families)
    assert [winners(v) for v in decided] == [["rl"], ["planner", "rl"], [], []]
    text = who_wins_text(decided, "runs/x/leaderboard.md")
    assert max(len(line) for line in text.splitlines()) <= WHO_WINS_WIDTH
    assert "runs/x/leaderboard.md" in text
    for name, verdict in zip(names, ("RL", "planner and RL", "none apart",
                                     "one row, nothing to compare"), strict=True):
        assert f"{name}: success (higher is better); winner: {verdict}" in text
    assert "RL 0.99 [0.98, 1.00] n=1000" in text.replace("\n    ", " ")
