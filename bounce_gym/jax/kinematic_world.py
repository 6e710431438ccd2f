"""Uniform random poses in a world's free space, as pure JAX functions.

The NumPy envs draw a start uniformly from the free space more than the robot's radius (and the
world's tolerance) from the boundary (`World.sample_free`, rejection sampling with as many rounds
as it takes). A jitted function needs a fixed amount of work, so `FreeSpace.sample` draws a fixed
number ``candidates`` of points uniformly in the bounding box at once and keeps the first that
passes the same test as `World.sample_free`'s (inside the polygon, even–odd rule over every ring;
distance to the nearest edge > radius + tol). Each candidate passes with probability p, the share
of the box the robot's centre can occupy, so ``candidates`` is chosen from p such that all miss
with probability at most `MISS` (at most `MAX_CANDIDATES`): the drawn point is then uniform in
the free space but for that probability, with which the draw is the free space's fixed
representative point instead.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

#: the most probability with which every candidate of a draw misses the free space
MISS = 1e-12
#: the most candidates one draw tests
MAX_CANDIDATES = 4096


class FreeSpace(NamedTuple):
    """A world's edges and box, for `inside` and `sample`."""

    start: jax.Array  # (E, 2) edge starts
    vector: jax.Array  # (E, 2) edge vectors
    length2: jax.Array  # (E,) squared edge lengths
    low: jax.Array  # (2,) bounding box corner
    span: jax.Array  # (2,) bounding box size
    clearance: jax.Array  # radius + tol: the least distance to the boundary of a start
    fallback: jax.Array  # (2,) a point of the free space, used where every candidate missed


def free_space(world: World, radius: float, dtype) -> tuple[FreeSpace, int]:
    """The `FreeSpace` of ``world`` for a robot of ``radius`` in float ``dtype``, and the number
    of candidates a draw needs (module docstring)."""
    region = world.eroded(radius)
    xmin, ymin, xmax, ymax = world.bounds
    share = region.area / ((xmax - xmin) * (ymax - ymin))
    if share <= 0:
        raise ConfigError(f"bounce_gym.jax: world {world.name!r} has no free space for a robot "
                          f"of radius {radius}")
    if share >= 1:
        candidates = 1
    else:
        candidates = min(MAX_CANDIDATES, max(1, math.ceil(math.log(MISS) / math.log1p(-share))))
    point = region.representative_point()
    real = lambda values: jnp.asarray(np.asarray(values, dtype=np.float64), dtype)  # noqa: E731
    vector = world.edge_end - world.edge_start
    space = FreeSpace(start=real(world.edge_start), vector=real(vector),
                      length2=real(world.lengths ** 2), low=real([xmin, ymin]),
                      span=real([xmax - xmin, ymax - ymin]), clearance=real(radius + world.tol),
                      fallback=real([point.x, point.y]))
    return space, candidates


def inside(space: FreeSpace, points: jax.Array) -> jax.Array:
    """Whether each point (n, 2) is a valid start: inside the polygon and more than the
    clearance from every edge."""
    start, vector = space.start, space.vector
    rel = points[:, None, :] - start[None]
    along = jnp.clip((rel * vector).sum(axis=2) / space.length2, 0.0, 1.0)
    gap = rel - along[..., None] * vector[None]
    distance = jnp.sqrt(jnp.min((gap * gap).sum(axis=2), axis=1))
    # even–odd rule: the edges a rightward ray from each point crosses
    y0, y1 = start[:, 1], start[:, 1] + vector[:, 1]
    py = points[:, 1:2]
    straddles = (y0 > py) != (y1 > py)
    dy = jnp.where(straddles, vector[:, 1], 1.0)
    x_cross = start[:, 0] + (py - y0) * vector[:, 0] / dy
    crossings = jnp.sum(straddles & (points[:, 0:1] < x_cross), axis=1)
    return (crossings % 2 == 1) & (distance > space.clearance)


def sample(key: jax.Array, space: FreeSpace, candidates: int) -> jax.Array:
    """A uniform point (2,) of the free space (module docstring)."""
    points = space.low + jax.random.uniform(key, (candidates, 2), space.low.dtype) * space.span
    ok = inside(space, points)
    first = jnp.argmax(ok)
    return jnp.where(ok[first], points[first], space.fallback)
