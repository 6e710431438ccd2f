"""The bump-table benchmark runs on a tiny budget (a coarse table of a 10 × 10 square) and
reports every figure."""

from benchmarks import bump_table


def test_bump_table_benchmark_runs(capsys):
    out = bump_table.main(["--maps", "square", "--particles", "60", "--poses", "30",
                           "--spacing", "4", "--headings", "12"])
    text = capsys.readouterr().out
    row = out["square"]
    assert len(row["table_seconds"]) == 3 and min(row["simulator_seconds"]) > 0
    assert all(r > 0 for r in row["ratio"]) and row["nodes"] > 0
    assert row["error"]["bumps"]["n"] > 0 and row["build_seconds"] > 0
    assert "load average before" in text and "simulator ÷ table" in text
