"""The spaces of the functional envs, in the gymnax convention: ``sample(key)`` draws with a JAX
key, ``contains(x)`` checks a value, and `to_gymnasium` gives the equal Gymnasium space (what an
adapter or a test compares with the NumPy env's).

gymnax itself is not a dependency: it pulls in flax, matplotlib and seaborn for what are three
small classes here.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
from gymnasium import spaces as gym_spaces


@dataclass(frozen=True)
class Discrete:
    """Actions 0 … n − 1."""

    n: int
    dtype: object = jnp.int32

    @property
    def shape(self) -> tuple:
        return ()

    def sample(self, key: jax.Array) -> jax.Array:
        return jax.random.randint(key, (), 0, self.n, dtype=self.dtype)

    def contains(self, x) -> jax.Array:
        x = jnp.asarray(x)
        return (x.shape == ()) & (x >= 0) & (x < self.n)

    def to_gymnasium(self) -> gym_spaces.Discrete:
        return gym_spaces.Discrete(self.n)


@dataclass(frozen=True)
class Box:
    """A float32 array of ``shape`` with bounds ``low`` and ``high`` (NumPy arrays)."""

    low: np.ndarray
    high: np.ndarray

    @property
    def shape(self) -> tuple:
        return tuple(np.shape(self.low))

    @property
    def dtype(self):
        return jnp.float32

    def sample(self, key: jax.Array) -> jax.Array:
        return jax.random.uniform(key, self.shape, jnp.float32, self.low, self.high)

    def contains(self, x) -> jax.Array:
        x = jnp.asarray(x)
        return (x.shape == self.shape) & jnp.all((x >= self.low) & (x <= self.high))

    def to_gymnasium(self) -> gym_spaces.Box:
        return gym_spaces.Box(np.asarray(self.low, np.float32), np.asarray(self.high, np.float32),
                              dtype=np.float32)


@dataclass(frozen=True)
class Dict:
    """Named subspaces (the goal-conditioned observation)."""

    spaces: dict

    @property
    def shape(self) -> None:
        return None

    def sample(self, key: jax.Array) -> dict:
        keys = jax.random.split(key, len(self.spaces))
        return {name: space.sample(k) for (name, space), k in zip(self.spaces.items(), keys,
                                                                   strict=True)}

    def contains(self, x) -> jax.Array:
        ok = jnp.bool_(set(x) == set(self.spaces))
        for name, space in self.spaces.items():
            ok = ok & space.contains(x[name])
        return ok

    def to_gymnasium(self) -> gym_spaces.Dict:
        return gym_spaces.Dict({name: space.to_gymnasium() for name, space in self.spaces.items()})
