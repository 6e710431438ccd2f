"""`BounceEnv`'s lean single-robot step (`BounceCore.step_one`) reports exactly what the general
m-robot step (`BounceCore.step`, unpacked for one robot) reports: observation, reward,
termination and every info key, step after step."""

import numpy as np
import pytest

from bounce_gym.envs.actions import to_angle
from bounce_gym.envs.bounce_env import BounceEnv, _single

CASES = [
    dict(backend="kinematic"),
    dict(backend="pymunk", robot_radius=0.2),
    dict(backend="cell"),
    dict(backend="kinematic", step_mode="tick", history=3),
    dict(backend="cell", step_mode="tick", privileged=True),
    dict(backend="kinematic", action_type="continuous", angle_range=[20, 340]),
    dict(backend="kinematic", noise={"type": "reliable", "r": 0.8, "eps_deg": 5}),
    dict(task="navigation", world="lab_navigation", backend="cell", history=2),
    dict(task="navigation", world="lab_navigation", backend="pymunk", privileged=True),
    dict(task="coverage", world="lab_fig1", backend="kinematic"),
    dict(task="coverage", world="lab_fig1", backend="cell", step_mode="tick"),
    dict(task="localization", world="lab_localization_a", backend="cell", angles=[45],
         task_kwargs={"filter_factory": "combinatorial"}),
]


def _same(a, b) -> None:
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            _same(a[key], b[key])
    elif isinstance(a, np.ndarray | list | tuple):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    else:
        assert a == b or (a != a and b != b)  # NaN == NaN here


@pytest.mark.parametrize("kwargs", CASES, ids=lambda k: "-".join(f"{v}" for v in k.values()))
def test_lean_step_reports_what_the_general_step_reports(kwargs):
    lean, general = BounceEnv(**kwargs), BounceEnv(**kwargs)
    lean.reset(seed=5)
    general.reset(seed=5)
    rng = np.random.default_rng(9)
    for _ in range(120):
        if kwargs.get("action_type") == "continuous":
            action = rng.uniform(-1, 1, 1).astype(np.float32)
        else:
            action = int(rng.integers(lean.action_space.n))
        obs, reward, terminated, _, info = lean.step(action)
        angle = to_angle(action, general.options.action_type, general.options.angles[0],
                         general.options.angle_range[0])
        g_obs, g_rewards, g_terminated, g_info = general.core.step(np.array([angle]))
        assert obs.dtype == g_obs.dtype
        np.testing.assert_array_equal(obs, g_obs[0])
        assert reward == float(g_rewards[0])
        assert terminated == bool(g_terminated[0])
        _same(info, _single(g_info))
        if terminated:
            break
