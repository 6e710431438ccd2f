"""The patrol graph of a World (Alam 2018, thesis §4.3); it lives in
`bounce_gym.cells.patrol_graph` (the patrol environment builds on it) and is re-exported here."""

from bounce_gym.cells.patrol_graph import DEFAULT_CORNER_RULE, cell_graph

__all__ = ["DEFAULT_CORNER_RULE", "cell_graph"]
