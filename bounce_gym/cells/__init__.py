"""The discrete (cell-to-cell) model of the bouncing robot (Alam, Bobadilla & Shell): position
cells × orientation bins with the unit-step map of one robot, the grid conflict rules of several
robots, the joint cell model of m robots, and the drifter cells of a layered flow (thesis ch. 5)."""

from bounce_gym.cells.conflicts import CloseCells, crossing, crowded, resolve_moves, too_close
from bounce_gym.cells.drifter import ACTIONS, DOWN, DRIFT, UP, DrifterCells
from bounce_gym.cells.joint import NEIGHBORS, JointCellModel
from bounce_gym.cells.model import CORNER_RULES, CellModel, king_offset, king_step

__all__ = ["ACTIONS", "CORNER_RULES", "DOWN", "DRIFT", "NEIGHBORS", "UP", "CellModel",
           "CloseCells", "DrifterCells", "JointCellModel", "crossing", "crowded", "king_offset",
           "king_step", "resolve_moves", "too_close"]
