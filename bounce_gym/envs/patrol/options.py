"""The arguments of the patrol environment: their checks (each bad value is a `ConfigError`
naming the argument and what is allowed), the patrol strategy and the start vertices."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bounce_gym import validate
from bounce_gym.cells.model import CORNER_RULES
from bounce_gym.cells.visibility import RULES
from bounce_gym.envs.options import resolve_world
from bounce_gym.envs.patrol.board import PatrolBoard, build_board
from bounce_gym.errors import ConfigError

ADVERSARY_OBSERVES = ("strategy", "positions")
ILLEGAL_ACTIONS = ("stay", "error")
RENDER_MODES = ["human", "rgb_array"]
#: How far a strategy's rows may be from summing to 1.
ROW_SUM_TOLERANCE = 1e-8
#: Default number of patrollers when ``start`` does not fix it.
DEFAULT_PATROLLERS = 2


@dataclass(frozen=True)
class PatrolOptions:
    """The validated arguments of `bounce_gym.envs.patrol.env.PatrolEnv`."""

    board: PatrolBoard
    n_patrollers: int
    attack_time: int
    adversary_observes: str
    strategy: np.ndarray
    start: np.ndarray | None
    max_cycles: int
    illegal_action: str
    render_mode: str | None


def _choice(field: str, value: object, allowed: Sequence) -> object:
    if not (value is None or isinstance(value, str)) or value not in allowed:
        raise ConfigError(f"{field}: expected one of {list(allowed)}, got {value!r}")
    return value


def parse_options(world: object, cell_size: object, corner_rule: object,
                  n_patrollers: object, sensor_range: object, visibility_rule: object,
                  attack_time: object, adversary_observes: object, strategy: object,
                  start: object, max_cycles: object, illegal_action: object,
                  render_mode: object) -> PatrolOptions:
    """Check every argument (the cheap ones first) and build the board."""
    world = resolve_world(world)
    cell_size = validate.number("cell_size", cell_size, minimum=0.0, strict=True)
    corner_rule = _choice("corner_rule", corner_rule, CORNER_RULES)
    sensor_range = validate.number("sensor_range", sensor_range, minimum=0.0, strict=True)
    visibility_rule = _choice("visibility_rule", visibility_rule, RULES)
    max_cycles = validate.integer("max_cycles", max_cycles, 1)
    attack_time = validate.integer("attack_time", attack_time, 1, max_cycles)
    adversary_observes = _choice("adversary_observes", adversary_observes, ADVERSARY_OBSERVES)
    illegal_action = _choice("illegal_action", illegal_action, ILLEGAL_ACTIONS)
    render_mode = _choice("render_mode", render_mode, [None, *RENDER_MODES])
    if n_patrollers is not None:
        n_patrollers = validate.integer("n_patrollers", n_patrollers, 1)
    if start is not None and not _is_vector(start):
        raise ConfigError(f"start: expected None or a list of vertex indices, got {start!r}")
    if n_patrollers is None:
        n_patrollers = DEFAULT_PATROLLERS if start is None else len(start)
    board = build_board(world, cell_size, corner_rule, sensor_range, visibility_rule)
    if n_patrollers > board.n:
        raise ConfigError(f"n_patrollers: expected at most the {board.n} vertices of the graph "
                          f"(patrollers start on distinct vertices), got {n_patrollers}")
    if start is not None:
        start = check_start(start, board.n, n_patrollers)
    strategy = board.uniform_walk() if strategy is None else check_strategy(strategy, board)
    return PatrolOptions(board=board, n_patrollers=n_patrollers, attack_time=attack_time,
                         adversary_observes=adversary_observes, strategy=strategy, start=start,
                         max_cycles=max_cycles, illegal_action=illegal_action,
                         render_mode=render_mode)


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
