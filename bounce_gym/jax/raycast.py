"""The first wall contact of a swept disk, as a pure JAX function of arrays.

The maths of `bounce_gym.worlds.raycast` (its module docstring has the model): every edge shifted
by the radius along its inward normal, a circle of the radius about every reflex vertex, only
approaching crossings count, grazing is no contact. The edge data are the NumPy query's own
prepared numbers (`bounce_gym.worlds.raycast.features`), so both evaluate the same expressions on
the same inputs: the four edge tests and the time numerator, the winning edge's distance
recomputed directly, the vertex circles, the first minimum in index order on ties.

Under ``jax_enable_x64`` the arithmetic is float64 like NumPy's (distances agree to rounding).
In float32 the world's length tolerance (1e-9 of its diagonal) is below the rounding of a
position, so a robot resting on a wall could find itself a hair behind it and miss it: there
`walls` widens the tolerance to `FLOAT32_TOL_ULPS` float32 epsilons of the world's largest
coordinate (the edge tests, the vertex test, and the env's contact and time tolerances with it).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.worlds import World
from bounce_gym.worlds.raycast import GRAZE, features

#: in float32, the length tolerance in epsilons of the world's largest coordinate
FLOAT32_TOL_ULPS = 64


class Walls(NamedTuple):
    """A world's boundary prepared for disks of one radius (`walls`)."""

    mat: jax.Array  # (6, 5 E): ray row [dx, dy, ox, oy, cross(o, d), 1] -> the edge tests
    ax: jax.Array  # (E,) shifted edge starts
    ay: jax.Array
    ex: jax.Array  # (E,) edge vectors
    ey: jax.Array
    normals: jax.Array  # (E, 2) inward unit normals
    vx: jax.Array  # (V,) reflex vertices (V = 0 for a point robot)
    vy: jax.Array
    vid: jax.Array  # (V,) the edge each vertex starts
    radius: jax.Array
    ttol: jax.Array  # the length tolerance (the world's, or wider in float32: `walls`)


class Hit(NamedTuple):
    """The first contact of one ray: distance (``inf``: none), edge (−1: none; a vertex
    contact names the edge starting there), reflex vertex (−1: an edge) and the unit normal
    pointing into the free space."""

    distance: jax.Array
    edge: jax.Array
    vertex: jax.Array
    normal: jax.Array


def walls(world: World, radius: float, dtype) -> Walls:
    """The `Walls` of ``world`` for disks of ``radius``, in float ``dtype``."""
    f = features(world, radius)
    scale = float(np.max(np.abs(world.bounds)))
    tol = max(f.ttol, FLOAT32_TOL_ULPS * float(jnp.finfo(dtype).eps) * scale)
    mat = f.mat
    if tol > f.ttol:  # the edge tests of `features` with the tolerance widened by ``more``
        more, n = tol - f.ttol, f.n_edges
        mat = mat.copy()
        slack = more / world.lengths * np.stack([f.ey, -f.ex])  # more / length · cross(d, e)
        mat[0:2, n:2 * n] += slack
        mat[0:2, 2 * n:3 * n] += slack
        mat[5, 3 * n:4 * n] += more * world.lengths

    def real(values):
        return jnp.asarray(np.asarray(values, dtype=np.float64), dtype)

    return Walls(mat=real(mat), ax=real(f.ax), ay=real(f.ay), ex=real(f.ex), ey=real(f.ey),
                 normals=real(f.normals), vx=real(f.vx), vy=real(f.vy),
                 vid=jnp.asarray(f.vid, jnp.int32), radius=real(radius), ttol=real(tol))


def cast(w: Walls, origin: jax.Array, direction: jax.Array) -> Hit:
    """The first contact of a disk of radius ``w.radius`` leaving ``origin`` (2,) along the unit
    ``direction`` (2,) (`bounce_gym.worlds.raycast.first_hit_scalar`)."""
    ox, oy = origin[0], origin[1]
    dx, dy = direction[0], direction[1]
    row = (dx, dy, ox, oy, ox * dy - oy * dx, jnp.ones_like(ox))
    q = row[0] * w.mat[0]
    for k in range(1, 6):  # the row-matrix product, spelled out (no reduced-precision matmul)
        q = q + row[k] * w.mat[k]
    q = q.reshape(5, -1)
    ok = jnp.all(q[:4] >= 0.0, axis=0)  # approach >= 1e-12 · length > 0 wherever ok
    t = jnp.where(ok, q[4] / jnp.where(ok, q[0], 1.0), jnp.inf)
    edge = jnp.argmin(t)
    found = jnp.isfinite(t[edge])
    ex, ey = w.ex[edge], w.ey[edge]
    exact = ((w.ax[edge] - ox) * ey - (w.ay[edge] - oy) * ex) / (dx * ey - dy * ex)
    distance = jnp.where(found, exact, jnp.inf)
    normal = w.normals[edge]
    edge = jnp.where(found, edge, -1).astype(jnp.int32)
    vertex = jnp.int32(-1)
    if w.vx.shape[0]:
        cx, cy = ox - w.vx, oy - w.vy
        b = cx * dx + cy * dy
        c = cx * cx + cy * cy - w.radius * w.radius
        disc = b * b - c
        okv = (disc > (GRAZE * w.radius) ** 2) & (b < 0) & (c >= -2.0 * w.radius * w.ttol)
        tv = jnp.where(okv, jnp.maximum(-b - jnp.sqrt(jnp.where(okv, disc, 0.0)), 0.0), jnp.inf)
        kv = jnp.argmin(tv)
        best = tv[kv]
        use = best < distance
        px, py = ox + best * dx - w.vx[kv], oy + best * dy - w.vy[kv]
        norm = jnp.hypot(px, py)
        safe = jnp.where(use, norm, 1.0)
        distance = jnp.where(use, best, distance)
        edge = jnp.where(use, w.vid[kv], edge)
        vertex = jnp.where(use, w.vid[kv], vertex)
        normal = jnp.where(use, jnp.stack([px / safe, py / safe]), normal)
    return Hit(jnp.maximum(distance, 0.0), edge, vertex, normal)
