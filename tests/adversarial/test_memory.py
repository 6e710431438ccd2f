"""Memory stays flat over 10,000 resets for the envs tests/envs/test_bounce_env.py does not
cover there: the multi-robot envs (parallel and AEC) on every backend and the single-robot env
on the cell backend. The same two measures as there: live pymalloc blocks over the untraced
resets, then bytes retained over a traced window of a tenth as many."""

import gc
import sys
import tracemalloc

import pytest

from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceAEC, MultiBounceEnv


def _envs(kind: str, backend: str) -> list:
    if kind == "single":  # every single-robot task the cell backend runs
        return [BounceEnv(backend="cell", world=world, task=task)
                for world, task in (("two_rooms", "free"), ("lab_fig1", "coverage"),
                                    ("lab_navigation", "navigation"))]
    cls = MultiBounceEnv if kind == "parallel" else MultiBounceAEC
    extra = {"robot_radius": 0.0} if backend == "cell" else {}
    return [cls(backend=backend, task=task, world=world, **extra)
            for world, task in (("grid_15x15", "free"), ("grid_15x15", "coverage"),
                                ("grid_20x12", "monitoring"))]


SLOW = pytest.mark.slow
#: (env form, backend, resets): 10,000 where a reset is cheap; the multi-robot envs (~3 ms a
#: reset on the continuous backends: four robots placed without overlap; ~1 ms on the cell one)
#: run 2,000 in the quick form, 10,000 slow
CASES = [("parallel", "cell", 2_000), ("single", "cell", 10_000),
         pytest.param("parallel", "cell", 10_000, marks=SLOW),
         ("parallel", "kinematic", 2_000), ("parallel", "pymunk", 2_000), ("aec", "kinematic", 2_000),
         pytest.param("parallel", "kinematic", 10_000, marks=SLOW),
         pytest.param("parallel", "pymunk", 10_000, marks=[SLOW, pytest.mark.long]),
         pytest.param("aec", "kinematic", 10_000, marks=SLOW),
         pytest.param("aec", "pymunk", 10_000, marks=[SLOW, pytest.mark.long])]


@pytest.mark.timeout(600)
@pytest.mark.parametrize(("kind", "backend", "n_resets"), CASES)
def test_memory_flat_over_many_resets(kind, backend, n_resets):
    """< 1,000 blocks more after ``n_resets`` resets (one leaked object per reset would be
    ``n_resets``), and < 100 bytes a reset retained over a traced window."""
    envs = _envs(kind, backend)
    for seed, env in enumerate(envs):
        env.reset(seed=seed)

    def resets(n):
        for k in range(n):
            envs[k % len(envs)].reset()

    resets(n_resets // 10)  # warm-up: caches filled, first-time allocations done
    gc.collect()
    blocks = sys.getallocatedblocks()
    resets(n_resets)
    gc.collect()
    assert sys.getallocatedblocks() - blocks < 1_000

    tracemalloc.start()
    try:
        resets(200)
        gc.collect()
        before = tracemalloc.take_snapshot()
        resets(n_resets // 10)
        gc.collect()
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    growth = sum(stat.size_diff for stat in after.compare_to(before, "filename"))
    assert growth < 100 * n_resets // 10, f"{growth} bytes retained over {n_resets // 10} resets"
