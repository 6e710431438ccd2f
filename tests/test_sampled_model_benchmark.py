"""The sampled-GCM build benchmark (issue 24) runs with a tiny budget and reports its rows."""

from benchmarks import sampled_model


def test_sampled_model_benchmark_runs(capsys):
    out = sampled_model.main(["--quick", "--rounds", "2", "--maps", "lab_navigation"])
    text = capsys.readouterr().out
    row = out["lab_navigation"]
    assert len(row["seconds"]) == len(row["ratio"]) == 2
    assert min(row["seconds"]) > 0 and min(row["ratio"]) > 0
    assert row["points"] >= row["states"] * 3 * 20  # 20 samples per state and angle
    assert "load average before" in text and "lab_navigation" in text
