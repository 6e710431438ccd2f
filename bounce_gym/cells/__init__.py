"""The discrete (cell-to-cell) model of the bouncing robot: cells, the simple and generalized
cell mappings (SCM, GCM), shared by the planners and the ``cell`` backend."""

from bounce_gym.cells.conflicts import crowded, resolve_moves, too_close
from bounce_gym.cells.model import CORNER_RULES, CellModel, king_offset

__all__ = ["CORNER_RULES", "CellModel", "crowded", "king_offset", "resolve_moves", "too_close"]
