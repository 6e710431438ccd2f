"""The keyword arguments of the patrol environment, declared once: `PatrolOptions`, whose
validation also builds the patrol board and checks the patrol strategy and the start vertices
against it (each bad value is a `ConfigError` naming the argument and what is allowed).
`bounce_gym.envs.arguments.json_schema` gives an env's JSON Schema."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    Field,
    PrivateAttr,
    SkipValidation,
    ValidationInfo,
    WithJsonSchema,
    field_validator,
    model_validator,
)

from bounce_gym import validate
from bounce_gym.cells.model import CORNER_RULES
from bounce_gym.cells.visibility import RULES
from bounce_gym.envs.arguments import Accepts, Arguments, Integer, Real, needs
from bounce_gym.envs.options import resolve_world
from bounce_gym.envs.patrol.board import PatrolBoard, build_board
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

#: How far a strategy's rows may be from summing to 1.
ROW_SUM_TOLERANCE = 1e-8
#: Default number of patrollers when ``start`` does not fix it.
DEFAULT_PATROLLERS = 2
#: The most cells of the patrol grid (`cell_size`): the strategy and the visibility are dense
#: (n, n) matrices of its n free cells (4096 cells: 128 MiB of strategy).
MAX_PATROL_CELLS = 4096
#: The most (cell, cell within range) lines of sight the board's visibility checks
#: (`sensor_range`): 2^22, about 0.4 GB at the peak of the check.
MAX_SIGHT_PAIRS = 1 << 22


class PatrolOptions(Arguments):
    """The validated arguments of `bounce_gym.envs.patrol.env.PatrolEnv`; from them the patrol
    board (`board`), the strategy as a matrix (`walk`) and the start vertices (`start_vertices`)."""

    world: Annotated[World, Accepts(SkipValidation[str | os.PathLike | World]), WithJsonSchema(
        {"type": "string"}), Field(description=(
            "The map whose free cells are the graph's vertices: a zoo name, a map file path or "
            "a `World`."))] = "patrol_15x15"
    cell_size: Annotated[Real, Field(gt=0.0, description=(
        "Side of a cell, in world units: from 1e-4 times the world's diameter to the diameter, "
        "and at most 4096 cells of the bounding box (the strategy is a dense vertices x "
        "vertices matrix)."))] = 1.0
    corner_rule: Annotated[Literal[CORNER_RULES], Field(description=(
        "Which diagonal moves past corners are edges (`bounce_gym.cells.model`; 'strict': no "
        "corner cutting)."))] = "strict"
    sensor_range: Annotated[Real, Field(gt=0.0, description=(
        "Range l of each patroller's omnidirectional sensor, in cells (the limited visibility "
        "polygon of thesis Eq. 4.1), at most the grid's diagonal (a longer range sees no "
        "more), and at most 2^22 lines of sight to check (grid cells x cells within "
        "range)."))] = 6.0
    visibility_rule: Annotated[Literal[RULES], Field(description=(
        "When a cell counts as seen: 'corners' or 'centre' (`bounce_gym.cells.visibility`)."))] = \
        "corners"
    max_cycles: Annotated[Integer, Field(ge=1, description=(
        "Steps after which every episode has ended."))] = 500
    attack_time: Annotated[Integer, Field(ge=1, description=(
        "t_a: the steps the adversary needs undetected, at most `max_cycles`."))] = 20
    adversary_observes: Annotated[Literal["strategy", "positions"], Field(description=(
        "'strategy': the adversary sees the capture probabilities of the strategy, its attack "
        "and the clock; 'positions': also which vertices a patroller occupies."))] = "strategy"
    illegal_action: Annotated[Literal["stay", "error"], Field(description=(
        "'stay': a move along a missing edge leaves the patroller where it is, and an "
        "adversary's start after the attack began is a wait (both flagged in "
        "`info['illegal_action']`); 'error': `ActionError` naming the agent and its legal "
        "actions."))] = "stay"
    start: Annotated[SkipValidation[Sequence[int] | None], Field(description=(
        "One start vertex per patroller (None: distinct vertices drawn uniformly each episode); "
        "per episode also with reset(options={'start': [...]})."))] = None
    n_patrollers: Annotated[int, Accepts(Integer | None), Field(ge=1, description=(
        "m, the number of patrollers, on distinct vertices (None: the length of `start`, or "
        "2)."))] = None
    strategy: Annotated[SkipValidation[Any], WithJsonSchema(
        {"type": ["array", "null"], "items": {"type": "array", "items": {"type": "number"}}}),
        Field(description=(
            "The patrol strategy: an n x n row-stochastic matrix (dense or scipy-sparse) over "
            "the vertices that moves only along edges (None: the uniform random walk); per "
            "episode also with reset(options={'strategy': P})."))] = None

    _board: PatrolBoard = PrivateAttr()
    _walk: np.ndarray = PrivateAttr()
    _start: np.ndarray | None = PrivateAttr()

    @field_validator("world")
    @classmethod
    def _world(cls, value: object) -> World:
        return resolve_world(value)

    @field_validator("cell_size")
    @classmethod
    def _cell_size(cls, value: float, info: ValidationInfo) -> float:
        [world] = needs(info, "world")
        world.check_length("cell_size", value)
        world.check_grid("cell_size", value, MAX_PATROL_CELLS)
        return value

    @field_validator("sensor_range")
    @classmethod
    def _range(cls, value: float, info: ValidationInfo) -> float:
        world, cell_size = needs(info, "world", "cell_size")
        rows, cols = world.grid_shape(cell_size)
        diagonal = math.hypot(rows, cols)
        if value > diagonal:
            raise ConfigError(f"sensor_range: expected cells in (0, {diagonal:.4g}] (the "
                              f"diagonal of the grid of world {world.name!r} at cell_size "
                              f"{cell_size:g}), got {value!r}")
        span = math.ceil(value)  # the offsets `cell_visibility` checks from every cell
        dy, dx = np.mgrid[-span:span + 1, -span:span + 1]
        pairs = rows * cols * int(np.count_nonzero(np.hypot(abs(dx) + 0.5, abs(dy) + 0.5)
                                                   <= value))
        if pairs > MAX_SIGHT_PAIRS:
            raise ConfigError(f"sensor_range: {value:g} cells on the {rows} x {cols} grid of world "
                              f"{world.name!r} means checking {pairs:,} lines of sight; at most "
                              f"{MAX_SIGHT_PAIRS:,}: a shorter range or larger cells")
        return value

    @field_validator("attack_time")
    @classmethod
    def _attack_time(cls, value: int, info: ValidationInfo) -> int:
        return validate.integer("attack_time", value, 1, *needs(info, "max_cycles"))

    @field_validator("start")
    @classmethod
    def _start_list(cls, value: object) -> object:
        if value is not None and not _is_vector(value):
            raise ConfigError(f"start: expected None or a list of vertex indices, got {value!r}")
        return value

    @field_validator("n_patrollers")
    @classmethod
    def _patrollers(cls, value: int | None, info: ValidationInfo) -> int:
        [start] = needs(info, "start")
        if value is not None:
            return value
        return DEFAULT_PATROLLERS if start is None else len(start)

    @model_validator(mode="after")
    def _on_the_board(self) -> PatrolOptions:
        """Build the board; the patrollers, start and strategy must fit its graph."""
        board = build_board(self.world, self.cell_size, self.corner_rule, self.sensor_range,
                            self.visibility_rule)
        if self.n_patrollers > board.n:
            raise ConfigError(f"n_patrollers: expected at most the {board.n} vertices of the "
                              f"graph (patrollers start on distinct vertices), got "
                              f"{self.n_patrollers}")
        self._board = board
        self._start = None if self.start is None else \
            check_start(self.start, board.n, self.n_patrollers)
        self._walk = board.uniform_walk() if self.strategy is None else \
            check_strategy(self.strategy, board)
        return self

    @property
    def board(self) -> PatrolBoard:
        """The cell graph, its neighbour table and visibility at ``sensor_range``."""
        return self._board

    @property
    def walk(self) -> np.ndarray:
        """The strategy as a read-only (n, n) row-stochastic float64 matrix."""
        return self._walk

    @property
    def start_vertices(self) -> np.ndarray | None:
        """``start`` as an (m,) int64 array of vertices, or None."""
        return self._start



def _is_vector(value: object) -> bool:
    return isinstance(value, Sequence | np.ndarray) and not isinstance(value, str | bytes)


def check_start(start: object, n: int, m: int, field: str = "start") -> np.ndarray:
    """``start`` as an (m,) int64 array of vertices in [0, n)."""
    if not _is_vector(start) or len(start) != m:
        raise ConfigError(f"{field}: expected {m} vertex indices, one per patroller, got "
                          f"{start!r}")
    return np.array([validate.integer(f"{field}[{i}]", v, 0, n - 1)
                     for i, v in enumerate(start)], dtype=np.int64)


def check_strategy(strategy: object, board: PatrolBoard, field: str = "strategy") -> np.ndarray:
    """``strategy`` (a dense or scipy-sparse n×n matrix over the graph's vertices) as a
    read-only float64 array, if it is row-stochastic and moves only along edges: a patroller
    moves to an adjacent vertex every step (thesis §4.3), so ``P[v, u] > 0`` needs the edge
    (v, u); only a vertex without edges keeps its walker (``P[v, v] = 1``)."""
    n = board.n
    dense = strategy.toarray() if hasattr(strategy, "toarray") else strategy
    try:
        P = validate.numbers(field, dense)
    except ConfigError:
        raise ConfigError(f"{field}: expected an {n}x{n} matrix of probabilities (None for the "
                          f"uniform random walk), got {type(strategy).__name__}") from None
    if P.shape != (n, n):
        raise ConfigError(f"{field}: expected an {n}x{n} matrix over the graph's vertices, got "
                          f"shape {P.shape}")
    if (P < 0).any():
        v, u = np.argwhere(P < 0)[0]
        raise ConfigError(f"{field}: probabilities must be >= 0, got P[{v}, {u}] = {P[v, u]}")
    sums = P.sum(axis=1)
    bad = np.flatnonzero(np.abs(sums - 1.0) > ROW_SUM_TOLERANCE)
    if len(bad):
        raise ConfigError(f"{field}: every row must sum to 1, row {bad[0]} sums to "
                          f"{sums[bad[0]]!r}")
    allowed = board.uniform_walk() > 0
    off = np.argwhere((P > 0) & ~allowed)
    if len(off):
        v, u = off[0]
        raise ConfigError(f"{field}: P[{v}, {u}] = {P[v, u]} > 0 but ({v}, {u}) is not an edge "
                          f"of the graph (a patroller moves along an edge every step)")
    P.flags.writeable = False
    return P
