"""The dynamic-physics benchmark (issue 23) runs with a tiny budget and reports every row."""

from benchmarks import dynamic_physics


def test_dynamic_physics_benchmark_runs(capsys):
    out = dynamic_physics.main(["--steps", "20", "--agent-steps", "40", "--rounds", "2"])
    text = capsys.readouterr().out
    labels = [label for label, *_ in dynamic_physics.SINGLE] + [dynamic_physics.MULTI]
    assert set(labels) <= set(out["rates"])
    assert all(len(v) == 2 and min(v) > 0 for v in out["rates"].values())
    names = {f"{num} ÷ {den}" for num, den, _ in dynamic_physics.RATIOS}
    assert set(out["ratios"]) <= names
    assert "Bounce-v0 dynamic ÷ Bounce-v0 kinematic" in out["ratios"]
    for row in out["ratios"].values():
        assert 0 < row["low"] <= row["median"] <= row["high"]
    assert "load average" in text and "≥ 1/4" in text
    if dynamic_physics.PISTONBALL in out["rates"]:
        assert "MultiBounce 20 dynamic ÷ pistonball_v6 20 pistons" in out["ratios"]
    else:
        assert "skipped" in text
