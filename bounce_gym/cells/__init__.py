"""The discrete (cell-to-cell) model of the bouncing robot (Alam, Bobadilla & Shell): position
cells × orientation bins with the unit-step map of one robot, the grid conflict rules of several
robots, and the joint cell model of m robots."""

from bounce_gym.cells.conflicts import crossing, crowded, resolve_moves, too_close
from bounce_gym.cells.joint import NEIGHBORS, JointCellModel
from bounce_gym.cells.model import CORNER_RULES, CellModel, king_offset

__all__ = ["CORNER_RULES", "NEIGHBORS", "CellModel", "JointCellModel", "crossing", "crowded",
           "king_offset", "resolve_moves", "too_close"]
