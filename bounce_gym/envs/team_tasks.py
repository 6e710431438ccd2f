"""The multi-robot tasks (`FreeTask`, `CoverageTask`, `MonitoringTask`) over B teams of m robots
on the cell backend in tick mode, for `bounce_gym.envs.team_vector_env.TeamVectorEnv`.

A tick-mode step on the cell backend is one tick, in which each robot either moves to a king
neighbour, bumps in place, or waits in place (a command tick). The tasks' step formulas are
applied to that as arrays over the teams, with the single task's own helpers and arithmetic:

* coverage integrates every robot's path with `path_samples` over all B·m robots at once, each
  team on its own visit histogram (`CoverageTask` per team; reward split evenly);
* monitoring tabulates, per robot and cell, the ticks a move from that cell spends in the robot's
  region (the same `path_samples` points and sums a single step makes), and the tick of a robot
  that stays; a step is then a lookup, the contact penalty and the pairs of robots in one cell.

Each team's episode starts from the single task's own reset (`start` takes over what it holds).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import shapely

from bounce_gym.envs.tasks import CoverageTask, MonitoringTask
from bounce_gym.envs.tasks.base import path_samples, tick_length
from bounce_gym.envs.tasks.coverage import CoverageHistograms


class TeamFree:
    """No reward, never ends, no info. ``model``: the `CellModel`; ``m``: robots per team."""

    def __init__(self, task, n_teams: int, m: int, model) -> None:
        self.n, self.m = n_teams, m

    def start(self, b: int, task) -> None:
        """Take over team ``b``'s new episode from the single ``task`` just reset."""

    def step(self, start_p: np.ndarray, start_k: np.ndarray, drive: np.ndarray,
             bump: np.ndarray, cells) -> tuple[np.ndarray, dict]:
        """Rewards (B, m) and the step's task info (arrays over the teams) of a tick from cells
        (``start_p``, ``start_k``) in which robots ``drive`` moved and ``bump`` bumped, the
        teams now at ``cells`` (`TeamCells`)."""
        return np.zeros((self.n, self.m)), {}


class TeamCoverage(TeamFree):
    """`CoverageTask` with one visit histogram and visited grid per team
    (`CoverageHistograms`)."""

    def __init__(self, task: CoverageTask, n_teams: int, m: int, model) -> None:
        super().__init__(task, n_teams, m, model)
        self.single = task
        self.histograms = CoverageHistograms(task, n_teams)
        self.centres = model.centres
        self.bin_heading = np.arange(model.n_bins) * model.bin_width
        self.team = np.repeat(np.arange(n_teams), m)

    def start(self, b, task):
        h = self.histograms
        h.visits[b] = task.visits
        h.visited[b] = task.visited
        h.distance[b] = task.distance

    def info(self) -> dict:
        """``coverage``, ``distance`` and ``tv_distance`` of every team (`CoverageTask`'s)."""
        return self.histograms.info()

    def step(self, start_p, start_k, drive, bump, cells):
        task = self.single
        # the fields of `StepEvents` that `path_samples` reads, of all B·m robots in team order
        events = SimpleNamespace(ticks=1, start=self.centres.take(start_p.ravel(), axis=0),
                                 end=self.centres.take(cells.p.ravel(), axis=0),
                                 bumps=bump.ravel().astype(np.int64))
        heading = self.bin_heading.take(cells.k.ravel())
        robot, points, spent = path_samples(events, tick_length(task.options, heading),
                                            task.cell_size / 4)
        reward, info = self.histograms.visit(self.team.take(robot), points, spent)
        return np.repeat((reward / self.m)[:, None], self.m, axis=1), info


class TeamMonitoring(TeamFree):
    """`MonitoringTask` by lookup: per robot i and cell, the ticks a step spends in region i."""

    def __init__(self, task: MonitoringTask, n_teams: int, m: int, model) -> None:
        super().__init__(task, n_teams, m, model)
        self.penalty = task.contact_penalty
        opts = task.options
        self.n_cells, self.n_positions = model.n_cells, model.n_positions
        p, k = model.decode(np.arange(model.n_cells))
        target = model.targets[k, p]
        moves = np.flatnonzero(target >= 0)
        # every possible move, one tick, as a single step's `path_samples` sees a moving robot
        events = SimpleNamespace(ticks=1, start=model.centres[p[moves]],
                                 end=model.centres[target[moves]],
                                 bumps=np.zeros(len(moves), dtype=np.int64))
        row, points, ticks = path_samples(
            events, tick_length(opts, k[moves] * model.bin_width), opts.step_length / 4)
        #: (m, n_cells): ticks in robot i's region of a move from each cell (0 where none)
        self.move_time = np.zeros((m, model.n_cells))
        #: (m, n_positions): the tick of a robot that bumps or waits in each position cell
        self.stay_time = np.zeros((m, model.n_positions))
        for i, region in enumerate(task.regions):
            inside = shapely.intersects_xy(region, points[:, 0], points[:, 1])
            self.move_time[i, moves] = np.bincount(row, weights=ticks * inside,
                                                   minlength=len(moves))
            at = shapely.intersects_xy(region, model.centres[:, 0], model.centres[:, 1])
            self.stay_time[i] = 1.0 * at
        self.robot_base = np.arange(m)[None, :]
        #: per position cell, the grid cell (cell size = step length) encounters compare
        cell = np.floor((model.centres - opts.world.bounds[:2]) / opts.step_length)
        self.encounter_cell = np.unique(cell.astype(np.int64), axis=0, return_inverse=True)[1]
        self.pairs = np.triu(np.ones((m, m), dtype=bool), 1)

    def step(self, start_p, start_k, drive, bump, cells):
        moved = self.move_time.take(self.robot_base * self.n_cells
                                    + start_k * self.n_positions + start_p)
        stayed = self.stay_time.take(self.robot_base * self.n_positions + start_p)
        time_in = np.where(drive, moved, stayed)  # a tick-mode step has one tick
        contact = cells.blocked & (cells.contact_robot >= 0)
        together = self.encounter_cell.reshape(-1).take(cells.p)
        encounters = ((together[:, :, None] == together[:, None, :]) & self.pairs).sum(axis=(1, 2))
        info = {"in_region_fraction": time_in, "robot_contacts": contact.sum(axis=1),
                "encounters": encounters}
        return time_in - self.penalty * contact, info


#: the batched form of each task the team env takes
TEAM_TASKS = {"free": TeamFree, "coverage": TeamCoverage, "monitoring": TeamMonitoring}
