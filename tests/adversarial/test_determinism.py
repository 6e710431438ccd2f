"""Same seed, same trajectory — in this process, in a fresh interpreter and in a spawned worker,
for every bounce rule. The worker gets only the seed and builds the dynamics itself, so nothing
needs to pickle; pickling the dynamics is checked separately."""

import multiprocessing
import pickle
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from bounce_adversarial import RULE_NAMES, make_dynamics, make_world, trajectory_digest

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
CASES = [(rule, backend) for rule in RULE_NAMES
         for backend in ("kinematic", "pymunk", "dynamic")] + [("relative", "cell")]


@pytest.fixture(scope="module")
def digests() -> dict:
    return {case: trajectory_digest(case[0], 7, backend=case[1]) for case in CASES}


def test_same_seed_same_trajectory_here(digests):
    for rule, backend in CASES:
        assert trajectory_digest(rule, 7, backend=backend) == digests[rule, backend]
    assert trajectory_digest("relative", 8) != digests["relative", "kinematic"]
    # two robots on one backend: the joint state too
    assert trajectory_digest("fixed", 7, n_robots=3) == trajectory_digest("fixed", 7, n_robots=3)


@pytest.mark.timeout(180)
def test_fresh_interpreter_gives_the_same_trajectories(digests):
    code = (f"import sys; sys.path[:0] = [{str(ROOT)!r}, {str(HERE)!r}]\n"
            "from bounce_adversarial import trajectory_digest\n"
            f"for rule, backend in {CASES!r}:\n"
            "    print(trajectory_digest(rule, 7, backend=backend))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT)
    assert out.stdout.split() == [digests[case] for case in CASES]


@pytest.mark.timeout(180)
def test_spawned_worker_gives_the_same_trajectories(digests):
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=1, mp_context=context) as pool:
        futures = {case: pool.submit(trajectory_digest, case[0], 7, backend=case[1])
                   for case in CASES}
        got = {case: future.result(timeout=150) for case, future in futures.items()}
    assert got == digests


@pytest.mark.parametrize("backend", ["kinematic", "dynamic"])
@pytest.mark.parametrize("rule", RULE_NAMES)
def test_pickled_dynamics_continue_identically(rule, backend):
    world = make_world("holes", 0, 100.0, 1e6)
    radius = 0.002 * world.diameter if backend == "dynamic" else 0.0
    dyn = make_dynamics(world, backend, rule, "reliable", radius, world.diameter / 40)
    dyn.reset(np.random.default_rng(3))
    dyn.drive_to_contact()
    copy = pickle.loads(pickle.dumps(dyn))
    params = np.random.default_rng(4).uniform(0.2, 2.9, 100)
    for phi in params:
        dyn.bounce(phi)
        copy.bounce(phi)
    np.testing.assert_array_equal(copy.state.position, dyn.state.position)
    np.testing.assert_array_equal(copy.state.clock, dyn.state.clock)
