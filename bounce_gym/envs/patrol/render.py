"""Drawing the patrol environment: the free cells, each patroller's visible cells shaded in its
colour, the patrollers, the attacked cell (deeper red as the attack goes on) and the outcome.

`PatrolRenderer` is a `Renderer` of the board's World, so frames, the human window, labels and
pickling work as for the other environments.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.envs.patrol.board import PatrolBoard
from bounce_gym.envs.render.renderer import Renderer, _import_pygame, robot_colour

ATTACK = (200, 30, 40)
#: alpha of a patroller's visible cells
SEEN_ALPHA = 55
#: patroller radius as a fraction of the cell side
PATROLLER_RADIUS = 0.3


class PatrolRenderer(Renderer):
    """Frames of a `PatrolBoard` (see the module docstring)."""

    def __init__(self, board: PatrolBoard, width: int = 640, margin: int = 16) -> None:
        super().__init__(board.world, width, margin, grid=False)
        self.board = board
        self.cell_size = float(board.graph.graph["cell_size"])
        xmin, ymin = board.world.bounds[:2]
        rows, cols = board.visibility.cells.T
        left, bottom = xmin + cols * self.cell_size, ymin + rows * self.cell_size
        self.centres = np.column_stack((left, bottom)) + 0.5 * self.cell_size
        top_left = np.floor(self.to_pixels(np.column_stack((left, bottom + self.cell_size))))
        bottom_right = np.ceil(self.to_pixels(np.column_stack((left + self.cell_size, bottom))))
        #: (n, 4) pixel rectangles (left, top, width, height) of the cells
        self.rects = np.column_stack((top_left, bottom_right - top_left)).astype(int)

    def draw_patrol(self, positions: np.ndarray, target: int, progress: float,
                    labels: list[str]) -> np.ndarray:
        """One RGB frame: the patrollers at ``positions`` (vertices) with what they see, the
        ``target`` vertex (-1: none) shaded by ``progress`` in [0, 1], and ``labels``."""
        pg = _import_pygame()
        if self._static is None:
            self._build_static(pg)
        frame = self._frame
        frame.blit(self._static, (0, 0))
        overlay = self._clear_overlay()
        for i, v in enumerate(positions):
            colour = (*robot_colour(i), SEEN_ALPHA)
            for z in np.flatnonzero(self.board.seen[v]):
                pg.draw.rect(overlay, colour, self.rects[z].tolist())
        if target >= 0:
            rect = self.rects[target].tolist()
            pg.draw.rect(overlay, (*ATTACK, round(60 + 170 * progress)), rect)
            pg.draw.rect(overlay, (*ATTACK, 255), rect, 2)
        frame.blit(overlay, (0, 0))
        m = len(positions)
        self._draw_robots(pg, frame, self.centres[positions], None,
                          np.full(m, PATROLLER_RADIUS * self.cell_size), np.zeros(m, dtype=bool))
        self._draw_labels(pg, frame, labels)
        return np.ascontiguousarray(pg.surfarray.array3d(frame).transpose(1, 0, 2))
