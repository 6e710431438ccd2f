"""Drawing drifters: one layer of a flow field with its land, current, visited cells and goal,
the drifters and their trails.

`FlowRenderer` is a `Renderer` whose world is the rectangle of the grid's cells (in display
units: for a longitude/latitude grid, longitudes are scaled by the cosine of the mid latitude so
that the map keeps its shape), so frames, the human window, labels, trails and pickling work as
for the bouncing robots. The current of the drawn layer at the drawn time is shown as arrows on
a subsampled grid (length proportional to speed in cells per second) or as short streamlines
(flow lines of that snapshot, RK4, from the same points).
"""

from __future__ import annotations

import math

import numpy as np

from bounce_gym.envs.render.renderer import GOAL, GOAL_DARK, Renderer, robot_colour
from bounce_gym.flows import FlowField
from bounce_gym.flows.integrate import coordinate_rates, rk4_step
from bounce_gym.worlds import World

WATER = (226, 238, 247)
LAND = (214, 204, 178)
VISITED = (120, 170, 220, 90)
CURRENT = (48, 74, 110)
#: at most this many arrows / streamlines along each axis
MAX_GLYPHS = 24
STREAMLINE_STEPS = 10


class FlowRenderer(Renderer):
    """Frames of a `FlowField`'s grid (see the module docstring); ``style`` is ``"arrows"``
    or ``"streamlines"``."""

    def __init__(self, field: FlowField, width: int = 640, margin: int = 16,
                 style: str = "arrows") -> None:
        self.field = field
        self.style = style
        self.xscale = math.cos(math.radians(float(np.mean(field.y)))) \
            if field.crs == "lonlat" else 1.0
        self.x_edges = _edges(field.x) * self.xscale
        self.y_edges = _edges(field.y)
        x0, x1 = self.x_edges[[0, -1]]
        y0, y1 = self.y_edges[[0, -1]]
        world = World([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], name=field.name)
        super().__init__(world, width, margin, grid=False)
        ny, nx = field.shape
        self.stride = max(1, math.ceil(max(ny, nx) / MAX_GLYPHS))
        self._glyphs: tuple | None = None  # ((layer, t), polylines in display units)

    def _reset_pygame_objects(self) -> None:
        super()._reset_pygame_objects()
        self._layer_surfaces: dict = {}

    def display(self, points: np.ndarray) -> np.ndarray:
        """Field coordinates (n, 2) to display units."""
        out = np.array(points, dtype=np.float64).reshape(-1, 2)
        out[:, 0] *= self.xscale
        return out

    # -- drawing ----------------------------------------------------------------------------
    def draw_layer(self, layer: int, t: float | None, positions: np.ndarray,
                   layers: np.ndarray, trails: list[np.ndarray], visited: np.ndarray | None,
                   highlight: np.ndarray | None, labels: list[str]) -> np.ndarray:
        """One RGB frame of ``layer`` at time ``t``: land and water, the ``visited`` and
        ``highlight`` (goal) cells ((Ny, Nx) bool, or None), the current, the ``trails`` and
        the drifters at ``positions`` (field coordinates) — filled if they are in ``layer``,
        rings otherwise."""
        from bounce_gym.envs.render.renderer import _import_pygame

        pg = _import_pygame()
        if self._static is None:
            self._build_static(pg)
        frame = self._frame
        frame.blit(self._background(pg, layer), (0, 0))
        if visited is not None and visited.any():
            self._fill_cells(pg, frame, visited, VISITED)
        if highlight is not None and highlight.any():
            self._fill_cells(pg, frame, highlight, (*GOAL, 110), outline=GOAL_DARK)
        self._draw_current(pg, frame, layer, t)
        if trails:
            self._draw_trails(pg, frame, [self.display(tr) for tr in trails])
        self._draw_drifters(pg, frame, self.display(positions), np.asarray(layers) == layer)
        if labels:
            self._draw_labels(pg, frame, labels)
        return np.ascontiguousarray(pg.surfarray.array3d(frame).transpose(1, 0, 2))

    def _cell_rects(self, mask: np.ndarray) -> list:
        """Pixel rectangles (left, top, width, height) of the cells where ``mask`` is True."""
        j, i = np.nonzero(mask)
        lo = self.to_pixels(np.column_stack((self.x_edges[i], self.y_edges[j + 1])))
        hi = self.to_pixels(np.column_stack((self.x_edges[i + 1], self.y_edges[j])))
        lo, hi = np.floor(lo).astype(int), np.ceil(hi).astype(int)
        return [(a, b, c - a, d - b) for (a, b), (c, d) in zip(lo.tolist(), hi.tolist(),
                                                                 strict=True)]

    def _background(self, pg, layer: int):
        """Water and land of ``layer`` over the static frame (cached per layer)."""
        if layer not in self._layer_surfaces:
            surface = self._static.copy()
            for rect in self._cell_rects(self.field.water[layer]):
                pg.draw.rect(surface, WATER, rect)
            for rect in self._cell_rects(self.field.land[layer]):
                pg.draw.rect(surface, LAND, rect)
            self._layer_surfaces[layer] = surface
        return self._layer_surfaces[layer]

    def _fill_cells(self, pg, frame, mask, colour, outline=None) -> None:
        overlay = self._clear_overlay()
        for rect in self._cell_rects(mask):
            pg.draw.rect(overlay, colour, rect)
            if outline is not None:
                pg.draw.rect(overlay, (*outline, 200), rect, 1)
        frame.blit(overlay, (0, 0))

    def _draw_current(self, pg, frame, layer: int, t: float | None) -> None:
        key = (layer, t)
        if self._glyphs is None or self._glyphs[0] != key:
            lines = (self._arrows(layer, t) if self.style == "arrows"
                     else self._streamlines(layer, t))
            self._glyphs = (key, lines)
        width = max(1, self._line // 2)
        for line in self._glyphs[1]:
            pts = self._ipx(line)
            pg.draw.lines(frame, CURRENT, False, pts, width)
            self._arrow_head(pg, frame, line[-2], line[-1], width)

    def _arrow_head(self, pg, frame, tail, tip, width: int) -> None:
        (tx, ty), (hx, hy) = self.to_pixels(np.array([tail, tip]))
        angle = math.atan2(hy - ty, hx - tx)
        size = max(3.0, 0.25 * self.scale * (self.x_edges[1] - self.x_edges[0]) * self.stride)
        size = min(size, 0.6 * math.hypot(hx - tx, hy - ty) + 3.0)
        for side in (-0.5, 0.5):
            end = (round(hx - size * math.cos(angle + side)),
                   round(hy - size * math.sin(angle + side)))
            pg.draw.line(frame, CURRENT, (round(hx), round(hy)), end, width)

    def _seeds(self, layer: int) -> tuple[np.ndarray, np.ndarray]:
        """Field coordinates of every ``stride``-th water node of ``layer``."""
        s = self.stride
        j, i = np.nonzero(self.field.water[layer][s // 2::s, s // 2::s])
        j, i = j * s + s // 2, i * s + s // 2
        return self.field.x[i], self.field.y[j]

    def _cell_rates(self, layer: int, t, x, y) -> tuple[np.ndarray, np.ndarray]:
        """The current at (x, y) in cells per second along x and y (local node spacing)."""
        t = None if self.field.time is None else t
        u, v = coordinate_rates(self.field, x, y, np.full(len(x), layer), t, outside="hold")
        jj, ii, _ = self.field.nearest_node(x, y)
        return u / np.gradient(self.field.x)[ii], v / np.gradient(self.field.y)[jj]

    def _arrows(self, layer: int, t) -> list[np.ndarray]:
        x, y = self._seeds(layer)
        cu, cv = self._cell_rates(layer, t, x, y)
        top = float(np.hypot(cu, cv).max()) if len(x) else 0.0
        if top == 0:
            return []
        length = 0.9 * self.stride / top  # cells per (cell per second): the fastest arrow
        dx = cu * length * np.gradient(self.field.x).mean()
        dy = cv * length * np.gradient(self.field.y).mean()
        keep = np.hypot(cu, cv) > 0.02 * top
        return [self.display(np.array([[a - 0.5 * p, b - 0.5 * q], [a + 0.5 * p, b + 0.5 * q]]))
                for a, b, p, q in zip(x[keep], y[keep], dx[keep], dy[keep], strict=True)]

    def _streamlines(self, layer: int, t) -> list[np.ndarray]:
        x, y = self._seeds(layer)
        cu, cv = self._cell_rates(layer, t, x, y)
        rate = np.hypot(cu, cv)
        keep = rate > 0
        x, y, rate = x[keep], y[keep], rate[keep]
        if not len(x):
            return []
        t = None if self.field.time is None else t
        dt = 0.8 * self.stride / STREAMLINE_STEPS / rate  # seconds per substep, per line
        lay = np.full(len(x), layer)
        path = [np.column_stack((x, y))]
        for _ in range(STREAMLINE_STEPS):
            nx_, ny_ = rk4_step(self.field, x, y, lay, dt, t, frozen=True, outside="hold")
            wet = self.field.water_at(nx_, ny_, lay)
            x, y = np.where(wet, nx_, x), np.where(wet, ny_, y)
            path.append(np.column_stack((x, y)))
        lines = np.stack(path, axis=1)  # (lines, steps + 1, 2)
        return [self.display(line) for line in lines
                if np.hypot(*(line[-1] - line[0])) > 0]

    def _draw_drifters(self, pg, frame, pos: np.ndarray, here: np.ndarray) -> None:
        radius = max(4, round(0.3 * self.scale * float(np.diff(self.x_edges).mean())))
        for k, (cx, cy) in enumerate(self._ipx(pos)):
            colour = robot_colour(k)
            if here[k]:
                pg.gfxdraw.filled_circle(frame, cx, cy, radius, colour)
                pg.gfxdraw.aacircle(frame, cx, cy, radius, tuple(int(c * 0.55) for c in colour))
            else:  # in another layer: a ring
                pg.draw.circle(frame, colour, (cx, cy), radius, 2)


def draw_drifters(renderer: FlowRenderer, core, layer: int) -> np.ndarray:
    """One frame of a drifter env's core (`bounce_gym.envs.drifters.core.DrifterCore`),
    showing ``layer``."""
    model = core.model
    field = model.field
    highlight = np.zeros(model.index.shape[1:], dtype=bool)
    if core.task.marked:
        region = core.task.region.states
        here = model.cells[region, 0] == layer
        highlight[model.cells[region[here], 1], model.cells[region[here], 2]] = True
    t = core.fleet.time
    clock = "" if t is None or field.time is None else (
        f"  t = {t / 3600:.1f} h" if core.options.backend == "continuous"
        else f"  model at t = {t / 3600:.1f} h")
    labels = [f"{field.name}  layer {layer} ({field.depth[layer]:g} m)  step {core.steps}{clock}"]
    return renderer.draw_layer(layer, t, core.fleet.positions(), core.fleet.layers(),
                               [np.array(trail) for trail in core.trails],
                               core.visited[layer], highlight, labels)


def _edges(nodes: np.ndarray) -> np.ndarray:
    """The (n + 1,) cell edges of n nodes: midpoints, and half a spacing beyond the ends."""
    mid = 0.5 * (nodes[1:] + nodes[:-1])
    return np.concatenate(([nodes[0] - (mid[0] - nodes[0])], mid,
                           [nodes[-1] + (nodes[-1] - mid[-1])]))
