"""The Drifter-v0 benchmark runs and measures every env of its table against CartPole-v1."""

from benchmarks import drifter_env


def test_drifter_env_benchmark_runs(capsys):
    ratios = drifter_env.main(["--steps", "30", "--rounds", "1"])
    assert set(ratios) == {label for label, *_ in drifter_env.ENVS}
    assert ratios["CartPole-v1"] == 1.0 and all(r > 0 for r in ratios.values())
    assert "Drifter-v0 continuous" in capsys.readouterr().out
