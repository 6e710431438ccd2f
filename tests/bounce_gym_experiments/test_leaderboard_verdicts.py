"""The leaderboard's "Who wins": decided by intervals, per experiment, sampled agents only."""

from bounce_gym_experiments.families.coverage import FAMILY as COVERAGE
from bounce_gym_experiments.families.navigation import FAMILY as NAVIGATION
from bounce_gym_experiments.leaderboard import kind, verdicts


def _row(experiment, policy, value, lo, hi, score="success"):
    return {"experiment": experiment, "policy": policy, score: value, f"{score}_lo": lo,
            f"{score}_hi": hi}


def test_kinds_of_rows():
    assert [kind(p) for p in ("rl dqn", "rl ppo (greedy)", "random", "fixed 45°",
                              "oracle: best fixed angle per episode (hindsight)",
                              "roadmap planner", "random layer", "always drift",
                              "value iteration")] == [
        "rl", "greedy", "random", "fixed", "oracle", "planner", "random", "fixed", "planner"]


def test_verdicts_by_disjoint_intervals():
    summary = [_row("a", "roadmap planner", 1.0, 0.98, 1.0),
               _row("a", "rl dqn", 0.99, 0.99, 1.0),
               _row("a", "rl dqn (greedy)", 0.5, 0.4, 0.6),
               _row("a", "random", 0.36, 0.30, 0.43),
               _row("b", "roadmap planner", 1.0, 0.98, 1.0),
               _row("b", "rl ppo", 0.40, 0.30, 0.50),
               _row("b", "random", 0.36, 0.30, 0.43)]
    a, b = verdicts(summary, {"a": NAVIGATION, "b": NAVIGATION})
    assert a["rl"]["policy"] == "rl dqn"  # the greedy twin is not the agent compared
    assert a["rl_vs_planner"] == "tie (intervals overlap)" and a["rl_vs_random"] == "rl dqn"
    assert b["rl_vs_planner"] == "roadmap planner"
    assert b["rl_vs_random"] == "tie (intervals overlap)"


def test_lower_is_better_scores_and_missing_agents():
    score = COVERAGE.score
    assert not COVERAGE.higher_is_better
    summary = [_row("c", "mixture α", 0.119, 0.118, 0.120, score),
               _row("c", "rl ppo", 0.15, 0.14, 0.16, score),
               _row("c", "random", 0.25, 0.24, 0.26, score),
               _row("d", "mixture α", 0.119, 0.118, 0.120, score)]
    c, d = verdicts(summary, {"c": COVERAGE, "d": COVERAGE})
    assert c["rl_vs_planner"] == "mixture α" and c["rl_vs_random"] == "rl ppo"
    assert d["rl"] is None and d["rl_vs_planner"] == "-"
