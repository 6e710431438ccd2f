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
  N = 1, 64 and 1,024 envs (targets: ≥ 10 at N = 64, ≥ 1 at N = 1,024).

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

#: how many times more steps the JAX env runs per round than the native one
JAX_MORE = 10
#: the envs: label -> (id, keyword arguments); the kinematic one is the registered v0
ENVS = {"cell": CELL_NAVIGATION, "kinematic": ("bounce_gym/BounceNavigation-v0", {})}
#: the batch sizes, and the target of the JAX ÷ native ratio at each (None: reported)
SIZES = {1: None, 64: 10.0, 1024: 1.0}


def jax_steps(n: int, steps: int, env_id: str, kwargs: dict) -> Callable[[], float]:
    """Env-steps/s of ``steps`` steps of N vmapped JAX envs (compiled before the first call)."""
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
        jax.random.split(jax.random.PRNGKey(0), n), params)
    carry = run(jax.random.PRNGKey(1), state)  # compiles
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


def measure(steps: int, rounds: int, sizes: dict) -> dict[str, list[float]]:
    """Env-steps/s of every env and size in every round, interleaved within each round; the
    native env runs about ``steps`` × 64 env-steps per size (at least ``steps`` steps of the
    batch), the JAX env `JAX_MORE` times as many (so that its timings, too, last milliseconds
    rather than microseconds)."""
    runs = {}
    for label, (env_id, kwargs) in ENVS.items():
        for n in sizes:
            batch_steps = max(steps * 64 // n, steps)
            runs[f"{label} JAX N={n}"] = jax_steps(n, JAX_MORE * batch_steps, env_id, kwargs)
            runs[f"{label} native N={n}"] = native_steps(n, batch_steps, env_id, kwargs)
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
    print(f"JAX env (issue 26): {args.rounds} rounds, interleaved; {threads}; load average "
          f"{load_before:.1f} before, {load_after:.1f} after, {os.cpu_count()} cores; "
          f"device {jax.devices()[0].device_kind}")
    print(f"{'environment':<26} {'env-steps/s':>14} {'min–max':>24}")
    for label, values in rates.items():
        print(f"{label:<26} {statistics.median(values):>14,.0f} {spread(values, ',.0f'):>24}")
    print(f"{'ratio (within a round)':<38} {'median':>8} {'min–max':>15} {'target':>7}")
    ratios = {}
    for label, n in itertools.product(ENVS, sizes):
        name, target = f"{label}: JAX ÷ native, N={n}", sizes[n]
        per_round = [a / b for a, b in zip(rates[f"{label} JAX N={n}"],
                                           rates[f"{label} native N={n}"], strict=True)]
        row = ratios[name] = ratio(per_round, target)
        goal = "-" if target is None else f"≥ {target:g}"
        print(f"{name:<38} {row['median']:>8.2f} {spread(per_round, '.2f'):>15} {goal:>7}"
              f"{verdict(row)}", flush=True)
    return dict(rates=rates, ratios=ratios, load=(load_before, load_after))


if __name__ == "__main__":
    main()
