"""Every script in ``examples/`` runs with a small budget, writes the files it announces into
its ``--out`` folder, and writes nothing into the checkout."""

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
#: script -> (modules it needs beyond the core dependencies, small-budget arguments, the files
#: it announces under ``--out``, as paths relative to it)
EXAMPLES = {
    "jax_ppo_navigation.py": (("jax", "optax"), ["--steps", "2048", "--episodes", "5"],
                              ["jax-ppo-example/jax_ppo_seed0.zip"]),
    "sb3_native_vector_env.py": (("stable_baselines3",), ["--steps", "1024", "--episodes", "5"],
                                 ["ppo_navigation.zip"]),
    "pettingzoo_rollout_gif.py": ((), ["--steps", "20"], ["multi_coverage.gif"]),
    "drifter_from_netcdf.py": ((), ["--episodes", "10"], ["channel.nc"]),
    "planners_on_custom_map.py": ((), ["--episodes", "10", "--samples", "100"], ["l_room.yaml"]),
}


def _checkout_state() -> str:
    """Everything git sees in the checkout, ignored files included."""
    return subprocess.run(["git", "status", "--porcelain", "--ignored", "--untracked-files=all"],
                          cwd=ROOT, capture_output=True, text=True, check=True).stdout


def test_every_example_is_listed():
    assert sorted(p.name for p in (ROOT / "examples").glob("*.py")) == sorted(EXAMPLES)


@pytest.mark.parametrize("script", sorted(EXAMPLES))
def test_example_runs_into_its_out_folder(script, tmp_path):
    needs, args, files = EXAMPLES[script]
    for module in needs:
        if importlib.util.find_spec(module) is None:
            pytest.skip(f"{script} needs {module}")
    args = [*args, "--out", str(tmp_path)]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONDONTWRITEBYTECODE": "1",
           "SDL_VIDEODRIVER": "dummy", "MPLBACKEND": "Agg"}
    before = _checkout_state()
    done = subprocess.run([sys.executable, str(ROOT / "examples" / script), *args], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert _checkout_state() == before
    # nothing else at the top of --out (a training run writes its folder, with more files)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted({f.split("/")[0] for f in files})
    assert all((tmp_path / name).stat().st_size > 0 for name in files)
    assert str(tmp_path) in done.stdout  # the folder is named at the end


def test_default_out_is_a_fresh_temporary_folder():
    """Without ``--out`` an example writes into a new temporary folder and names it."""
    done = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "planners_on_custom_map.py"), "--episodes", "2",
         "--samples", "10"], cwd=ROOT, capture_output=True, text=True, timeout=600,
        env={**os.environ, "PYTHONPATH": str(ROOT), "PYTHONDONTWRITEBYTECODE": "1"})
    assert done.returncode == 0, done.stderr[-3000:]
    written = Path(done.stdout.split("map file written to ")[-1].strip())
    try:
        assert written.is_file() and ROOT not in written.parents
    finally:
        written.unlink(missing_ok=True)
        written.parent.rmdir()
