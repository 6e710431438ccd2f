"""docs/continuous_models.md: its figure script runs (the documented command, verbatim) and
draws the same figure twice, and its table of physical defaults is `PhysicsParams`'."""

import importlib.util
import math
import os
import re
import subprocess
import sys
from dataclasses import fields
from pathlib import Path

import pytest

from bounce_gym.dynamics.platform import PLATFORM_RADIUS, PhysicsParams

ROOT = Path(__file__).parents[1]
PAGE = (ROOT / "docs" / "continuous_models.md").read_text(encoding="utf-8")
SCRIPT = ROOT / "docs" / "make_model_figures.py"
PNG = b"\x89PNG\r\n\x1a\n"


def _script():
    spec = importlib.util.spec_from_file_location("make_model_figures", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_documented_command_writes_the_figure(tmp_path):
    """Run as written in the page, from a folder laid out like the repository root (so the
    committed figure is left alone)."""
    commands = re.findall(r"```bash\n(python docs/make_model_figures\.py [^\n`]*)\n```", PAGE)
    assert commands == ["python docs/make_model_figures.py docs/continuous_models.png"]
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / SCRIPT.name).symlink_to(SCRIPT)
    words = commands[0].split()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, *words[1:]], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    written = tmp_path / "docs" / "continuous_models.png"
    assert written.read_bytes()[:8] == PNG
    assert sorted(p.name for p in (tmp_path / "docs").iterdir()) == [
        "continuous_models.png", SCRIPT.name]


def test_a_short_figure_is_deterministic(tmp_path):
    script = _script()
    first, second = tmp_path / "a" / "models.png", tmp_path / "models.png"
    script.main([str(first), "--bounces", "3"])
    script.main([str(second), "--bounces", "3"])
    assert first.read_bytes()[:8] == PNG
    assert first.read_bytes() == second.read_bytes()


def test_the_two_ideal_models_agree_and_the_dynamic_limit_converges():
    """What the page says of the figure's runs, on a few bounces."""
    script = _script()
    actions = script.np.random.default_rng(script.ACTION_SEED).integers(3, size=6)
    runs = {name: script.run(kwargs, actions) for name, kwargs in script.MODELS.items()}
    (kinematic, ticks), (ideal, ideal_ticks) = runs["kinematic"], runs["pymunk, physics='ideal'"]
    limit, limit_ticks = runs["pymunk, physics='dynamic', ideal limit"]
    dynamic, dynamic_ticks = runs["pymunk, physics='dynamic'"]
    assert (ideal == kinematic).all() and ideal_ticks == ticks
    assert abs(limit - kinematic).max() < 1e-5 and limit_ticks == ticks
    assert abs(dynamic - kinematic).max() > 1e-3 and dynamic_ticks > ticks


def test_a_bad_bounce_count_is_refused(tmp_path):
    with pytest.raises(SystemExit) as exit_:
        _script().main([str(tmp_path / "x.png"), "--bounces", "0"])
    assert exit_.value.code == 2
    assert not (tmp_path / "x.png").exists()


def test_the_defaults_table_is_physics_params():
    """Every row of the table names a `PhysicsParams` field (or ``robot_radius``) and gives
    its default; every field has a row."""
    rows = dict(re.findall(r"^\| `(\w+)`(?: \(env argument\))? \| ([-\d.]+)", PAGE, re.M))
    defaults = {f.name: getattr(PhysicsParams(), f.name) for f in fields(PhysicsParams)}
    defaults["robot_radius"] = PLATFORM_RADIUS
    assert set(rows) == set(defaults)
    for name, value in rows.items():
        assert math.isclose(float(value), defaults[name], rel_tol=5e-3), name
