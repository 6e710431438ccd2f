"""Visibility-based patrol subsets (Alam 2018, thesis ch. 4): the distributed policies of §4.3.3
(every robot covers the whole map by itself) and the centralised policies of §4.3.4 (a base
station, one angular region per robot, a contact cell in the base station's range).

Both return the subsets Q_i of Eq. 4.5 as vertex indices of the `cell_graph` numbering, which is
the free-cell numbering of `CellVisibility`; the chains themselves are solved elsewhere (on the
full graph, as the thesis does: Table 4.5 has n = 188 for every policy). Geometry is done in
cell units on the integer grid, so a plan does not depend on where the map lies or on its scale.
The choices where the thesis is open are in docs/choices/patrolling.md, "Stochastic patrolling: visibility
policies".
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np

from baselines.patrolling.base_station import base_station, kept_overlap, sectors
from baselines.patrolling.visibility import (
    CellVisibility,
    WatchRegion,
    cell_visibility,
    complete_visibility,
)
from bounce_gym import validate
from bounce_gym.errors import ConfigError

__all__ = ["CentralisedPlan", "centralised_plan", "centralised_starts", "distributed_subsets"]


def _check_visibility(field: str, visibility: object) -> CellVisibility:
    if not isinstance(visibility, CellVisibility):
        raise ConfigError(f"{field}: expected a CellVisibility, got {type(visibility).__name__}")
    return visibility


def distributed_subsets(visibility: CellVisibility, m: int) -> list[list[int]]:
    """The subsets Q_1..Q_m of the distributed policies (thesis §4.3.3, Figs 4.7-4.9).

    Robot i patrols the cover-centre cells of the i-th cover of Alg. 4.3: the cells whose
    limited visibility polygons `complete_visibility` picked for it, in the order picked. The
    cells seen from each subset are all free cells, so each robot alone watches the whole map.

    Raises:
        ConfigError: ``visibility`` is not a CellVisibility, ``m`` is not an integer >= 1, or a
            cell is seen from no cell.
    """
    return complete_visibility(_check_visibility("visibility", visibility), m)


@dataclass(frozen=True)
class CentralisedPlan:
    """The centralised visibility policies' plan (thesis §4.3.4, Figs 4.2 and 4.10-4.12).

    All cells are vertex indices of the `cell_graph` numbering; geometry is in cell units with
    y up (x = column + 1/2, y = row + 1/2).

    Attributes:
        m: the number of robots (and regions).
        r: the base station's communication (visibility) range, in cells.
        l: the robots' sensing range, in cells.
        centroid: (x, y), the mean of the free cells' centres.
        candidates: the cells considered for the base station, ascending.
        base_station: b, the candidate seeing the most cells within r.
        sector_width: 360 / m degrees.
        sectors: the sector of every cell, by the angle from b's centre (b itself: sector 0).
        comm_region: the cells b sees within r, ascending.
        monitored: the comm cells no robot patrols (b watches them), ascending.
        overlap: per robot, its region's comm cells (the overlap with b's range), ascending.
        regions: per robot, the cells it patrols: its sector's cells outside the comm region
            and its overlap cells, ascending.
        covers: per robot, the cover-centre cells of a greedy cover of its region, in the order
            chosen.
        contacts: per robot, the contact cell: the overlap cell nearest to the cover cells.
        subsets: per robot, Q_i = the cover cells, then the contact cell if it is not one.
        confine_to_region: whether the chains are to be solved on the region's subgraph
            instead of the full graph (the thesis solves on the full graph); carried for the
            chain solver.
    """

    m: int
    r: float
    l: float  # noqa: E741 (the thesis' name for the range)
    centroid: tuple[float, float]
    candidates: tuple[int, ...]
    base_station: int
    sector_width: float
    sectors: tuple[int, ...]
    comm_region: tuple[int, ...]
    monitored: tuple[int, ...]
    overlap: tuple[tuple[int, ...], ...]
    regions: tuple[tuple[int, ...], ...]
    covers: tuple[tuple[int, ...], ...]
    contacts: tuple[int, ...]
    subsets: tuple[tuple[int, ...], ...]
    confine_to_region: bool = False


def _check_graph(graph: object, visibility: CellVisibility) -> None:
    if not isinstance(graph, nx.Graph):
        raise ConfigError(f"graph: expected a networkx graph, got {type(graph).__name__}")
    expected = {v: tuple(cell) for v, cell in enumerate(visibility.cells.tolist())}
    found = {v: data.get("cell") for v, data in graph.nodes(data=True)}
    if found != expected:
        raise ConfigError("graph: expected the cell_graph of the map the visibility was "
                          "computed on (vertex v at the free cell visibility.cells[v])")


def _range_visibility(visibility_r: object, visibility_l: CellVisibility) -> CellVisibility:
    """``visibility_r`` as given, or computed at range r on ``visibility_l``'s grid and rule."""
    if isinstance(visibility_r, CellVisibility):
        if not np.array_equal(visibility_r.cells, visibility_l.cells):
            raise ConfigError("visibility_r: computed on another map than visibility_l")
        return visibility_r
    r = validate.number("visibility_r", visibility_r, minimum=0.0, strict=True)
    rows, cols = visibility_l.cells.T
    free = np.zeros((rows.max() + 1, cols.max() + 1), dtype=bool)
    free[rows, cols] = True  # blocked cells beyond the free cells' extent block no sight line
    return cell_visibility(free, r, visibility_l.rule)


def _region_cover(visibility: CellVisibility, region: np.ndarray) -> list[int]:
    """Alg. 4.3's greedy cover (robot 1's rule) of ``region`` by cells of ``region``."""
    sub = visibility.seen[region][:, region]
    local = CellVisibility(cells=visibility.cells[region], seen=sub.tocsr(), l=visibility.l,
                           rule=visibility.rule)
    return [int(region[k]) for k in complete_visibility(local, 1)[0]]


def _contact(cells: np.ndarray, overlap: np.ndarray, cover: list[int]) -> int:
    """The overlap cell nearest to the cover cells (squared distance in cells; ties: index)."""
    gap = cells[overlap][:, None, :] - cells[cover][None, :, :]
    nearest = (gap ** 2).sum(axis=2).min(axis=1)
    return int(overlap[np.lexsort((overlap, nearest))[0]])


def centralised_plan(graph: nx.Graph, visibility_r: CellVisibility | float,
                     visibility_l: CellVisibility, m: int, *,
                     confine_to_region: bool = False) -> CentralisedPlan:
    """Base station, regions, covers and contact cells of the centralised policies (§4.3.4).

    1. b: among the free cells within r/2 of the free cells' centroid (the nearest cells when
       none is that close), the one seeing the most cells within r; ties by distance to the
       centroid, then index.
    2. Sectors: θ = atan2(Δy, Δx) from b's centre in [0°, 360°), sector ⌊θ / (360°/m)⌋.
    3. b's comm region is what it sees within r. A comm cell stays for patrolling iff it is
       8-adjacent to a free cell of its own sector outside the comm region (the overlap ring);
       b alone monitors the other comm cells.
    4. Region i: sector i's non-comm cells and overlap cells. Its cover is Alg. 4.3's greedy
       cover (robot 1's rule: the regions are disjoint, so no robot needs another order) of the
       region by visibility polygons at range l centred in the region.
    5. Contact cell: the region's overlap cell nearest to its cover cells; Q_i = cover ∪
       {contact} (Eq. 4.5's subset).

    Args:
        graph: the `cell_graph` of the map (its numbering is checked against the visibility).
        visibility_r: the cell visibility at the base station's range r, or the number r (then
            computed on ``visibility_l``'s map with its rule).
        visibility_l: the cell visibility at the robots' range l.
        m: the number of robots.
        confine_to_region: carried in the plan for the chain solver.

    Raises:
        ConfigError: a bad argument (named), or a sector with no cell outside b's range or no
            overlap cell (fewer robots or a shorter r help).
    """
    visibility_l = _check_visibility("visibility_l", visibility_l)
    m = validate.integer("m", m, 1)
    confine_to_region = validate.flag("confine_to_region", confine_to_region)
    visibility_r = _range_visibility(visibility_r, visibility_l)
    _check_graph(graph, visibility_l)
    cells = visibility_l.cells
    centres = cells[:, ::-1] + 0.5  # (x, y), y up
    centroid = centres.mean(axis=0)
    candidates, b = base_station(visibility_r, centroid)
    sector = sectors(cells, b, m)
    comm = visibility_r.visible_from(b)
    kept = kept_overlap(cells, sector, comm)
    in_comm = np.zeros(len(cells), dtype=bool)
    in_comm[comm] = True
    overlap, regions, covers, contacts, subsets = [], [], [], [], []
    for i in range(m):
        own = sector == i
        ring = np.flatnonzero(own & kept)
        region = np.flatnonzero(own & (~in_comm | kept))
        if len(ring) == 0:
            why = ("no cells outside" if len(region) == 0 else
                   "no cell of the overlap ring (for a contact cell) in")
            raise ConfigError(f"m: sector {i} ({i * 360 / m:g}° to {(i + 1) * 360 / m:g}°) has "
                              f"{why} the base station's range r = {visibility_r.l}; use fewer "
                              f"robots or a smaller r")
        cover = _region_cover(visibility_l, region)
        contact = _contact(cells, ring, cover)
        overlap.append(tuple(ring.tolist()))
        regions.append(tuple(region.tolist()))
        covers.append(tuple(cover))
        contacts.append(contact)
        subsets.append(tuple(cover) if contact in cover else (*cover, contact))
    return CentralisedPlan(
        m=m, r=float(visibility_r.l), l=float(visibility_l.l),
        centroid=(float(centroid[0]), float(centroid[1])), candidates=tuple(candidates.tolist()),
        base_station=b, sector_width=360.0 / m, sectors=tuple(sector.tolist()),
        comm_region=tuple(comm.tolist()), monitored=tuple(np.flatnonzero(in_comm & ~kept).tolist()),
        overlap=tuple(overlap), regions=tuple(regions), covers=tuple(covers),
        contacts=tuple(contacts), subsets=tuple(subsets), confine_to_region=confine_to_region)


def centralised_starts(plan: CentralisedPlan, watch: WatchRegion) -> list[list[int]]:
    """Per robot, the cells it may start on when the target of ``watch`` is evaluated in the
    centralised case (thesis §4.3.5): T' ∩ its own region. Pass them to
    `vulnerability.detection_times` with ``per_robot_starts=True``.

    Raises:
        ConfigError: ``plan`` or ``watch`` has the wrong type, or a robot's region lies inside
            T (it has no start cell).
    """
    if not isinstance(plan, CentralisedPlan):
        raise ConfigError(f"plan: expected a CentralisedPlan, got {type(plan).__name__}")
    if not isinstance(watch, WatchRegion):
        raise ConfigError(f"watch: expected a WatchRegion, got {type(watch).__name__}")
    outside = set(watch.outside.tolist())
    starts = [[v for v in region if v in outside] for region in plan.regions]
    for i, start in enumerate(starts):
        if not start:
            raise ConfigError(f"watch: robot {i}'s region lies inside T of target "
                              f"{watch.target}; it has no start cell in T'")
    return starts

