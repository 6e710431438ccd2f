"""Bump sections: the poses at which a robot meets the boundary, cut into the cells of a
`CellModel`, with their natural measure, and uniform samples of them.

A robot of radius R bumps with its centre on the boundary of its configuration space (the free
space shrunk by R, `World.eroded`) while heading into it. Those poses — a contact point on the
boundary and a heading — form the *section* of the motion at the boundary (the Poincaré section
of billiards, in Birkhoff's coordinates: arc length along the boundary and the angle of the
heading). The flow of straight drives carries the measure

    dμ = max(0, −n · d(θ)) ds dθ

onto it (n: the inward normal at the contact point, d(θ): the unit heading): robots whose paths
are spread uniformly across their direction of travel meet a piece of boundary in proportion to
its length foreshortened by the angle of incidence. It is the invariant measure of the billiard
map (Chernov & Markarian, *Chaotic Billiards*, AMS 2006, ch. 2), the flux of uniformly spread
parallel rays of each heading.

`BumpSections` cuts the boundary into pieces that each lie in one grid cell (assigned by
`bounce_gym.cells.bump_states`, like any bump pose), gives every decision state (position cell
× heading bin) its measure μ, and draws poses of a state from μ restricted to it: a piece by its
share of the state's measure, a point uniform along the piece, and a heading from the density
∝ −cos(θ − α) (α: the piece's normal angle) over the bin's headings that face the piece, by
inversion of its distribution function. A disk's boundary arcs (around reflex vertices) are the
polygonal approximation of `World.eroded`, within 1.2e-3 R of the true arcs; the simulator that
takes these poses computes the exact contact (`bounce_gym.dynamics.bump_sampler`).

With a heading ``offset`` the headings are not spread over the bin: every pose of bin k heads
exactly k·Δθ + offset. Noise-free relative bounces keep a robot's heading modulo the bin width
(they add whole multiples of it), so a robot that starts at a bin's heading plus ``offset`` meets
the boundary only at such headings; the measure is then the flux of that one heading,
``max(0, −n · d) ds`` per piece.
"""

from __future__ import annotations

import math

import numpy as np
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from bounce_gym.cells.bump_states import BumpStates
from bounce_gym.cells.model import CellModel

#: Pieces shorter than this (in cell sides) are dropped: the ends of a segment on a grid line.
_MIN_PIECE = 1e-12


class BumpSections:
    """The boundary of a cell model's configuration space, cut into one piece per grid cell,
    and the measure and samples of its decision states (see the module docstring).

    Attributes:
        start, end: (m, 2) ends of the pieces, the free space on their left.
        normal: (m, 2) inward unit normals.
        cell: (m,) position index (`CellModel`) of each piece.
        measure: (N,) μ of every cell number (0 where no robot bumps).
    """

    def __init__(self, model: CellModel) -> None:
        self.model = model
        start, end = _segments(model.world.eroded(model.robot_radius))
        start, end = _cut(start, end, model.origin, model.cell_size)
        tangent = end - start
        length = np.hypot(tangent[:, 0], tangent[:, 1])
        keep = length > _MIN_PIECE * model.cell_size
        self.start, self.end, self.length = start[keep], end[keep], length[keep]
        tangent = tangent[keep] / self.length[:, None]
        self.normal = np.column_stack((-tangent[:, 1], tangent[:, 0]))
        middle = 0.5 * (self.start + self.end)
        states = BumpStates(model)
        self.cell = model.decode(states.of(middle, np.zeros(len(middle)), self.normal))[0]
        self._atoms()

    def _atoms(self) -> None:
        """Pieces × bins with a positive measure: for each, the heading range facing the piece
        as angles u = θ − α in [π/2, 3π/2] (α: the normal's angle), and its measure."""
        model = self.model
        width = model.bin_width
        alpha = np.arctan2(self.normal[:, 1], self.normal[:, 0])
        piece, k = np.meshgrid(np.arange(len(alpha)), np.arange(model.n_bins), indexing="ij")
        piece, k = piece.ravel(), k.ravel()
        lo = np.mod(k * width - 0.5 * width - alpha[piece], 2 * math.pi)
        hi = lo + width
        parts = []
        for shift in (0.0, 2 * math.pi):  # the facing range [π/2, 3π/2], and one turn on
            a = np.maximum(lo, 0.5 * math.pi + shift) - shift
            b = np.minimum(hi, 1.5 * math.pi + shift) - shift
            ok = b > a
            parts.append((piece[ok], k[ok], a[ok], b[ok]))
        piece, k, a, b = (np.concatenate(x) for x in zip(*parts, strict=True))
        weight = self.length[piece] * (np.sin(a) - np.sin(b))  # ∫ −cos u du over [a, b]
        z = model.cell_id(self.cell[piece], k)
        order = np.lexsort((piece, z))
        keep = order[weight[order] > 0]
        self._atom_z, self._atom_piece = z[keep], piece[keep]
        self._atom_lo, self._atom_hi = a[keep], b[keep]
        self._atom_cum = np.cumsum(weight[keep])
        self.measure = np.bincount(self._atom_z, weights=weight[keep], minlength=model.n_cells)

    def fixed_heading(self, offset: float) -> tuple[np.ndarray, np.ndarray]:
        """Per piece and bin, the flux ``length · max(0, −n · d)`` of the one heading
        k·Δθ + ``offset`` (radians) of bin k: an (m, n_bins) array; and the (N,) measure of every
        cell number under it."""
        model = self.model
        heading = np.arange(model.n_bins) * model.bin_width + offset
        d = np.column_stack((np.cos(heading), np.sin(heading)))
        flux = self.length[:, None] * np.maximum(0.0, -(self.normal @ d.T))
        z = model.cell_id(self.cell[:, None], np.arange(model.n_bins)[None, :])
        return flux, np.bincount(z.ravel(), weights=flux.ravel(), minlength=model.n_cells)

    def sample_heading(self, cells: np.ndarray, n: int, rng: np.random.Generator,
                       offset: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """As `sample`, with every heading of bin k exactly k·Δθ + ``offset`` (radians) and the
        pieces drawn by their flux at that heading (`fixed_heading`)."""
        model = self.model
        cells = np.asarray(cells, dtype=np.int64)
        flux, measure = self.fixed_heading(offset)
        if np.any(measure[cells] <= 0):
            raise ValueError("sample_heading: some cells have no bump poses at this heading")
        p, k = model.decode(cells)
        # per state, the pieces of its position cell weighted by their flux in its bin
        weight = np.where(self.cell[None, :] == p[:, None], flux.T[k], 0.0)
        cum = np.cumsum(weight, axis=1)
        q = rng.random((len(cells), n)) * cum[:, -1:]
        piece = np.stack([np.searchsorted(c, row, side="right") for c, row in zip(cum, q,
                                                                                   strict=True)])
        piece = np.minimum(piece, len(self.length) - 1).ravel()
        t = rng.random(len(piece))
        point = self.start[piece] + t[:, None] * (self.end[piece] - self.start[piece])
        heading = np.mod(np.repeat(k * model.bin_width + offset, n), 2 * math.pi)
        return point, heading, self.normal[piece]

    def sample(self, cells: np.ndarray, n: int, rng: np.random.Generator
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``n`` poses of each state of ``cells`` (cell numbers of positive measure), drawn from
        μ restricted to the state: contact points (len(cells)·n, 2), headings (radians) and the
        inward normals of their pieces, state by state."""
        cells = np.asarray(cells, dtype=np.int64)
        first = np.searchsorted(self._atom_z, cells, side="left")
        last = np.searchsorted(self._atom_z, cells, side="right")
        if np.any(last == first):
            raise ValueError("sample: some cells have no bump poses (measure 0)")
        below = np.where(first > 0, self._atom_cum[np.maximum(first - 1, 0)], 0.0)
        total = self._atom_cum[last - 1] - below
        q = np.repeat(below, n) + rng.random(len(cells) * n) * np.repeat(total, n)
        atom = np.searchsorted(self._atom_cum, q, side="right")
        atom = np.clip(atom, np.repeat(first, n), np.repeat(last - 1, n))
        piece = self._atom_piece[atom]
        t = rng.random(len(atom))
        point = self.start[piece] + t[:, None] * (self.end[piece] - self.start[piece])
        # the heading: density ∝ −cos u on [lo, hi] ⊂ [π/2, 3π/2], where sin falls from 1 to −1
        lo, hi = self._atom_lo[atom], self._atom_hi[atom]
        s = np.sin(lo) - rng.random(len(atom)) * (np.sin(lo) - np.sin(hi))
        u = np.clip(math.pi - np.arcsin(np.clip(s, -1.0, 1.0)), lo, hi)
        alpha = np.arctan2(self.normal[piece, 1], self.normal[piece, 0])
        heading = np.mod(alpha + u, 2 * math.pi)
        return point, heading, self.normal[piece]


def _segments(region) -> tuple[np.ndarray, np.ndarray]:
    """(m, 2) starts and ends of the boundary segments of a shapely (Multi)Polygon, oriented
    with the region on their left (outer rings counter-clockwise, holes clockwise)."""
    polygons = region.geoms if isinstance(region, MultiPolygon) else [region]
    starts, ends = [], []
    for polygon in polygons:
        if not isinstance(polygon, Polygon) or polygon.is_empty:
            continue
        polygon = orient(polygon, sign=1.0)
        for ring in (polygon.exterior, *polygon.interiors):
            xy = np.asarray(ring.coords, dtype=np.float64)
            starts.append(xy[:-1])
            ends.append(xy[1:])
    if not starts:
        return np.empty((0, 2)), np.empty((0, 2))
    return np.concatenate(starts), np.concatenate(ends)


def _cut(start: np.ndarray, end: np.ndarray, origin: tuple[float, float], size: float
         ) -> tuple[np.ndarray, np.ndarray]:
    """The segments cut where they cross the grid lines x = x0 + i·size, y = y0 + j·size."""
    starts, ends = [], []
    for a, b in zip(start, end, strict=True):
        cuts = [0.0, 1.0]
        for axis in (0, 1):
            if a[axis] == b[axis]:
                continue
            lo, hi = sorted(((a[axis] - origin[axis]) / size, (b[axis] - origin[axis]) / size))
            lines = np.arange(math.floor(lo) + 1, math.ceil(hi))
            cuts.extend((origin[axis] + lines * size - a[axis]) / (b[axis] - a[axis]))
        t = np.unique(np.clip(cuts, 0.0, 1.0))
        points = a + t[:, None] * (b - a)
        starts.append(points[:-1])
        ends.append(points[1:])
    if not starts:
        return np.empty((0, 2)), np.empty((0, 2))
    return np.concatenate(starts), np.concatenate(ends)
