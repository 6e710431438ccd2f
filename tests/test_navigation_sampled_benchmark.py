"""The sampled-GCM navigation benchmark (docs/sampled_models.md) runs end to end."""

import numpy as np

from benchmarks import navigation_sampled


def test_navigation_sampled_benchmark_runs(capsys):
    out = navigation_sampled.main(["--episodes", "2", "--samples", "4", "--depth", "1",
                                   "--reach", "3", "--cell-size", "1"])
    assert len(out["sampled"]) == 2 and len(out["roadmap"]) == 2
    assert np.all((out["predicted"] >= 0) & (out["predicted"] <= 1))
    assert "sampled SSP + filter" in capsys.readouterr().out
