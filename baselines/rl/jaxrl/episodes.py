"""Per-env episode bookkeeping inside a jitted loop: the running return and length of every
env's episode, and for every step a record of the episodes that ended at it — what the monitor
file gets one row each of (`baselines.rl.monitor`)."""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp


class Running(NamedTuple):
    """The return and length so far of each env's episode."""

    ret: jax.Array  # (n_envs,) float32
    length: jax.Array  # (n_envs,) int32


def start(n_envs: int) -> Running:
    return Running(jnp.zeros((n_envs,), jnp.float32), jnp.zeros((n_envs,), jnp.int32))


def track(running: Running, reward: jax.Array, done: jax.Array, info: dict,
          keys: tuple[str, ...]) -> tuple[Running, dict]:
    """The bookkeeping after one step of every env, and its record: ``done``, the episode's
    return ``r`` and length ``l`` (meaningful where ``done``) and the outcome ``keys`` of
    ``info`` (the monitor's extra columns)."""
    ret = running.ret + reward.astype(jnp.float32)
    length = running.length + 1
    record = {"done": done, "r": ret, "l": length, **{k: info[k] for k in keys}}
    return Running(jnp.where(done, 0.0, ret), jnp.where(done, 0, length)), record

