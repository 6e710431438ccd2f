"""Coverage: match a target distribution over cells."""

from __future__ import annotations

import numpy as np

from bounce_gym.envs.tasks.base import Task, path_samples, tick_length
from bounce_gym.errors import ConfigError
from bounce_gym.validate import number, numbers


class CoverageTask(Task):
    """Cover the world to match a target distribution over cells.

    Args:
        target: None (uniform over free cells), an array (rows, cols) with row 0 at the bottom
            (the layout of `World.occupancy`), or a path to a ``.npy`` file of that array.
            Non-negative, positive total, zero on blocked cells; it is normalised to sum 1.
        cell_size: grid cell size (default: the step length, the cell of the papers' model):
            from 1e-4 times the world's diameter to the diameter, and at most 2^20 cells of the
            bounding box (`bounce_gym.worlds.World.check_grid`).
        coverage_weight: reward = coverage_weight × (fraction of free cells newly visited)
            + distance_weight × (decrease of the L2 distance to the target).
        distance_weight: see ``coverage_weight``.

    ``info`` reports ``coverage`` (fraction of free cells visited), ``distance`` (L2 between the
    normalised visit histogram — time spent per cell — and the target) and ``tv_distance``.
    """

    name = "coverage"

    def __init__(self, target: object = None, cell_size: float | None = None,
                 coverage_weight: float = 1.0, distance_weight: float = 1.0) -> None:
        self.target_arg = target
        self.cell_size_arg = cell_size if cell_size is None else number(
            "cell_size", cell_size, minimum=0.0, strict=True)
        self.coverage_weight = number("coverage_weight", coverage_weight)
        self.distance_weight = number("distance_weight", distance_weight)

    def configure(self, core) -> None:
        super().configure(core)
        options = self.options
        self.cell_size = float(self.cell_size_arg or options.step_length)
        field = "task_kwargs.cell_size" if self.cell_size_arg else "step_length"
        options.world.check_length(field, self.cell_size)
        options.world.check_grid(field, self.cell_size)
        self.free = options.world.occupancy(self.cell_size, options.robot_radius)
        if not self.free.any():
            raise ConfigError("coverage: the world has no free cell of this size for this robot")
        self.target = self._target(self.target_arg)
        #: ``distance`` of an episode's start: no visit yet
        self.initial_distance = float(np.hypot.reduce(self.target.ravel()))

    def _target(self, spec: object) -> np.ndarray:
        if spec is None:
            return self.free / self.free.sum()
        if isinstance(spec, str):
            try:
                spec = np.load(spec)
            except (OSError, ValueError) as exc:
                raise ConfigError(f"coverage target: cannot read {spec!r}: {exc}") from None
        target = numbers("coverage target", spec)
        if target.shape != self.free.shape:
            raise ConfigError(f"coverage target: expected shape {self.free.shape} (rows, cols of "
                              f"the cell grid), got {target.shape}")
        if np.any(target < 0) or target.sum() <= 0:
            raise ConfigError("coverage target: values must be finite, >= 0, with a positive sum")
        if np.any(target[~self.free] > 0):
            raise ConfigError("coverage target: puts mass on blocked cells")
        return target / target.sum()

    def reset(self, state, rng, options):
        self.visits = np.zeros(self.free.shape)
        self.visited = np.zeros(self.free.shape, dtype=bool)
        self.distance = self.initial_distance
        self._add(state.position, np.zeros(state.n_robots))
        return self._info()

    def cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) of the coverage grid's cell of each point (n, 2), clipped to the grid."""
        xmin, ymin = self.options.world.bounds[:2]
        col = np.clip(((points[:, 0] - xmin) / self.cell_size).astype(int), 0, self.free.shape[1] - 1)
        row = np.clip(((points[:, 1] - ymin) / self.cell_size).astype(int), 0, self.free.shape[0] - 1)
        return row, col

    def _add(self, points: np.ndarray, ticks: np.ndarray) -> int:
        row, col = self.cells(points)
        np.add.at(self.visits, (row, col), ticks)
        new = ~self.visited[row, col] & self.free[row, col]
        self.visited[row, col] = True
        return int(len(set(zip(row[new].tolist(), col[new].tolist(), strict=True))))

    def _info(self) -> dict:
        total = self.visits.sum()
        hist = self.visits / total if total > 0 else self.visits
        return {"coverage": float(self.visited[self.free].mean()),
                "distance": float(np.hypot.reduce((hist - self.target).ravel())),
                "tv_distance": float(0.5 * np.abs(hist - self.target).sum())}

    def step(self, state, events):
        _, points, ticks = path_samples(events, tick_length(self.options, events.heading),
                                        self.cell_size / 4)
        new_cells = self._add(points, ticks)
        info = self._info()
        reward = (self.coverage_weight * new_cells / self.free.sum()
                  + self.distance_weight * (self.distance - info["distance"]))
        self.distance = info["distance"]
        m = state.n_robots
        return np.full(m, reward / m), np.zeros(m, dtype=bool), info

    def render_layers(self):
        origin = self.options.world.bounds[:2]
        return {"heatmap": (self.visits.copy(), origin, self.cell_size)}


class CoverageHistograms:
    """`CoverageTask`'s bookkeeping for ``n`` episodes at once (the batched envs'): a visit
    histogram, a visited grid and the distance to the target per episode, with the task's
    formulas on arrays.

    Attributes:
        visits, visited: (n, rows, cols) time spent and whether visited, per episode.
        distance: (n,) each episode's last L2 distance to the target.
    """

    def __init__(self, task: CoverageTask, n: int) -> None:
        self.task, self.n = task, n
        shape = (n, *task.free.shape)
        self.visits = np.zeros(shape)
        self.visited = np.zeros(shape, dtype=bool)
        self.distance = np.zeros(n)
        self.n_free = task.free.sum()

    def info(self, rows: np.ndarray | slice = slice(None)) -> dict:
        """``coverage``, ``distance`` and ``tv_distance`` of the episodes ``rows``."""
        flat = self.visits[rows].reshape(-1, self.visits[0].size)
        total = flat.sum(axis=1)
        hist = np.where(total[:, None] > 0, flat / np.where(total > 0, total, 1.0)[:, None], flat)
        gap = hist - self.task.target.reshape(1, -1)
        return {"coverage": self.visited[rows][:, self.task.free].mean(axis=1),
                "distance": np.hypot.reduce(gap, axis=1),
                "tv_distance": 0.5 * np.abs(gap).sum(axis=1)}

    def visit(self, episode: np.ndarray, points: np.ndarray, spent: np.ndarray
              ) -> tuple[np.ndarray, dict]:
        """Add path samples (`path_samples`: ``points`` with their ``spent`` ticks) to their
        ``episode``'s histogram; returns each episode's reward (n,) — the coverage and distance
        terms of `CoverageTask` — and the `info` of every episode."""
        task = self.task
        row, col = task.cells(points)
        np.add.at(self.visits, (episode, row, col), spent)
        new = ~self.visited[episode, row, col] & task.free[row, col]
        self.visited[episode, row, col] = True
        cells = np.unique(np.ravel_multi_index((episode[new], row[new], col[new]),
                                               self.visits.shape))
        new_cells = np.bincount(cells // task.free.size, minlength=self.n)
        info = self.info()
        reward = (task.coverage_weight * new_cells / self.n_free
                  + task.distance_weight * (self.distance - info["distance"]))
        self.distance = info["distance"].copy()
        return reward, info
