"""Headless pygame rendering of a `World` and the robots in it.

`Renderer.draw` rasterises one frame into an off-screen `pygame.Surface` and returns it as a fresh
(H, W, 3) ``uint8`` RGB array, so ``render_mode="rgb_array"`` works without a display (for example
with ``SDL_VIDEODRIVER=dummy`` on a server). `Renderer.show` puts a frame in a window for
``render_mode="human"``.

pygame is imported lazily. The renderer never calls ``pygame.init()`` and never touches the
mixer: it initialises ``pygame.font`` for labels (text is skipped if that fails) and
``pygame.display`` only when a window is requested (the Gymnasium ``test_pygame_selective_init``
convention).

Each robot is a disk in its colour with a heading line from the centre past the rim; given
`Bumpers`, also its bumper (a band along the rim over the front arc, `BUMPER_PRESSED` while
pressed, else `BUMPER`), a `CONTACT` dot at the contact the bumper latched, and a centre dot (plus
a label) in the colour of its motion phase (`PHASE_COLOURS`).

World coordinates have y pointing up; pixel rows grow downwards. The world's bounding box is
scaled uniformly (aspect ratio kept) to fit ``width - 2 * margin`` pixels; the frame's height
follows from the world's aspect ratio.
"""

from __future__ import annotations

import colorsys
import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bounce_gym.errors import ConfigError
from bounce_gym.extras import require
from bounce_gym.worlds.world import World

# -- colours (RGB) ---------------------------------------------------------------------------
EXTERIOR = (203, 208, 216)
FREE = (250, 250, 246)
GRID = (234, 236, 238)
HOLE = (160, 166, 178)
WALL = (44, 52, 66)
INK = (28, 30, 36)
BLOCKED_RING = (20, 20, 24)
GOAL = (46, 158, 72)
GOAL_DARK = (22, 110, 44)
LABEL_BOX = (255, 255, 255, 200)
BUMPER = (236, 236, 236)
BUMPER_PRESSED = (255, 214, 0)
CONTACT = (232, 0, 140)
#: The centre dot of each motion phase of ``physics="dynamic"`` (see `Bumpers.phases`).
PHASE_COLOURS = {
    "drive": (255, 255, 255),
    "brake": (255, 150, 0),
    "blocked": (20, 20, 24),
    "turn": (0, 190, 255),
    "wait": (170, 170, 170),
    "hold": (150, 90, 220),
}

#: Distinct robot colours (a colour-blind friendly qualitative set); more robots cycle hues.
ROBOT_COLOURS = (
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (23, 190, 207),
    (188, 189, 34),
)

#: Heatmap ramp (low to high), a yellow-orange-red sequence.
_HEAT_STOPS = np.array([[255, 237, 160], [253, 141, 60], [189, 0, 38]], dtype=np.float64)

#: Screen coordinates are clipped to this range (pygame.gfxdraw uses 16-bit integers).
_PIXEL_LIMIT = 16000
#: Minimum on-screen radius of a robot, so point robots stay visible.
MIN_ROBOT_PX = 3
#: Robots drawn smaller than this (radius, pixels) get no bumper arc nor phase dot.
MIN_DETAIL_PX = 6
#: Frames with more robots than this colour their phases without naming them.
MAX_PHASE_LABELS = 12


def robot_colour(index: int) -> tuple[int, int, int]:
    """The colour of robot ``index``: the qualitative palette first, then golden-ratio hues."""
    if index < len(ROBOT_COLOURS):
        return ROBOT_COLOURS[index]
    hue = (0.13 + 0.618033988749895 * index) % 1.0
    r, g, b = colorsys.hsv_to_rgb(hue, 0.75, 0.85)
    return (round(r * 255), round(g * 255), round(b * 255))


def _import_pygame():
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    require("rendering (render_mode 'rgb_array' or 'human')", "pygame")
    import pygame
    import pygame.gfxdraw  # noqa: F401  (registers the submodule)

    return pygame


@dataclass
class RenderLayers:
    """Optional overlays for `Renderer.draw`, drawn in this order under the robots.

    Attributes:
        heatmap: ``(values, origin, cell_size)``: a (rows, cols) array of values >= 0, the
            (x, y) world position of the lower-left corner of cell (0, 0), and the cell side
            length. Row 0 is the **bottom** row (y up), as in `World.occupancy`. Drawn as a
            translucent yellow-to-red layer (0 = transparent, the maximum = deepest red),
            clipped to the free space.
        regions: polygons, each (k, 2) in world coordinates; region ``i`` is filled
            translucently in robot ``i``'s colour (e.g. monitoring target regions).
        goal: ``(x, y, radius, heading, tolerance)``; drawn as a green disk and, if
            ``heading`` (radians) is not None, an arrow plus a wedge of half-angle
            ``tolerance`` (radians). ``(x, y, radius)`` alone is accepted too.
        trails: per robot, a (k, 2) array of recent positions, oldest first; drawn as a
            polyline fading towards the oldest point.
        labels: text lines printed in the top-left corner (skipped if fonts are unavailable).
    """

    trails: list[np.ndarray] = field(default_factory=list)
    goal: tuple | None = None
    regions: list[np.ndarray] = field(default_factory=list)
    heatmap: tuple | None = None
    labels: list[str] = field(default_factory=list)


@dataclass
class Bumpers:
    """Each robot's bumper and motion phase, for `Renderer.draw`.

    Attributes:
        arc: degrees, the front arc the bumper covers, centred on the heading; drawn on the
            rim in `BUMPER_PRESSED` where ``pressed``, else in `BUMPER`.
        pressed: (m,) bool.
        contacts: (m, 2) world points of the contacts the bumpers latched, NaN rows where none;
            each is marked by a `CONTACT` dot.
        phases: None, or each robot's motion phase by name: a centre dot of its
            `PHASE_COLOURS` colour and, with at most `MAX_PHASE_LABELS` robots (and fonts),
            the name beside the robot.
    """

    arc: float
    pressed: np.ndarray
    contacts: np.ndarray
    phases: list[str] | None = None

    def check(self, m: int) -> None:
        """Raise `ConfigError` unless every field fits ``m`` robots."""
        if not 0.0 < float(self.arc) <= 360.0:
            raise ConfigError(f"bumpers.arc must be degrees in (0, 360], got {self.arc!r}")
        if np.shape(self.pressed) != (m,):
            raise ConfigError(f"bumpers.pressed must have shape ({m},), "
                              f"got {np.shape(self.pressed)}")
        if np.shape(self.contacts) != (m, 2):
            raise ConfigError(f"bumpers.contacts must have shape ({m}, 2), "
                              f"got {np.shape(self.contacts)}")
        if self.phases is not None:
            unknown = sorted({str(p) for p in self.phases} - set(PHASE_COLOURS))
            if len(self.phases) != m or unknown:
                raise ConfigError(f"bumpers.phases must name {m} phases of "
                                  f"{sorted(PHASE_COLOURS)}, got {self.phases!r}")


class Renderer:
    """Draws a `World` and robots into RGB frames; optionally shows them in a window.

    Args:
        world: the world to draw.
        width: frame width in pixels; the height follows from the world's aspect ratio.
        margin: empty border around the world's bounding box, in pixels.
        grid: draw a faint grid at a round world-unit spacing in the free space.

    The renderer pickles without its pygame objects (surfaces, font, window), which are
    rebuilt on the next `draw`; an unpickled renderer draws identical frames.
    """

    def __init__(self, world: World, width: int = 640, margin: int = 16, grid: bool = True):
        if not isinstance(world, World):
            raise ConfigError(f"world must be a bounce_gym World, got {type(world).__name__}")
        if isinstance(width, bool) or not isinstance(width, (int, np.integer)) or width < 32:
            raise ConfigError(f"width must be an integer >= 32 pixels, got {width!r}")
        if (
            isinstance(margin, bool)
            or not isinstance(margin, (int, np.integer))
            or not 0 <= 2 * margin < width - 16
        ):
            raise ConfigError(
                f"margin must be an integer >= 0 leaving at least 16 pixels of width, "
                f"got {margin!r} for width {width}"
            )
        self.world = world
        self.width = int(width)
        self.margin = int(margin)
        self.grid = bool(grid)
        xmin, ymin, xmax, ymax = world.bounds
        #: pixels per world unit
        self.scale = (self.width - 2 * self.margin) / (xmax - xmin)
        self.height = int(math.ceil((ymax - ymin) * self.scale - 1e-9)) + 2 * self.margin
        self._xmin, self._ymax = xmin, ymax
        self._line = max(2, round(self.width / 240))
        self._reset_pygame_objects()

    # -- pickling: pygame objects are rebuilt lazily ----------------------------------------
    def _reset_pygame_objects(self) -> None:
        self._static = None  # background, grid, exterior, holes, walls (opaque)
        self._base = None  # background and grid only (under a heatmap)
        self._mask = None  # exterior, holes and walls with transparent free space
        self._frame = None
        self._overlay = None
        self._font: Any = None  # None = not tried yet, False = unavailable
        self._screen = None
        self._clock = None

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        for key in ("_static", "_base", "_mask", "_frame", "_overlay", "_font", "_screen",
                    "_clock"):
            state[key] = None
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._reset_pygame_objects()

    # -- geometry -----------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int, int]:
        """Shape of the frames `draw` returns: (height, width, 3)."""
        return (self.height, self.width, 3)

    def to_pixels(self, points: np.ndarray) -> np.ndarray:
        """World (n, 2) points to (n, 2) float pixel coordinates (column, row); row 0 is the top."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        out = np.empty_like(pts)
        out[:, 0] = self.margin + (pts[:, 0] - self._xmin) * self.scale
        out[:, 1] = self.margin + (self._ymax - pts[:, 1]) * self.scale
        return out

    def _ipx(self, points: np.ndarray) -> list[tuple[int, int]]:
        px = np.clip(np.rint(self.to_pixels(points)), -_PIXEL_LIMIT, _PIXEL_LIMIT).astype(int)
        return [(int(x), int(y)) for x, y in px]

    # -- static layers ------------------------------------------------------------------------
    def _build_static(self, pg) -> None:
        size = (self.width, self.height)
        base = pg.Surface(size)
        base.fill(FREE)
        if self.grid:
            self._draw_grid(pg, base)
        mask = pg.Surface(size, pg.SRCALPHA)
        mask.fill((*EXTERIOR, 255))
        pg.draw.polygon(mask, (0, 0, 0, 0), self._ipx(self.world.outer))
        for hole in self.world.holes:
            pg.draw.polygon(mask, (*HOLE, 255), self._ipx(hole))
        for ring in self.world.rings:
            pts = self._ipx(ring)
            pg.draw.lines(mask, (*WALL, 255), True, pts, self._line)
            for p in pts:  # round the joints of the thick polyline
                pg.draw.circle(mask, (*WALL, 255), p, max(1, self._line // 2))
        static = base.copy()
        static.blit(mask, (0, 0))
        self._base, self._mask, self._static = base, mask, static
        self._frame = pg.Surface(size)
        self._overlay = pg.Surface(size, pg.SRCALPHA)

    def _draw_grid(self, pg, surface) -> None:
        """Faint lines every 1, 2 or 5 x 10^k world units, at least ~24 pixels apart."""
        target = 24.0 / self.scale
        exponent = math.floor(math.log10(target))
        step = next(
            m * 10.0**exponent for m in (1, 2, 5, 10) if m * 10.0**exponent >= target
        )
        xmin, ymin, xmax, ymax = self.world.bounds
        for x in np.arange(math.ceil(xmin / step) * step, xmax + 1e-9, step):
            (x0, y0), (x1, y1) = self._ipx(np.array([[x, ymin], [x, ymax]]))
            pg.draw.line(surface, GRID, (x0, y0), (x1, y1), 1)
        for y in np.arange(math.ceil(ymin / step) * step, ymax + 1e-9, step):
            (x0, y0), (x1, y1) = self._ipx(np.array([[xmin, y], [xmax, y]]))
            pg.draw.line(surface, GRID, (x0, y0), (x1, y1), 1)

    def _get_font(self, pg):
        if self._font is None:
            try:
                if not pg.font.get_init():
                    pg.font.init()
                self._font = pg.font.Font(None, max(12, round(self.width / 40)))
            except Exception:  # noqa: BLE001 - text is optional
                self._font = False
        return self._font or None

    # -- drawing ------------------------------------------------------------------------------
    def draw(
        self,
        positions: np.ndarray,
        headings: np.ndarray | None,
        radius: float | np.ndarray,
        layers: RenderLayers | None = None,
        blocked: np.ndarray | None = None,
        bumpers: Bumpers | None = None,
    ) -> np.ndarray:
        """Render one frame.

        Args:
            positions: (m, 2) robot centres in world coordinates.
            headings: (m,) headings in radians (0 = +x, counter-clockwise), or None for no
                heading lines.
            radius: robot radius in world units, a scalar or one per robot; robots are drawn
                at least `MIN_ROBOT_PX` pixels wide so point robots stay visible.
            layers: optional overlays (heatmap, regions, goal, trails, labels).
            blocked: (m,) bool; blocked robots get a dark ring.
            bumpers: optional bumper arcs (drawn where ``headings`` are given), latched
                contacts and motion phases (`Bumpers`).

        Returns:
            A new (height, width, 3) ``uint8`` RGB array.
        """
        pos = np.asarray(positions, dtype=np.float64)
        if pos.size == 0:
            pos = pos.reshape(0, 2)
        if pos.ndim != 2 or pos.shape[1] != 2:
            raise ConfigError(f"positions must have shape (m, 2), got {pos.shape}")
        m = len(pos)
        head = None
        if headings is not None:
            head = np.asarray(headings, dtype=np.float64).reshape(-1)
            if len(head) != m:
                raise ConfigError(f"headings must have shape ({m},), got {np.shape(headings)}")
        try:
            rad = np.broadcast_to(np.asarray(radius, dtype=np.float64), (m,))
        except ValueError as exc:
            raise ConfigError(
                f"radius must be a scalar or have shape ({m},), got {np.shape(radius)}"
            ) from exc
        if np.any(~np.isfinite(rad)) or np.any(rad < 0):
            raise ConfigError(f"radius must be finite and >= 0, got {radius!r}")
        blk = np.zeros(m, dtype=bool)
        if blocked is not None:
            blk = np.asarray(blocked, dtype=bool).reshape(-1)
            if len(blk) != m:
                raise ConfigError(f"blocked must have shape ({m},), got {np.shape(blocked)}")
        if bumpers is not None:
            if not isinstance(bumpers, Bumpers):
                raise ConfigError(f"bumpers must be a Bumpers, got {type(bumpers).__name__}")
            bumpers.check(m)
        layers = layers if layers is not None else RenderLayers()
        if not isinstance(layers, RenderLayers):
            raise ConfigError(f"layers must be a RenderLayers, got {type(layers).__name__}")

        pg = _import_pygame()
        if self._static is None:
            self._build_static(pg)
        frame = self._frame
        if layers.heatmap is not None:
            frame.blit(self._base, (0, 0))
            self._draw_heatmap(pg, frame, layers.heatmap)
            frame.blit(self._mask, (0, 0))
        else:
            frame.blit(self._static, (0, 0))
        if layers.regions:
            self._draw_regions(pg, frame, layers.regions)
        if layers.goal is not None:
            self._draw_goal(pg, frame, layers.goal)
        if layers.trails:
            self._draw_trails(pg, frame, layers.trails)
        self._draw_robots(pg, frame, pos, head, rad, blk, bumpers)
        if layers.labels:
            self._draw_labels(pg, frame, layers.labels)
        return np.ascontiguousarray(pg.surfarray.array3d(frame).transpose(1, 0, 2))

    def _clear_overlay(self):
        self._overlay.fill((0, 0, 0, 0))
        return self._overlay

    def _draw_heatmap(self, pg, frame, heatmap: tuple) -> None:
        try:
            values, origin, cell = heatmap
        except (TypeError, ValueError) as exc:
            raise ConfigError(
                "layers.heatmap must be (values, (x, y) origin, cell_size)"
            ) from exc
        vals = np.asarray(values, dtype=np.float64)
        if vals.ndim != 2 or vals.size == 0:
            raise ConfigError(f"heatmap values must be a non-empty 2-D array, got {vals.shape}")
        if not np.all(np.isfinite(vals)) or np.any(vals < 0):
            raise ConfigError("heatmap values must be finite and >= 0")
        ox, oy = (float(v) for v in np.asarray(origin, dtype=np.float64).reshape(2))
        cell = float(cell)
        if not math.isfinite(cell) or cell <= 0:
            raise ConfigError(f"heatmap cell_size must be a finite number > 0, got {cell!r}")
        vmax = float(vals.max())
        if vmax <= 0:
            return
        rows, cols = vals.shape
        t = np.flipud(vals / vmax)  # image row 0 is the top, heatmap row 0 the bottom
        pos = t * (len(_HEAT_STOPS) - 1)
        knots = np.arange(len(_HEAT_STOPS))
        rgba = np.empty((rows, cols, 4), dtype=np.uint8)
        for ch in range(3):
            rgba[..., ch] = np.rint(np.interp(pos, knots, _HEAT_STOPS[:, ch]))
        rgba[..., 3] = np.where(t > 0, np.rint(70 + 120 * t), 0).astype(np.uint8)
        image = pg.image.frombytes(rgba.tobytes(), (cols, rows), "RGBA")
        (left, top), (right, bottom) = self._ipx(
            np.array([[ox, oy + rows * cell], [ox + cols * cell, oy]])
        )
        w, h = right - left, bottom - top
        if w < 1 or h < 1:
            return
        if w > 4 * _PIXEL_LIMIT or h > 4 * _PIXEL_LIMIT:  # pragma: no cover - absurd sizes
            return
        frame.blit(pg.transform.scale(image, (w, h)), (left, top))

    def _draw_regions(self, pg, frame, regions) -> None:
        overlay = self._clear_overlay()
        for i, region in enumerate(regions):
            poly = np.asarray(region, dtype=np.float64)
            if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3:
                raise ConfigError(f"layers.regions[{i}] must have shape (k >= 3, 2)")
            pts = self._ipx(poly)
            colour = robot_colour(i)
            pg.draw.polygon(overlay, (*colour, 60), pts)
            pg.draw.lines(overlay, (*colour, 210), True, pts, 2)
        frame.blit(overlay, (0, 0))

    def _draw_goal(self, pg, frame, goal: tuple) -> None:
        goal = tuple(goal)
        if not 3 <= len(goal) <= 5:
            raise ConfigError(
                "layers.goal must be (x, y, radius, heading or None, tolerance), "
                f"got {len(goal)} items"
            )
        x, y, r = (float(v) for v in goal[:3])
        heading = goal[3] if len(goal) > 3 else None
        tol = float(goal[4]) if len(goal) > 4 and goal[4] is not None else 0.0
        (cx, cy), = self._ipx(np.array([[x, y]]))
        r_px = max(4, round(r * self.scale))
        overlay = self._clear_overlay()
        pg.draw.circle(overlay, (*GOAL, 80), (cx, cy), r_px)
        pg.draw.circle(overlay, (*GOAL_DARK, 230), (cx, cy), r_px, 2)
        if heading is not None:
            h = float(heading)
            length = max(2.2 * r_px, 22)
            if tol > 0:
                if tol >= math.pi:
                    pg.draw.circle(overlay, (*GOAL, 45), (cx, cy), round(length))
                else:
                    n = max(4, int(math.degrees(2 * tol) / 6))
                    angles = np.linspace(h - tol, h + tol, n + 1)
                    wedge = [(cx, cy)] + [
                        (round(cx + length * math.cos(a)), round(cy - length * math.sin(a)))
                        for a in angles
                    ]
                    pg.draw.polygon(overlay, (*GOAL, 55), wedge)
                    pg.draw.lines(overlay, (*GOAL_DARK, 120), True, wedge, 1)
            tip = (cx + length * math.cos(h), cy - length * math.sin(h))
            back = 0.35 * length
            head_pts = [(round(tip[0]), round(tip[1]))] + [
                (round(tip[0] - back * math.cos(h + s)), round(tip[1] + back * math.sin(h + s)))
                for s in (-0.45, 0.45)
            ]
            pg.draw.line(overlay, (*GOAL_DARK, 255), (cx, cy), head_pts[0], 3)
            pg.draw.polygon(overlay, (*GOAL_DARK, 255), head_pts)
        frame.blit(overlay, (0, 0))

    def _draw_trails(self, pg, frame, trails) -> None:
        overlay = self._clear_overlay()
        width = max(1, self._line - 1)
        for i, trail in enumerate(trails):
            if trail is None:
                continue
            pts = np.asarray(trail, dtype=np.float64)
            if pts.size == 0:
                continue
            if pts.ndim != 2 or pts.shape[1] != 2:
                raise ConfigError(f"layers.trails[{i}] must have shape (k, 2), got {pts.shape}")
            pts = pts[np.all(np.isfinite(pts), axis=1)]
            if len(pts) < 2:
                continue
            px = self._ipx(pts)
            colour = robot_colour(i)
            n = len(px) - 1
            for k in range(n):  # oldest segment faintest
                alpha = round(35 + 185 * (k + 1) / n)
                pg.draw.line(overlay, (*colour, alpha), px[k], px[k + 1], width)
        frame.blit(overlay, (0, 0))

    def _draw_robots(self, pg, frame, pos, head, rad, blocked, bumpers=None) -> None:
        gfx = pg.gfxdraw
        for i in range(len(pos)):
            if not np.all(np.isfinite(pos[i])):
                continue
            (cx, cy), = self._ipx(pos[i : i + 1])
            r_px = max(MIN_ROBOT_PX, round(rad[i] * self.scale))
            colour = robot_colour(i)
            dark = tuple(int(c * 0.55) for c in colour)
            if blocked[i]:
                ring = max(2, self._line)
                pg.draw.circle(frame, BLOCKED_RING, (cx, cy), r_px + ring + 1)
            gfx.filled_circle(frame, cx, cy, r_px, colour)
            gfx.aacircle(frame, cx, cy, r_px, dark)
            heading = head[i] if head is not None and np.isfinite(head[i]) else None
            detail = bumpers is not None and r_px >= MIN_DETAIL_PX
            if detail and bumpers.phases is not None:
                dot = max(2, r_px // 3)
                pg.draw.circle(frame, PHASE_COLOURS[bumpers.phases[i]], (cx, cy), dot)
                pg.draw.circle(frame, INK, (cx, cy), dot, 1)
            if detail and heading is not None:
                self._draw_bumper(pg, frame, (cx, cy), r_px, heading, float(bumpers.arc),
                                  bool(bumpers.pressed[i]))
            if heading is not None:
                length = r_px + max(5, 0.6 * r_px)
                tip = (
                    round(cx + length * math.cos(heading)),
                    round(cy - length * math.sin(heading)),
                )
                pg.draw.line(frame, INK, (cx, cy), tip, 2 if r_px >= 5 else 1)
        if bumpers is None:
            return
        for point in np.asarray(bumpers.contacts, dtype=np.float64):
            if np.all(np.isfinite(point)):
                (px, py), = self._ipx(point[None])
                size = max(3, self._line + 1)
                pg.draw.circle(frame, CONTACT, (px, py), size)
                pg.draw.circle(frame, INK, (px, py), size + 1, 1)
        if bumpers.phases is not None and len(pos) <= MAX_PHASE_LABELS:
            self._draw_phase_labels(pg, frame, pos, rad, bumpers.phases)

    def _draw_bumper(self, pg, frame, centre, r_px, heading, arc, pressed) -> None:
        """The bumper: a band along the rim, ``arc`` degrees centred on ``heading``."""
        width = max(2, r_px // 4)
        colour = BUMPER_PRESSED if pressed else BUMPER
        if arc >= 360.0:
            pg.draw.circle(frame, colour, centre, r_px, width)
            return
        half = math.radians(arc) / 2
        angles = np.linspace(heading - half, heading + half, max(3, int(arc / 6) + 1))
        cx, cy = centre
        outer = [(round(cx + r_px * math.cos(a)), round(cy - r_px * math.sin(a)))
                 for a in angles]
        inner = [(round(cx + (r_px - width) * math.cos(a)), round(cy - (r_px - width) * math.sin(a)))
                 for a in angles[::-1]]
        pg.draw.polygon(frame, colour, outer + inner)

    def _draw_phase_labels(self, pg, frame, pos, rad, phases) -> None:
        font = self._get_font(pg)
        if font is None:
            return
        for i, name in enumerate(phases):
            if not np.all(np.isfinite(pos[i])):
                continue
            (cx, cy), = self._ipx(pos[i : i + 1])
            r_px = max(MIN_ROBOT_PX, round(rad[i] * self.scale))
            text = font.render(name, True, INK)
            box = pg.Surface((text.get_width() + 4, text.get_height()), pg.SRCALPHA)
            box.fill(LABEL_BOX)
            box.blit(text, (2, 0))
            w, h = box.get_size()
            x = cx + r_px + 3  # to the right, or to the left where the frame ends
            x = x if x + w <= self.width else cx - r_px - 3 - w
            y = min(cy + r_px // 2, self.height - h)
            frame.blit(box, (x, y))

    def _draw_labels(self, pg, frame, labels) -> None:
        font = self._get_font(pg)
        if font is None:
            return
        rendered = [font.render(str(line), True, INK) for line in labels]
        pad = 4
        w = max(s.get_width() for s in rendered) + 2 * pad
        h = sum(s.get_height() for s in rendered) + 2 * pad
        box = pg.Surface((w, h), pg.SRCALPHA)
        box.fill(LABEL_BOX)
        frame.blit(box, (2, 2))
        y = 2 + pad
        for s in rendered:
            frame.blit(s, (2 + pad, y))
            y += s.get_height()

    # -- human mode ---------------------------------------------------------------------------
    def show(self, frame: np.ndarray, fps: float | None = None) -> None:
        """Show ``frame`` in a window (opened on first use) and wait to keep ``fps``.

        Initialises only ``pygame.display``. Events are pumped so the window stays responsive.
        """
        img = np.asarray(frame)
        if img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
            raise ConfigError(
                f"frame must be a (H, W, 3) uint8 array, got shape {img.shape} dtype {img.dtype}"
            )
        pg = _import_pygame()
        size = (img.shape[1], img.shape[0])
        if self._screen is None or not pg.display.get_init() or self._screen.get_size() != size:
            if not pg.display.get_init():
                pg.display.init()
            self._screen = pg.display.set_mode(size)
            pg.display.set_caption(f"bounce_gym: {self.world.name}")
        if self._clock is None:
            self._clock = pg.time.Clock()
        surface = pg.surfarray.make_surface(np.ascontiguousarray(img.transpose(1, 0, 2)))
        self._screen.blit(surface, (0, 0))
        pg.event.pump()
        pg.display.flip()
        if fps:
            self._clock.tick(fps)

    def close(self) -> None:
        """Close the window if one was opened (quits ``pygame.display``). Safe to call twice."""
        if self._screen is not None:
            self._screen = None
            self._clock = None
            import pygame

            if pygame.display.get_init():
                pygame.display.quit()
