"""The patrolling benchmark (issue #16) runs with a tiny budget and reports every row."""

from benchmarks import patrolling


def test_patrolling_benchmark_runs(capsys):
    out = patrolling.main(["--quick", "--repeats", "1", "--steps", "40"])
    text = capsys.readouterr().out
    maect = out["maect"][patrolling.MAP]
    assert (maect["n"], maect["edges"]) == (188, 586)
    assert maect["objective"] > 0 and maect["iterations"] > 0 and maect["seconds"] > 0
    assert "Table 4.5" in text and "Table 4.4" in text
    policies = out["policies"]
    assert sorted(policies) == ["distributed 4.9(a)", "distributed 4.9(b)"]
    for row in policies.values():
        assert row["n"] == 188 and row["seconds"] > 0 and row["iterations"] > 0
        assert 676 <= row["thesis"] <= 734
    assert "distributed 4.9(a)" in text
    assert out["covers"]["cells"] == 188
    assert 0 < out["covers"]["covers_ms"] < out["covers"]["with_visibility_ms"]
    if patrolling._registered():
        assert out["env"]["patrol"] > 0 and "x pistonball" in text
    else:
        assert out["env"] == {} and "skipped" in text
