"""Persistent monitoring with two bouncing robots: Algorithm 2, PERSISTENTBEHAVIOR (Alam & Bobadilla
2020, §4.2).

Alam & Bobadilla's Algorithm 2 enumerates the periodic groups (joint limit cycles) of the simple
cell mapping of m robots and keeps those that monitor the target regions without a robot-robot
collision. This module does it for **m = 2** robots, with the choices of docs/choices/multirobot.md
("Robot–robot conflicts on the grid", "Monitoring: regions and the collision sink", "Algorithm 2's
bookkeeping", "Joint cell numbering"):

* **Dynamics.** Each robot i follows its own cell map C_i (`CellModel.successor` with its own
  bounce angle φ_i); robots bounce only off the walls and ignore each other (§4.2).
* **Joint cells.** ``z = z1 · N2 + z2`` (mixed radix, robot 1 most significant) for
  ``z1, z2`` the single-robot cells, ``N1 = N2 = 8 · n_free`` cells each; ``SINK = N1 · N2`` is one
  extra cell ⊥.
* **Collisions.** A joint cell whose two robots' position cells are within Chebyshev (king-move)
  distance ``min_sep_cells`` on the grid — 0 (default) = the same cell; 1, 2, … for cells smaller
  than the robot diameter —, one whose step makes two diagonal moves cross
  (`bounce_gym.cells.crossing`: both robots at the midpoint of one 2×2 block half-way through
  the tick), and, with ``forbid_swaps=True``, one whose step makes the two robots swap cells
  (they would pass through each other) maps to the absorbing sink ⊥ instead of its product
  successor. So every cycle other than ⊥ itself, and every transient trajectory into it, is
  collision-free by construction. A swap or a crossing moves each robot one king move, so it
  starts from Chebyshev distance 1 and only matters for ``min_sep_cells=0``.
* **SCM.** The joint successor array is analysed with `bounce_gym.markov.scm.simple_cell_mapping`
  (array-based, so every joint cell is processed once, as in Algorithm 2's outer loop).
* **SAMEREGION(F, x̃).** Robot j is assigned region F_j (a set of free position cells);
  ``mode="visit"`` (default): robot j's cycle positions intersect F_j; ``"cover"``: they contain
  all of F_j; ``"any"``: every F_j is visited by some robot each period. The sink group is always
  rejected.
* **Bookkeeping.** r counts only the accepted groups, numbered 0..r-1 in the order of
  their SCM group numbers. ``MonitoringResult.label`` gives every joint cell one final label:
  the accepted group number for its periodic cells (P_g) *and* its transient cells (Q_g: the
  runs that end in an already-labelled group take that group's number), and ``REJECTED = -2``
  for every cell, periodic or transient, of a rejected group — the sink ⊥ and its basin
  included. ``MonitoringResult.periodic`` tells P from Q, so every joint cell is exactly one of
  accepted-periodic, accepted-transient or rejected.

Because the robots ignore each other, a joint cycle is a pair of individual cycles of periods
p1, p2 run in lock step: its period is lcm(p1, p2), and one pair of individual cycles gives
gcd(p1, p2) joint cycles before the collision filter — collision filtering
can only remove some of them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bounce_gym.cells import CellModel, crossing, too_close
from bounce_gym.errors import ConfigError
from bounce_gym.markov.scm import SCMResult, simple_cell_mapping

__all__ = ["MODES", "REJECTED", "MonitoringResult", "default_regions", "joint_successor",
           "joint_monitoring_cycles", "region_indices", "summary"]

MODES = ("visit", "cover", "any")
#: The label of every cell of a group rejected by SAMEREGION (docs/choices/multirobot.md, "Algorithm 2's
#: bookkeeping").
REJECTED = -2


@dataclass(eq=False)
class MonitoringResult:
    """The output of `joint_monitoring_cycles` (Algorithm 2's P and Q, plus bookkeeping).

    Attributes:
        model: the single-robot cell model (both robots use it).
        phis: (φ1, φ2) in radians.
        regions: two sorted arrays of position indices, F_1 and F_2.
        mode: the SAMEREGION mode.
        min_sep_cells: the collision distance (Chebyshev, in grid cells; 0 = same cell).
        forbid_swaps: whether swapping cells in one step counts as a collision.
        scm: the SCM of the joint map (cells 0..N1·N2, the last one the sink).
        sink: the sink cell number ``N1 · N2``.
        accepted: sorted SCM group numbers of the accepted groups (r of them); accepted group g
            is SCM group ``accepted[g]``.
        label: (N1·N2 + 1,) int32, Algorithm 2's final group label of every joint cell, sink
            included ("Algorithm 2's bookkeeping"): g in 0..r-1 for the periodic and transient cells
            of accepted group g (P_g ∪ Q_g), `REJECTED` (-2) for every cell of a rejected group.
        cycles: the accepted groups' joint cycles (P_1..P_r), in the order of C.
        periods: (r,) their periods.
        basins: (r,) the number of transient joint cells leading into each (|Q_1|..|Q_r|).
        n_groups: the number of periodic groups of the joint map, the sink included.
        n_collision_cells: joint cells that collide (map to the sink directly).
    """

    model: CellModel
    phis: tuple[float, float]
    regions: tuple[np.ndarray, np.ndarray]
    mode: str
    min_sep_cells: int
    forbid_swaps: bool
    scm: SCMResult
    sink: int
    accepted: np.ndarray
    label: np.ndarray
    cycles: list[np.ndarray]
    periods: np.ndarray
    basins: np.ndarray
    n_groups: int
    n_collision_cells: int

    @property
    def r(self) -> int:
        """The number of accepted periodic groups."""
        return len(self.accepted)

    @property
    def periodic(self) -> np.ndarray:
        """(N1·N2 + 1,) bool, True for periodic joint cells (the SCM's view): with `label`, a
        cell with ``label >= 0`` is in P_label if periodic and in Q_label otherwise."""
        return self.scm.periodic

    def split(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Single-robot cells (z1, z2) of joint cells z (not the sink)."""
        z = np.asarray(z, dtype=np.int64)
        return z // self.model.n_cells, z % self.model.n_cells

    def start_options(self, z: int) -> dict:
        """``env.reset(options=...)`` that places the two robots in joint cell z."""
        z1, z2 = self.split(np.array([z, z]))
        (c1, h1), (c2, h2) = (self.model.configuration(int(z1[0])),
                              self.model.configuration(int(z2[0])))
        return {"start": {"position": [[float(c1[0]), float(c1[1])],
                                       [float(c2[0]), float(c2[1])]],
                          "heading": [float(h1), float(h2)]}}


def region_indices(model: CellModel, region: object) -> np.ndarray:
    """A region as sorted unique position indices.

    ``region`` is either a 1-D sequence of position indices (0..n_positions-1) or a (k, 2)
    sequence of (row, col) grid cells (row 0 at the bottom); every cell must be free.
    """
    arr = np.asarray(region)
    if arr.size == 0:
        raise ConfigError("regions: a target region must contain at least one free cell")
    if not np.issubdtype(arr.dtype, np.integer):
        raise ConfigError(f"regions: expected integer cells, got dtype {arr.dtype}")
    if arr.ndim == 2 and arr.shape[1] == 2:
        row, col = arr[:, 0], arr[:, 1]
        inside = (row >= 0) & (row < model.rows) & (col >= 0) & (col < model.cols)
        if not inside.all():
            raise ConfigError(f"regions: cells {arr[~inside].tolist()} are outside the grid")
        p = model.position_index[row, col]
        if (p < 0).any():
            raise ConfigError(f"regions: cells {arr[p < 0].tolist()} are not free")
    elif arr.ndim == 1:
        p = arr.astype(np.int64)
        if p.min() < 0 or p.max() >= model.n_positions:
            raise ConfigError(f"regions: position indices must be in 0..{model.n_positions - 1}")
    else:
        raise ConfigError(f"regions: expected position indices or (row, col) pairs, got shape "
                          f"{arr.shape}")
    return np.unique(p)


def default_regions(model: CellModel) -> tuple[np.ndarray, np.ndarray]:
    """Split the free cells into two halves by column: F_1 = the left columns, F_2 = the rest.

    The split column is the one that makes the halves closest to equal in size.
    """
    cols = model.position_rc[:, 1]
    counts = np.array([(cols < c).sum() for c in range(model.cols + 1)])
    c = int(np.argmin(np.abs(2 * counts - model.n_positions)))
    left = np.flatnonzero(cols < c)
    right = np.flatnonzero(cols >= c)
    if len(left) == 0 or len(right) == 0:
        raise ConfigError("regions: the free cells cannot be split into two non-empty halves")
    return left, right


def joint_successor(model: CellModel, phis: Sequence[float], forbid_swaps: bool = False,
                    min_sep_cells: int = 0) -> tuple[np.ndarray, int]:
    """The joint map of two independent robots with a collision sink, vectorised
    (docs/choices/multirobot.md, "Monitoring: regions and the collision sink", "Joint cell numbering").

    Returns ``(successor, n_collision_cells)``: ``successor`` has N1·N2 + 1 entries (the last is
    the sink ⊥, which maps to itself); joint cells that collide — position cells within
    Chebyshev distance ``min_sep_cells`` (`bounce_gym.cells.too_close`), crossing diagonal
    moves (`bounce_gym.cells.crossing`), or a swap when ``forbid_swaps`` — map to ⊥.
    """
    if len(phis) != 2:
        raise ConfigError(f"phis: expected two bounce angles, got {len(phis)}")
    close = too_close(model.position_rc, min_sep_cells)
    n = model.n_cells
    s1, _ = model.successor(float(phis[0]))
    s2, _ = model.successor(float(phis[1]))
    pos = model.decode(np.arange(n))[0]
    sink = n * n
    succ = np.empty(sink + 1, dtype=np.int64)
    joint = succ[:sink].reshape(n, n)
    np.add(s1[:, None] * n, s2[None, :], out=joint)
    collide = close[pos[:, None], pos[None, :]]
    npos1, npos2 = model.decode(s1)[0], model.decode(s2)[0]
    rc = model.position_rc.astype(np.int32)
    collide |= crossing(rc[pos][:, None], rc[npos1][:, None], rc[pos][None], rc[npos2][None])
    if forbid_swaps:
        collide |= (npos1[:, None] == pos[None, :]) & (npos2[None, :] == pos[:, None])
    joint[collide] = sink
    succ[sink] = sink
    return succ, int(collide.sum())


def joint_monitoring_cycles(
    model: CellModel,
    phis: Sequence[float],
    regions: Sequence[object] | None = None,
    mode: str = "visit",
    forbid_swaps: bool = False,
    min_sep_cells: int = 0,
) -> MonitoringResult:
    """Algorithm 2 for two robots: the collision-free joint limit cycles that monitor F.

    Args:
        model: the single-robot cell model of the world (both robots use it).
        phis: the bounce angles (φ1, φ2) in radians, one per robot.
        regions: (F_1, F_2), see `region_indices`; default `default_regions`.
        mode: ``"visit"`` | ``"cover"`` | ``"any"`` (module docstring).
        forbid_swaps: also treat two robots swapping cells in one step as a collision.
        min_sep_cells: collide when the robots' cells are within this Chebyshev distance
            (docs/choices/multirobot.md, "Robot–robot conflicts on the grid"; 0 = the same cell only, for cells
            smaller than the robot diameter use ≥ 1).

    Returns:
        A `MonitoringResult`; ``result.r`` is the number of accepted groups and
        ``result.label`` Algorithm 2's final label of every joint cell.

    Raises:
        ConfigError: a bad ``mode``, ``regions``, ``phis`` or ``min_sep_cells``.
    """
    if mode not in MODES:
        raise ConfigError(f"mode: expected one of {MODES}, got {mode!r}")
    if regions is None:
        f1, f2 = default_regions(model)
    else:
        if len(regions) != 2:
            raise ConfigError(f"regions: expected two regions, got {len(regions)}")
        f1, f2 = (region_indices(model, r) for r in regions)
    succ, n_coll = joint_successor(model, phis, forbid_swaps, min_sep_cells)
    res = simple_cell_mapping(succ)
    sink = len(succ) - 1
    n = model.n_cells
    n_pos = model.n_positions

    pc = np.flatnonzero(res.periodic[:sink])  # periodic joint cells, the sink excluded
    grp = res.group[pc].astype(np.int64)
    p1, p2 = (pc // n) % n_pos, (pc % n) % n_pos
    in1 = np.zeros(n_pos, dtype=bool)
    in1[f1] = True
    in2 = np.zeros(n_pos, dtype=bool)
    in2[f2] = True
    ng = res.n_groups

    def per_group_any(flag: np.ndarray) -> np.ndarray:
        return np.bincount(grp[flag], minlength=ng) > 0

    def per_group_covers(pos: np.ndarray, member: np.ndarray, size: int) -> np.ndarray:
        keys = np.unique(grp[member[pos]] * n_pos + pos[member[pos]])
        return np.bincount(keys // n_pos, minlength=ng) == size

    if mode == "visit":
        ok = per_group_any(in1[p1]) & per_group_any(in2[p2])
    elif mode == "cover":
        ok = per_group_covers(p1, in1, len(f1)) & per_group_covers(p2, in2, len(f2))
    else:
        ok = (per_group_any(in1[p1] | in1[p2])) & (per_group_any(in2[p1] | in2[p2]))
    ok[res.group[sink]] = False  # SAMEREGION (b): the sink is the only colliding cycle
    accepted = np.flatnonzero(ok)
    number = np.full(ng, REJECTED, dtype=np.int32)  # SCM group -> Algorithm 2 label
    number[accepted] = np.arange(len(accepted), dtype=np.int32)
    transient_counts = np.bincount(res.group[~res.periodic], minlength=ng)
    return MonitoringResult(
        model=model,
        phis=(float(phis[0]), float(phis[1])),
        regions=(f1, f2),
        mode=mode,
        min_sep_cells=int(min_sep_cells),
        forbid_swaps=bool(forbid_swaps),
        scm=res,
        sink=sink,
        accepted=accepted,
        label=number[res.group],
        cycles=[res.cycles[g] for g in accepted],
        periods=res.periods[accepted].copy(),
        basins=transient_counts[accepted].astype(np.int64),
        n_groups=int(ng),
        n_collision_cells=n_coll,
    )


def summary(result: MonitoringResult) -> dict:
    """r, periods and basin sizes as plain numbers (for reports)."""
    return {
        "phis_deg": [math.degrees(p) for p in result.phis],
        "mode": result.mode,
        "min_sep_cells": result.min_sep_cells,
        "n_joint_cells": int(result.sink + 1),
        "n_groups": result.n_groups,
        "r": result.r,
        "periods": sorted(set(result.periods.tolist())),
        "basin_total": int(result.basins.sum()),
        "basin_max": int(result.basins.max()) if result.r else 0,
        "sink_basin": int((result.scm.group == result.scm.group[result.sink]).sum()),
    }
