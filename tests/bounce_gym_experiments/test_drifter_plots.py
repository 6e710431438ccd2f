"""The drifter planner figures are written as PNG files (atomically, nothing left behind)."""

from __future__ import annotations

import numpy as np
from PIL import Image

from baselines.drifters import (
    deployment_locations,
    persistent_behavior,
    persistent_reachability,
    random_deployment,
    value_iteration,
    visibility_deployment,
)
from bounce_gym.cells import DrifterCells
from bounce_gym.flows import get_flow
from bounce_gym_experiments import stats
from bounce_gym_experiments.plots import drifters as plots


def test_every_drifter_figure_is_written(tmp_path):
    model = DrifterCells(get_flow("two_sink", n_layers=2))
    b = persistent_behavior(model)
    dep = deployment_locations(b)
    goal = int(model.state_of(1, 10, 10))
    written = [
        plots.plot_flow(model.field, tmp_path / "flow.png", layer=1),
        plots.plot_behavior(model, b, tmp_path / "behavior.png"),
        plots.plot_absorption_times(model, b, tmp_path / "absorption.png"),
        plots.plot_deployment(model, b, {"Alg. 5.2": dep, "random": random_deployment(b, 5)},
                              tmp_path / "deployment.png"),
        plots.plot_visibility_deployment(model, visibility_deployment(model, b, 4),
                                         tmp_path / "visibility.png"),
        plots.plot_reachability(model, persistent_reachability(model, int(b.groups[0][0])),
                                tmp_path / "reach.png"),
        plots.plot_policy(model, value_iteration(model, goal), tmp_path / "policy.png"),
        plots.plot_paths(model, {"a": np.stack([np.column_stack(model.centre(dep.states))] * 3),
                                 "b": np.zeros((1, 1, 2))}, tmp_path / "paths.png", goal=[goal]),
        plots.plot_coverage_curves([0, 1, 2], {"a": stats.mean_band([[0.1, 0.2, 0.3],
                                                                     [0.1, 0.3, 0.4]])},
                                   tmp_path / "coverage.png", predicted={"a": 0.33}),
    ]
    for path in written:
        with Image.open(path) as image:
            assert image.format == "PNG" and min(image.size) > 200
            assert np.asarray(image).std() > 0  # something was drawn
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in written)
