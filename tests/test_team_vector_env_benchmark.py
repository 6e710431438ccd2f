"""The batched team core's benchmark runs with a tiny budget and reports its row."""

from benchmarks import team_vector_env


def test_team_vector_env_benchmark_runs(capsys):
    out = team_vector_env.main(["--steps", "20", "--teams", "4", "--rounds", "2"])
    text = capsys.readouterr().out
    assert set(out["rates"]) == {team_vector_env.BATCHED, team_vector_env.ANCHOR}
    assert all(len(v) == 2 and min(v) > 0 for v in out["rates"].values())
    row = out["ratio"]
    assert 0 < row["low"] <= row["median"] <= row["high"] and row["target"] == 10
    assert "load average" in text and "≥ 10" in text
