"""Generalized cell mapping by sampling for the drifter envs: the drift of each cell measured by
running the env's own backend from sample points of the cell for one decision step.

Construction (Hsu 1980; Hsu, *Cell-to-Cell Mapping*, 1987, ch. 10-11): every water cell of every
layer gets ``samples`` points drawn uniformly (seeded) over the cell's rectangle in the field's
coordinates; all of them are stepped at once by the backend the env steps — for the continuous
backend a `ContinuousFleet` (RK4 in ``substeps`` steps, the env's diffusion, land rule and
holding of the last snapshot), for the cell backend a `CellFleet` (a draw from the exact
model) — and ``P_k[z, z']`` is the fraction of z's points that end in cell z'. On a
time-dependent field the step's currents depend on when it starts, so the matrix is estimated
for every decision step k whose start time ``start_time + k * step_seconds`` precedes the
field's last snapshot (at most ``horizon`` of them); the next one, whose currents are held,
stands for every later step. A static field and the cell backend have one matrix.

Refinement: with ``refine`` r > 1 the model's states are the r x r sub-cells of every water
cell (`refined_field`: the same grid subdivided, land per parent cell); the particles still move
through the env's own field, only the cells they are counted in are finer. The GCM then forgets
less of where in a cell a drifter is (Hsu 1987 refines cells for the same reason).

Convergence: the points of each cell are drawn as two independent halves; the model reports the
mean (and largest) total-variation distance between the rows estimated from the first half and
from all of them — the change when the sample count doubles from ``samples / 2``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from bounce_gym.cells.drifter import DRIFT, DrifterCells
from bounce_gym.cells.sampled_drifter import SampledDrifterCells
from bounce_gym.envs.drifters.backends import CellFleet, ContinuousFleet
from bounce_gym.envs.drifters.options import DrifterOptions
from bounce_gym.errors import ConfigError
from bounce_gym.flows import FlowField

__all__ = ["DEFAULT_SAMPLES", "MAX_PARTICLES", "MAX_REFINE",
           "build_sampled_model", "grid_model", "refined_field",
           "step_start_times"]

#: Sample points per cell unless told otherwise.
DEFAULT_SAMPLES = 256
#: Most particles stepped at once (the cells are stepped in batches of this many points).
MAX_PARTICLES = 1_000_000
#: Finest refinement: sub-cells per cell along each axis.
MAX_REFINE = 16
#: Sample points keep this fraction of a cell's width from its edges (an edge point could
#: round into the neighbouring cell).
_MARGIN = 1e-9


def step_start_times(options: DrifterOptions, horizon: int) -> list[float | None]:
    """The field times at which the decision steps with a matrix of their own start: every step
    that starts before the field's last snapshot (at most ``horizon``), then the first one that
    does not (or the step ``horizon``). The clock advances as the env's does, one substep at a
    time. ``[None]`` for a static field, ``[start_time]`` on the cell backend."""
    field = options.flow
    if options.backend == "cell" or field.time is None:
        return [options.start_time]
    dt = options.step_seconds / options.substeps
    t, times = float(options.start_time), []
    while len(times) < horizon and t < field.time[-1]:
        times.append(t)
        for _ in range(options.substeps):
            t += dt
    return [*times, t]


def refined_field(field: FlowField, refine: int) -> FlowField:
    """``field`` on a grid whose cells are the ``refine`` x ``refine`` sub-cells of its cells
    (nodes at the sub-cell centres, land as the parent cell, velocities sampled from ``field``:
    only the cells of the refined grid are used, the particles move through ``field``)."""
    if refine == 1:
        return field
    axes = []
    for nodes in (field.x, field.y):
        e = _edges(nodes)
        fractions = (np.arange(refine) + 0.5) / refine
        axes.append((e[:-1, None] + fractions * np.diff(e)[:, None]).ravel())
    fx, fy = axes
    parent_j, parent_i = np.arange(len(fy)) // refine, np.arange(len(fx)) // refine
    land = field.land[:, parent_j][:, :, parent_i]
    gx, gy = np.meshgrid(fx, fy)
    times = [None] if field.time is None else list(field.time)
    u = np.zeros((field.n_layers, len(times), len(fy), len(fx)))
    v = np.zeros_like(u)
    for layer in range(field.n_layers):
        for k, t in enumerate(times):
            u[layer, k], v[layer, k] = field.velocity(gx, gy, layer, t)
    if field.time is None:
        u, v = u[:, 0], v[:, 0]
    return FlowField(u, v, x=fx, y=fy, depth=field.depth, time=field.time, land=land,
                     crs=field.crs, name=f"{field.name} refined x{refine}")


def grid_model(model: DrifterCells, refine: int) -> DrifterCells:
    """The exact model on the cells a sampled model with ``refine`` counts in: ``model``
    itself, or its field's `refined_field`."""
    if refine == 1:
        return model
    return DrifterCells(refined_field(model.field, refine), model.rho, t=model.t, outside="hold",
                        step=model.step)


def build_sampled_model(model: DrifterCells, options: DrifterOptions, samples: int, seed: int,
                        horizon: int, refine: int = 1) -> SampledDrifterCells:
    """The sampled model of the env described by ``options`` over its exact ``model``
    (module docstring); ``samples`` (even, >= 2) points per (sub-)cell drawn from ``seed``."""
    if samples < 2 or samples % 2:
        raise ConfigError(f"samples: expected an even number >= 2, got {samples!r}")
    if refine != 1 and options.backend == "cell":
        raise ConfigError("refine: the cell backend moves whole cells; refine only the "
                          "continuous backend's model")
    grid = grid_model(model, refine)
    rng = np.random.default_rng(seed)
    drifts, tv_mean, tv_max = [], [], []
    for t in step_start_times(options, horizon):
        full, half = _estimate(model, grid, options, t, samples, rng)
        tv = 0.5 * np.asarray(abs(full - half).sum(axis=1)).ravel()
        drifts.append(full)
        tv_mean.append(float(tv.mean()))
        tv_max.append(float(tv.max()))
    return SampledDrifterCells(grid, drifts, vertical_then_drift=options.backend != "cell",
                               samples=samples, seed=seed, doubling_tv=float(np.mean(tv_mean)),
                               max_doubling_tv=max(tv_max))


def _estimate(model: DrifterCells, grid: DrifterCells, options: DrifterOptions, t: float | None,
              samples: int, rng: np.random.Generator) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The drift over the cells of ``grid`` of the step starting at ``t`` (the env's fleet on
    its exact ``model``) from all ``samples`` points per cell and from the first half of them."""
    n = grid.n_states
    per_batch = max(1, MAX_PARTICLES // samples)
    rows, cols = [], []
    for lo in range(0, n, per_batch):
        states = np.repeat(np.arange(lo, min(lo + per_batch, n)), samples)
        x, y = _points(grid, states, rng)
        fleet = _fleet(model, options, t)
        fleet.reset(model.state_at_point(x, y, grid.cells[states, 0]),
                    list(zip(x, y, strict=True)), rng)
        fleet.step(np.full(len(states), DRIFT, dtype=np.int64), rng)
        ends = grid.state_at_point(*fleet.positions().T, fleet.layers())
        if np.any(ends < 0):
            raise ConfigError("samples: a sample point left the water cells (the backend "
                              "should hold it)")
        rows.append(states)
        cols.append(ends)
    states, ends = np.concatenate(rows), np.concatenate(cols)
    first = (np.arange(len(states)) % samples) < samples // 2
    return _frequencies(states, ends, samples, n), _frequencies(states[first], ends[first],
                                                                samples // 2, n)


def _fleet(model: DrifterCells, options: DrifterOptions, t: float | None):
    """A fleet of the env's backend whose step starts at field time ``t``."""
    if options.backend == "cell":
        return CellFleet(model)
    return ContinuousFleet(model, t, options.step_seconds, options.substeps,
                           options.diffusivity, options.land_rule)


def _points(model: DrifterCells, states: np.ndarray, rng: np.random.Generator
            ) -> tuple[np.ndarray, np.ndarray]:
    """Uniform points in the cells of ``states``: a cell spans the midpoints between its node
    and the neighbouring nodes (half a spacing beyond the outer nodes)."""
    field = model.field
    _, j, i = model.cells[states].T
    out = []
    for nodes, k in ((field.x, i), (field.y, j)):
        edges = _edges(nodes)
        r = _MARGIN + (1.0 - 2.0 * _MARGIN) * rng.random(len(states))  # never on an edge
        out.append(edges[k] + r * (edges[k + 1] - edges[k]))
    return out[0], out[1]


def _edges(nodes: np.ndarray) -> np.ndarray:
    """The cell edges along an axis: midpoints between nodes, half a spacing beyond the ends."""
    return np.concatenate(([nodes[0] - 0.5 * (nodes[1] - nodes[0])], 0.5 * (nodes[1:] + nodes[:-1]),
                           [nodes[-1] + 0.5 * (nodes[-1] - nodes[-2])]))


def _frequencies(states: np.ndarray, ends: np.ndarray, samples: int, n: int) -> sp.csr_matrix:
    """(n, n) CSR: the fraction of each cell's ``samples`` points that end in each cell."""
    P = sp.csr_matrix((np.full(len(states), 1.0 / samples), (states, ends)), shape=(n, n))
    P.sum_duplicates()
    return P
