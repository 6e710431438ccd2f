"""A replay buffer of device arrays, with hindsight relabelling for goal-conditioned envs.

Like Stable-Baselines3's buffers it keeps ``buffer_size // n_envs`` transitions per env in a
ring (all envs write at the same slot each step). Every transition knows how many steps later
its episode ended (``to_end``, written for the whole episode when it ends; episodes are at most
the env's horizon long), so that the "future" strategy of hindsight experience replay
(Andrychowicz et al. 2017, Sec. 4.5) can relabel it: with probability ``her_ratio`` =
1 − 1/(k + 1) (k relabelled goals per real one, SB3's ``n_sampled_goal``) the goal becomes the
pose achieved at a step drawn uniformly from this one to the episode's end, and the reward is
the env's ``compute_reward`` of that goal. As in SB3, only transitions of finished episodes are
sampled when relabelling, and the stored termination flag is kept.

A goal-conditioned observation is stored in parts: ``observation``, and the one-hot
``achieved_goal`` (before and after) and ``desired_goal`` as uint8 (their entries are 0 or 1).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp


class Buffer(NamedTuple):
    data: dict  # name -> (n_envs, capacity, ...)
    to_end: jax.Array  # (n_envs, capacity) steps to the episode's last transition; -1 open
    pos: jax.Array  # the slot written next
    count: jax.Array  # slots filled (at most capacity)
    length: jax.Array  # (n_envs,) transitions of each env's open episode


def create(example: dict, capacity: int) -> Buffer:
    """An empty buffer for transitions shaped like ``example`` (one entry per env)."""
    n_envs = next(iter(example.values())).shape[0]
    data = {k: jnp.zeros((n_envs, capacity, *v.shape[1:]), v.dtype) for k, v in example.items()}
    return Buffer(data, jnp.full((n_envs, capacity), -1, jnp.int32), jnp.int32(0), jnp.int32(0),
                  jnp.zeros((n_envs,), jnp.int32))


def add(buffer: Buffer, transition: dict, done: jax.Array, horizon: int) -> Buffer:
    """The buffer with one transition per env written; where ``done`` the env's episode (at most
    ``horizon`` transitions) is closed: each of its transitions learns its ``to_end``."""
    capacity = buffer.to_end.shape[1]
    pos = buffer.pos
    data = {k: v.at[:, pos].set(transition[k]) for k, v in buffer.data.items()}
    to_end = buffer.to_end.at[:, pos].set(-1)
    length = buffer.length + 1
    back = jnp.arange(horizon)
    slots = (pos - back) % capacity
    close = done[:, None] & (back[None, :] < length[:, None])
    to_end = to_end.at[:, slots].set(jnp.where(close, back[None, :], to_end[:, slots]))
    return Buffer(data, to_end, (pos + 1) % capacity, jnp.minimum(buffer.count + 1, capacity),
                  jnp.where(done, 0, length))


def _finished(buffer: Buffer, closed_only: bool) -> jax.Array:
    """(n_envs,) how many transitions of each env may be sampled: all stored ones, or with
    ``closed_only`` those of finished episodes."""
    return buffer.count - (buffer.length if closed_only else 0)


def ready(buffer: Buffer, closed_only: bool) -> jax.Array:
    """Whether there is anything to sample."""
    return _finished(buffer, closed_only).sum() > 0


def sample_transitions(buffer: Buffer, key: jax.Array, size: int, closed_only: bool) -> tuple:
    """``(env, slot)`` index arrays of ``size`` transitions drawn uniformly among those that may
    be sampled (`ready` must hold)."""
    capacity = buffer.to_end.shape[1]
    valid = _finished(buffer, closed_only)
    ends = jnp.cumsum(valid)
    u = jax.random.randint(key, (size,), 0, jnp.maximum(ends[-1], 1))
    env = jnp.searchsorted(ends, u, side="right")
    back = (buffer.length[env] if closed_only else 0) + u - (ends - valid)[env]
    return env, (buffer.pos - 1 - back) % capacity


def relabelled_goals(buffer: Buffer, key: jax.Array, env: jax.Array, slot: jax.Array,
                     her_ratio: float) -> jax.Array:
    """The goals of the sampled transitions: with probability ``her_ratio`` the achieved goal
    after a step drawn uniformly from the transition's own to its episode's last, else the
    stored one (float32 one-hots)."""
    capacity = buffer.to_end.shape[1]
    k_which, k_future = jax.random.split(key)
    relabel = jax.random.uniform(k_which, env.shape) < her_ratio
    offset = jax.random.randint(k_future, env.shape, 0, buffer.to_end[env, slot] + 1)
    future = buffer.data["next_achieved_goal"][env, (slot + offset) % capacity]
    goal = jnp.where(relabel[:, None], future, buffer.data["desired_goal"][env, slot])
    return goal.astype(jnp.float32)
