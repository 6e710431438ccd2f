"""Throughput of the functional JAX env against the native NumPy vector env, in one run.

Run with ``python -m benchmarks.jax_env`` (``--steps``, ``--rounds``). Prints a table; asserts
nothing. Issue 26's rows, on ``BounceNavigation-v0`` on the cell backend (angles 45°, 90°, 135°,
goal radius 0.3, heading tolerance 10°: the configuration of `benchmarks.vector_env`'s cell row)
and on the kinematic backend (the registered v0); random actions, episodes ending by goal and by
time, so resets included:

* env-steps/s of the JAX env (`bounce_gym.jax.make`; ``jax.jit`` of a ``lax.scan`` over steps of
  ``jax.vmap(env.step)``, one key per env and step as the gymnax convention asks) ÷ the native
  vector env (``gym.make_vec(..., vectorization_mode="vector_entry_point")``), both with the
  same random actions drawn beforehand, at
  N = 1, 64 and 1,024 envs (targets, issue 39: ≥ 10 at N = 64, ≥ 3 at N = 1,024), also on a
  generated map (``random_grid``, seed 7, 9 × 12: a map nobody tuned for);
* on the cell backend, both against the **bare lookup** — the native env's own tables of the
  bump-to-bump map (`bounce_gym.envs.vector_cells.CellRobots`: next cell of (cell, action)),
  gathered for the batch with nothing else: native ÷ bare (target ≥ 1/10 at N = 1,024) and
  JAX ÷ bare (target ≥ 1/3 at N = 1,024);
* the JAX env of ``BounceNavigation-v1`` (the lab and the generated map), reported: there is no
  native NumPy vector env of v1 to compare it with;
* every JAX row twice: with JAX's default keys (threefry) and, as "JAX rbg", with keys of
  ``jax.random.key(seed, impl="unsafe_rbg")`` — the loop splits one key per env and step, and
  on a CPU threefry's hashing of those keys costs more than the cell env's step itself;
* the **floor of the vector API** on the cell envs (`floor_steps`: a fresh copy of every array a
  native step returns, computing nothing), against the bare lookup and under the native env:
  what any env with Gymnasium's vector API and these observations and infos costs at least.

Both run on one CPU thread (`benchmarks.one_core`; NumPy's loops are single-threaded). The
JAX function is compiled before timing. The envs are built once and interleaved: each round
times every env in turn, so the load of a shared machine hits all alike; each ratio is taken
within a round, and the table gives its median and min–max over the rounds, with the one-minute
load average before and after.
"""

from __future__ import annotations  # noqa: I001  (one_core must come before jax)

import argparse
import itertools
import os
import statistics
import time
from collections.abc import Callable

from benchmarks import one_core  # before jax

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np

import bounce_gym  # noqa: F401  (registers the environments)
from benchmarks.rounds import interleaved, ratio, spread, verdict
from benchmarks.vector_env import CELL_NAVIGATION
from bounce_gym.jax import make
from bounce_gym.worlds.generators import random_grid

#: how many times more steps the JAX env runs per round than the native one
JAX_MORE = 10
#: a map nobody tuned the envs for
GENERATED = random_grid(np.random.default_rng(7), 9, 12, 6, 3)
#: the envs with a native vector env: label -> (id, keyword arguments); the kinematic one is
#: the registered v0
ENVS = {"cell": CELL_NAVIGATION,
        "cell generated": (CELL_NAVIGATION[0], {**CELL_NAVIGATION[1], "world": GENERATED}),
        "kinematic": ("bounce_gym/BounceNavigation-v0", {})}
#: the cell envs, whose bare lookup anchors the rows against it
CELL_ENVS = ("cell", "cell generated")
#: the JAX envs without a native vector env (reported)
JAX_ONLY = {"v1": ("bounce_gym/BounceNavigation-v1", {}),
            "v1 generated": ("bounce_gym/BounceNavigation-v1", {"world": GENERATED})}
#: the batch sizes, and the target of the JAX ÷ native ratio at each (None: reported)
SIZES = {1: None, 64: 10.0, 1024: 3.0}
#: the targets of the ratios against the bare lookup, at N = 1,024
BARE_TARGETS = {"native": 1 / 10, "JAX": 1 / 3}
#: the rows against the bare lookup (the JAX env with either kind of key, and the floor of
#: the vector API: `floor_steps`)
BARE_SIDES = ("native", "JAX", "JAX rbg", "API floor")
#: the cheaper PRNG of the "JAX rbg" rows: the caller's keys, split per env and step, cost most
#: of a cell step with JAX's default threefry keys on a CPU
FAST_KEYS = "unsafe_rbg"


def jax_steps(n: int, steps: int, env_id: str, kwargs: dict,
              impl: str = "threefry2x32") -> Callable[[], float]:
    """Env-steps/s of ``steps`` steps of N vmapped JAX envs (compiled before the first call),
    with keys of JAX's PRNG implementation ``impl``."""
    env, params = make(env_id, **kwargs)
    batch_step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

    actions = jnp.asarray(np.random.default_rng(1).integers(0, env.num_actions, (steps, n)),
                          jnp.int32)

    @jax.jit
    def run(key, state):
        def body(carry, row):
            key, state = carry
            key, step_key = jax.random.split(key)
            _, state, reward, done, _ = batch_step(jax.random.split(step_key, n), state, row,
                                                   params)
            return (key, state), reward.sum() + done.sum()

        (key, state), total = jax.lax.scan(body, (key, state), actions)
        return key, state, total.sum()

    _, state = jax.vmap(env.reset, in_axes=(0, None))(
        jax.random.split(jax.random.key(0, impl=impl), n), params)
    carry = run(jax.random.key(1, impl=impl), state)  # compiles
    jax.block_until_ready(carry)

    def rate() -> float:
        nonlocal carry
        start = time.perf_counter()
        carry = jax.block_until_ready(run(carry[0], carry[1]))
        return n * steps / (time.perf_counter() - start)

    return rate


def native_steps(n: int, steps: int, env_id: str, kwargs: dict) -> Callable[[], float]:
    """Env-steps/s of ``steps`` steps of the native NumPy vector env with N envs."""
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    env.reset(seed=0)
    actions = np.random.default_rng(1).integers(0, env.single_action_space.n, (steps, n))

    def rate() -> float:
        start = time.perf_counter()
        for row in actions:
            env.step(row)
        return n * steps / (time.perf_counter() - start)

    return rate


def bare_steps(n: int, steps: int, env_id: str, kwargs: dict) -> Callable[[], float]:
    """Lookups/s of the bare bump-to-bump map of the native env's cell robots: per step, the
    next cell of each robot's (cell, action), gathered for the batch (`CellRobots.bounce`'s
    first two ``take``s), nothing else."""
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    env.reset(seed=0)
    robots = env.unwrapped.cell_robots
    ends, ticks, width = robots.step_end, robots.step_ticks, robots.n_actions
    actions = np.random.default_rng(1).integers(0, width, (steps, n))
    z = robots.z.copy()

    def rate() -> float:
        nonlocal z
        start = time.perf_counter()
        for row in actions:
            at = z * width + row
            ticks.take(at)
            z = ends.take(at)
        return n * steps / (time.perf_counter() - start)

    return rate


def floor_steps(n: int, steps: int, env_id: str, kwargs: dict) -> Callable[[], float]:
    """Env-steps/s of the floor of Gymnasium's vector API for the native env: per step, a fresh
    copy of every array one of its steps returns (observation, reward, flags, each info and
    mask), computing nothing."""
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    env.reset(seed=0)
    obs, reward, terminated, truncated, infos = env.step(
        np.zeros(n, dtype=np.int64))
    arrays = [obs, reward, terminated, truncated, *infos.values()]

    def rate() -> float:
        start = time.perf_counter()
        for _ in range(steps):
            for array in arrays:
                array.copy()
        return n * steps / (time.perf_counter() - start)

    return rate


def measure(steps: int, rounds: int, sizes: dict) -> dict[str, list[float]]:
    """Env-steps/s of every env and size in every round, interleaved within each round; the
    native env runs about ``steps`` × 64 env-steps per size (at least ``steps`` steps of the
    batch), the JAX env `JAX_MORE` times as many (so that its timings, too, last milliseconds
    rather than microseconds)."""
    runs = {}
    for label, (env_id, kwargs) in (*ENVS.items(), *JAX_ONLY.items()):
        for n in sizes:
            batch_steps = max(steps * 64 // n, steps)
            runs[f"{label} JAX N={n}"] = jax_steps(n, JAX_MORE * batch_steps, env_id, kwargs)
            runs[f"{label} JAX rbg N={n}"] = jax_steps(n, JAX_MORE * batch_steps, env_id, kwargs,
                                                       impl=FAST_KEYS)
            if label in ENVS:
                runs[f"{label} native N={n}"] = native_steps(n, batch_steps, env_id, kwargs)
            if label in CELL_ENVS:
                runs[f"{label} bare N={n}"] = bare_steps(n, JAX_MORE * batch_steps, env_id,
                                                         kwargs)
                runs[f"{label} API floor N={n}"] = floor_steps(n, batch_steps, env_id, kwargs)
    return interleaved(runs, rounds)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200,
                        help="batch steps at N = 64 per round (N = 1 runs 64× more)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES),
                        help="batch sizes N (e.g. 65536 on a GPU)")
    args = parser.parse_args(argv)
    sizes = {n: SIZES.get(n) for n in args.sizes}
    load_before = os.getloadavg()[0]
    rates = measure(args.steps, args.rounds, sizes)
    load_after = os.getloadavg()[0]
    threads = "one XLA thread" if one_core.PINNED else "XLA threads NOT pinned (jax imported first)"
    print(f"JAX env (issues 26, 39): {args.rounds} rounds, interleaved; {threads}; load average "
          f"{load_before:.1f} before, {load_after:.1f} after, {os.cpu_count()} cores; "
          f"device {jax.devices()[0].device_kind}")
    print(f"{'environment':<30} {'env-steps/s':>14} {'min–max':>24}")
    for label, values in rates.items():
        print(f"{label:<30} {statistics.median(values):>14,.0f} {spread(values, ',.0f'):>24}")
    print(f"{'ratio (within a round)':<46} {'median':>8} {'min–max':>15} {'target':>7}")
    ratios = {}
    rows = [(f"{label}: JAX{keys} ÷ native, N={n}", f"{label} JAX{keys} N={n}",
             f"{label} native N={n}", sizes[n])
            for label, n, keys in itertools.product(ENVS, sizes, ("", " rbg"))]
    rows += [(f"{label}: {side} ÷ bare lookup, N={n}", f"{label} {side} N={n}",
              f"{label} bare N={n}", BARE_TARGETS.get(side.split()[0]) if n == 1024 else None)
             for label, n, side in itertools.product(CELL_ENVS, sizes, BARE_SIDES)]
    rows += [(f"{label}: native ÷ API floor, N={n}", f"{label} native N={n}",
              f"{label} API floor N={n}", None) for label, n in itertools.product(CELL_ENVS, sizes)]
    for name, top, bottom, target in rows:
        per_round = [a / b for a, b in zip(rates[top], rates[bottom], strict=True)]
        row = ratios[name] = ratio(per_round, target)
        goal = "-" if target is None else f"≥ {target:.3g}"
        print(f"{name:<46} {row['median']:>8.3f} {spread(per_round, '.3f'):>15} {goal:>7}"
              f"{verdict(row)}", flush=True)
    return dict(rates=rates, ratios=ratios, load=(load_before, load_after))


if __name__ == "__main__":
    main()
