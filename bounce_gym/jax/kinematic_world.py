"""Uniform random poses in a world's free space, as pure JAX functions.

The NumPy envs draw a start uniformly from the free space more than the robot's radius (and the
world's tolerance) from the boundary (`World.sample_free`, rejection sampling with as many rounds
as it takes). A jitted function needs a fixed amount of work, so `sample_free_point` draws a fixed number
``candidates`` of points at once and keeps the first that passes the same test as
`World.sample_free`'s (inside the polygon, even–odd rule over every ring; distance to the nearest
edge > radius + tol). The candidates are uniform in the polygonal C-space `World.eroded` (a
triangle of its triangulation chosen by area, then a uniform point of it, as
`bounce_gym.worlds.world.sample_in` draws), which contains the exact C-space — its arcs about
reflex vertices are cut by chords on the vertex side — so the kept point is uniform in the
exact C-space. A candidate passes with probability p (1 but for the chords' slivers and the
tolerance), estimated once in NumPy from `ESTIMATE` candidates; ``candidates`` is chosen so that
all miss with probability at most `MISS` at a 95 % upper bound of 1 − p (at most
`MAX_CANDIDATES`). With that
probability the draw is the free space's fixed representative point instead.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import shapely

from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World
from bounce_gym.worlds.world import sample_in

#: the most probability with which every candidate of a draw misses the free space
MISS = 1e-12
#: the most candidates one draw tests
MAX_CANDIDATES = 256
#: candidates drawn in NumPy to estimate the share that passes
ESTIMATE = 4096


class FreeSpace(NamedTuple):
    """A world's edges and its C-space's triangles, for `inside` and `sample_free_point`."""

    start: jax.Array  # (E, 2) edge starts
    vector: jax.Array  # (E, 2) edge vectors
    length2: jax.Array  # (E,) squared edge lengths
    corner: jax.Array  # (T, 2) a corner of each triangle of the C-space
    side_b: jax.Array  # (T, 2) its two sides from that corner
    side_c: jax.Array
    cumulative: jax.Array  # (T,) the triangles' cumulative share of the area
    clearance: jax.Array  # radius + tol: the least distance to the boundary of a start
    fallback: jax.Array  # (2,) a point of the free space, used where every candidate missed


def free_space(world: World, radius: float, dtype) -> tuple[FreeSpace, int]:
    """The `FreeSpace` of ``world`` for a robot of ``radius`` in float ``dtype``, and the number
    of candidates a draw needs (module docstring)."""
    region = world.eroded(radius)
    if region.area <= world.tol ** 2:
        raise ConfigError(f"bounce_gym.jax: world {world.name!r} has no free space for a robot "
                          f"of radius {radius}")
    triangles = shapely.get_parts(shapely.constrained_delaunay_triangles(region))
    corners = shapely.get_coordinates(shapely.get_exterior_ring(triangles)).reshape(-1, 4, 2)
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    ab, ac = b - a, c - a
    area = 0.5 * np.abs(ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0])
    cumulative = np.cumsum(area) / area.sum()
    estimate = sample_in(region, np.random.default_rng(0), ESTIMATE)
    passed = shapely.contains_xy(world.polygon, estimate[:, 0], estimate[:, 1])
    passed &= world.boundary_distance(estimate) > radius + world.tol
    # a 95 % upper bound on the share that misses ("rule of three" above the count seen)
    miss = min((ESTIMATE - int(passed.sum()) + 3) / ESTIMATE, 1.0)
    candidates = MAX_CANDIDATES if miss >= 1 else min(
        MAX_CANDIDATES, math.ceil(math.log(MISS) / math.log(miss)))
    point = region.representative_point()
    real = lambda values: jnp.asarray(np.asarray(values, dtype=np.float64), dtype)  # noqa: E731
    vector = world.edge_end - world.edge_start
    space = FreeSpace(start=real(world.edge_start), vector=real(vector),
                      length2=real(world.lengths ** 2), corner=real(a), side_b=real(ab),
                      side_c=real(ac), cumulative=real(cumulative),
                      clearance=real(radius + world.tol), fallback=real([point.x, point.y]))
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


def sample_free_point(uniforms: jax.Array, space: FreeSpace) -> jax.Array:
    """A uniform point (2,) of the free space (module docstring), from 3 × candidates uniforms
    in [0, 1) (drawn with the reset's others in one call: each call costs as much as a cell
    env's step)."""
    pick, u, v = uniforms.reshape(3, -1, 1)
    triangle = jnp.minimum(jnp.searchsorted(space.cumulative, pick[:, 0]),
                           space.cumulative.shape[0] - 1)
    flip = u + v > 1
    u, v = jnp.where(flip, 1 - u, u), jnp.where(flip, 1 - v, v)
    points = (space.corner[triangle] + u * space.side_b[triangle]
              + v * space.side_c[triangle])
    ok = inside(space, points)
    first = jnp.argmax(ok)
    return jnp.where(ok[first], points[first], space.fallback)
