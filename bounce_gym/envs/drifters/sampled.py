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

__all__ = ["DEFAULT_SAMPLES", "MAX_PARTICLES", "build_sampled_model", "step_start_times"]

#: Sample points per cell unless told otherwise.
DEFAULT_SAMPLES = 256
#: Most particles stepped at once (the cells are stepped in batches of this many points).
MAX_PARTICLES = 1_000_000
#: Sample points keep this fraction of a cell's width from its edges (an edge point could
#: round into the neighbouring cell).
_MARGIN = 1e-9


def step_start_times(options: DrifterOptions, horizon: int) -> list[float | None]:
    """The field times at which the decision steps with a matrix of their own start: every step
    that starts before the field's last snapshot (at most ``horizon``), then the first one that
    does not (or the step ``horizon``). The clock advances as the env's does, one substep at a
    time. ``[None]`` for a static field, ``[start_time]`` on the cell backend."""
    field = options.field
    if options.backend == "cell" or field.time is None:
        return [options.start_time]
    dt = options.step_seconds / options.substeps
    t, times = float(options.start_time), []
    while len(times) < horizon and t < field.time[-1]:
        times.append(t)
        for _ in range(options.substeps):
            t += dt
    return [*times, t]


def build_sampled_model(model: DrifterCells, options: DrifterOptions, samples: int, seed: int,
                        horizon: int) -> SampledDrifterCells:
    """The sampled model of the env described by ``options`` over its exact ``model``
    (module docstring); ``samples`` (even, >= 2) points per cell drawn from ``seed``."""
    if samples < 2 or samples % 2:
        raise ConfigError(f"samples: expected an even number >= 2, got {samples!r}")
    rng = np.random.default_rng(seed)
    drifts, tv_mean, tv_max = [], [], []
    for t in step_start_times(options, horizon):
        full, half = _estimate(model, options, t, samples, rng)
        tv = 0.5 * np.asarray(abs(full - half).sum(axis=1)).ravel()
        drifts.append(full)
        tv_mean.append(float(tv.mean()))
        tv_max.append(float(tv.max()))
    return SampledDrifterCells(model, drifts, vertical_then_drift=options.backend != "cell",
                               samples=samples, seed=seed, doubling_tv=float(np.mean(tv_mean)),
                               max_doubling_tv=max(tv_max))


def _estimate(model: DrifterCells, options: DrifterOptions, t: float | None, samples: int,
              rng: np.random.Generator) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The drift of the step starting at ``t`` from all ``samples`` points per cell and from
    the first half of them."""
    n = model.n_states
    per_batch = max(1, MAX_PARTICLES // samples)
    rows, cols = [], []
    for lo in range(0, n, per_batch):
        states = np.repeat(np.arange(lo, min(lo + per_batch, n)), samples)
        x, y = _points(model, states, rng)
        fleet = _fleet(model, options, t)
        fleet.reset(states, list(zip(x, y, strict=True)), rng)
        fleet.step(np.full(len(states), DRIFT, dtype=np.int64), rng)
        ends = fleet.cell_states()
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
        edges = np.concatenate(([nodes[0] - 0.5 * (nodes[1] - nodes[0])],
                                0.5 * (nodes[1:] + nodes[:-1]),
                                [nodes[-1] + 0.5 * (nodes[-1] - nodes[-2])]))
        r = _MARGIN + (1.0 - 2.0 * _MARGIN) * rng.random(len(states))  # never on an edge
        out.append(edges[k] + r * (edges[k + 1] - edges[k]))
    return out[0], out[1]


def _frequencies(states: np.ndarray, ends: np.ndarray, samples: int, n: int) -> sp.csr_matrix:
    """(n, n) CSR: the fraction of each cell's ``samples`` points that end in each cell."""
    P = sp.csr_matrix((np.full(len(states), 1.0 / samples), (states, ends)), shape=(n, n))
    P.sum_duplicates()
    return P
