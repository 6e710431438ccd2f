"""The suite's own set-up (tests/conftest.py, the Makefile's test targets): parallel workers with
their own homes and a shared model cache, the slowest tests listed, the time budget in sight."""

import os
import re
import subprocess
import sys
from pathlib import Path

from bounce_gym.model_cache import CACHE_VARIABLE, cache_folder
from bounce_gym.trust import HOME_VARIABLE, home

ROOT = Path(__file__).resolve().parents[1]


def test_both_test_targets_run_on_workers_and_list_their_slowest_tests():
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    (run,) = re.findall(r"^PYTEST_RUN = (.*)$", makefile, flags=re.MULTILINE)
    assert "-n $(PYTEST_WORKERS)" in run and "--durations=20" in run
    assert re.search(r"^PYTEST_WORKERS \?= auto$", makefile, flags=re.MULTILINE)
    for target, mark in (("test", '-m "$(PYTEST_MARK)"'), ("test-slow", "-m slow")):
        (recipe,) = re.findall(rf"^{target}: .*\n\t(.*)$", makefile, flags=re.MULTILINE)
        assert f"$(PYTEST_RUN) {mark}" in recipe, target
    dev = (ROOT / "pyproject.toml").read_text(encoding="utf-8").split("\ndev = [", 1)[1]
    assert '"pytest-xdist' in dev.split("]", 1)[0]  # declared where `make install` finds it


def test_the_run_keeps_its_own_home_and_one_shared_cache():
    run = Path(os.environ["BOUNCE_GYM_TEST_RUN"])
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    assert home() == run / f"home-{worker}" == Path(os.environ[HOME_VARIABLE])
    assert home().is_dir() and home().stat().st_mode & 0o077 == 0
    assert cache_folder("x") == run / "cache" / "x" == Path(os.environ[CACHE_VARIABLE]) / "x"
    assert os.environ["JAX_COMPILATION_CACHE_DIR"] == str(run / "jax")


def test_a_run_ends_with_its_wall_time_beside_its_budget():
    """A run of one quick test of this file, as `make test` selects it, in a pytest of its own."""
    env = {k: v for k, v in os.environ.items()
           if k != "BOUNCE_GYM_TEST_RUN" and not k.startswith("PYTEST_XDIST")}
    one = f"{Path(__file__).relative_to(ROOT)}::" \
          "test_both_test_targets_run_on_workers_and_list_their_slowest_tests"
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           "-m", "not slow", one], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    assert re.search(r"this run: \d+\.\d min of wall time on 1 worker\(s\); budget of "
                     r"`-m 'not slow'`: 8 min on the project's 2-core machine\n", done.stdout), \
        done.stdout
