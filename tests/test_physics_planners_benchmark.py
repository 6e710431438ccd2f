"""The physics planners' benchmark runs on a tiny budget (a small room, few particles, one
episode per round) and reports every figure."""

import pytest

from baselines.localization import ParticleLocalizationPolicy
from baselines.navigation.continuous import ContinuousNavigationPlanner
from benchmarks import physics_planners


@pytest.mark.slow
def test_physics_planners_benchmark_runs(capsys, monkeypatch):
    room = {**physics_planners.DYNAMIC, "world": "square"}
    monkeypatch.setattr(physics_planners, "ROWS", (
        ("search planner, square", "bounce_gym/BounceNavigation-v0",
         {**room, "angles": [45, 90, 135], "task_kwargs": physics_planners.GOAL},
         lambda: ContinuousNavigationPlanner(horizon=20, search_bumps=4)),
        ("particle localization, square", "bounce_gym/BounceLocalization-v0",
         {**room, "angles": [45, 135], "task_kwargs": {"filter_factory": None}},
         lambda: ParticleLocalizationPolicy(particles=200)),
    ))
    anchor = physics_planners.anchor_seconds
    monkeypatch.setattr(physics_planners, "anchor_seconds", lambda: anchor(200, "square"))
    out = physics_planners.main(["--episodes", "1", "--bumps", "3"])
    text = capsys.readouterr().out
    assert out["anchor_seconds"] > 0
    for row in ("search planner, square", "particle localization, square"):
        assert len(out[row]["round_medians"]) == 3 and out[row]["median"] > 0
    assert "load average before" in text and "anchor ÷ median" in text
