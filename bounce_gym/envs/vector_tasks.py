"""The single-robot tasks of `BounceVectorEnv`, for N envs at once, on arrays.

Each batched task keeps the per-env values its single-robot task keeps for one episode (goal,
potential, plan cost, visit histogram) as arrays over the N envs, and computes its rewards,
terminations and infos with the single task's own formulas, so the batch agrees with N separate
envs to the last bit.

``robots``: the `CellRobots` of the cell backend, else None (the kinematic backend). ``bounds``:
(low, high), the observation bounds of the task's features, which the batch clips them to when
drawn (as the single env clips its observation).
"""

from __future__ import annotations

import numpy as np

from bounce_gym.cells.geodesic import GridGeodesic
from bounce_gym.envs.goal_tables import NEAR_MARGIN, GoalTables, passes_near
from bounce_gym.envs.tasks import CoverageTask, NavigationTask
from bounce_gym.envs.tasks.base import StepEvents, path_samples, tick_length
from bounce_gym.envs.tasks.coverage import CoverageHistograms
from bounce_gym.envs.vector_cells import CellRobots

#: every env's rows of an array
EVERY = slice(None)


class FreeBatch:
    """No reward, never terminates."""

    #: whether `draw_cells` draws the episodes (without reset options)
    draws_cells = False

    def __init__(self, task, n: int, robots: CellRobots | None = None, bounds=None) -> None:
        self.n = n

    def draw_cells(self, rngs: list, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The start cells (position indices, bins) of envs ``rows``, each drawn from its
        generator in ``rngs`` with what else the task draws, as the single-robot task draws
        them (where `draws_cells`)."""
        raise NotImplementedError

    def drawn(self, i: int, task) -> None:
        """Take what the single-robot ``task`` drew for env ``i``'s new episode (its goal)."""

    def start(self, rows: np.ndarray, state, ticks: np.ndarray,
              robots: CellRobots | None = None) -> None:
        """Start the episodes of envs ``rows``, whose robots (``state``; their cells
        ``robots``) were placed and drove ``ticks`` to their first contact, as the single-robot
        task's reset starts one."""

    def info(self, state, rows: np.ndarray | slice = EVERY) -> dict:
        """Task info of envs ``rows`` (default: every env), for the robots' ``state``."""
        return {}

    def observation(self) -> np.ndarray | None:
        return None

    def step(self, state, events: StepEvents, ticks: np.ndarray,
             robots: CellRobots | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
        """Rewards, terminations and task info of a step whose ``events`` left the robots in
        ``state`` (their cells ``robots``) with ``ticks`` since their episodes began."""
        return np.zeros(self.n), np.zeros(self.n, dtype=bool), {}


class NavigationBatch(FreeBatch):
    """`NavigationTask` for N robots: goals, arrival, the rewards (`NavigationTask.step_rewards`,
    every ``reward`` option) and the plan cost.

    On the cell backend (where the model's tables fit, `GoalTables.fits`) arrival and Φ are
    lookups in `GoalTables`; a goal that is not a cell (a reset option off the cell centres)
    and the kinematic backend take the single task's exact test, run only on the envs whose
    heading is within tolerance and whose path passes near the goal.
    """

    def __init__(self, task: NavigationTask, n: int, robots: CellRobots | None = None,
                 bounds=None) -> None:
        super().__init__(task, n)
        self.single = task
        self.model = model = robots.model if robots is not None else None
        self.low, self.high = bounds
        self.draws_cells = model is not None and task.random_cells
        if model is not None and self.draws_cells and task.observe_task:
            # every cell's features as the start's and as the goal's pose, cast and clipped
            p, k = model.decode(np.arange(model.n_cells))
            pose = task.pose_features(model.centres[p], k * model.bin_width).astype(np.float32)
            half = pose.shape[1]
            self.start_features, self.goal_features = (
                self._bounded(pose, self.low[part], self.high[part])
                for part in (slice(None, half), slice(half, None)))
        self.tables = (GoalTables(robots, task)
                       if robots is not None and GoalTables.fits(robots, task) else None)
        self.goal_position = np.zeros((n, 2))
        self.goal_heading = np.zeros(n)
        self.goal_wrapped = np.zeros(n)  # the goal headings in [0, 2π)
        #: each env's goal as a cell of the tables (position index, bin; `GoalTables.off_cell`
        #: and -1 where the goal is not a cell), and where its arrival column starts in them
        self.goal_cell = np.full((n, 2), -1, dtype=np.int64)
        self.arrival_at = np.zeros(n, dtype=np.int64)
        self.off_cell = np.zeros(0, dtype=np.int64)  # the envs whose goal is not a cell
        self.reached = np.zeros(n, dtype=bool)
        self.plan_cost = np.zeros(n)
        self.features = np.zeros((n, task.observation_size), dtype=np.float32)
        self.rows = np.arange(n)
        if task.geodesic is not None:  # the progress reward
            self.potential_now = np.zeros(n)
            self.goal_node = np.zeros(n, dtype=np.int64)  # the grid node of each env's goal
            #: the grid node of each position index of the cell model
            self.node_of_position = (task.geodesic.node_of(model.centres)
                                     if model is not None else None)
            if self.tables is None:  # Φ of every grid node, per env
                self.potentials = np.zeros((n, task.geodesic.n_nodes))
            else:  # where each env's goal's Φ starts in the tables
                self.potential_at = np.zeros(n, dtype=np.int64)

    def draw_cells(self, rngs, rows):
        single, model = self.single, self.model
        # per env: the start's position index and bin, then the goal's
        drawn = np.array([single.random_cell(rng) + single.random_cell(rng) for rng in rngs],
                         dtype=np.int64).reshape(-1, 4)
        p, k, goal_p, goal_k = drawn.T
        self.goal_position[rows] = model.centres.take(goal_p, axis=0)
        self.goal_heading[rows] = goal_k * model.bin_width
        self.goal_cell[rows] = drawn[:, 2:]
        if single.geodesic is not None:
            self.goal_node[rows] = self.node_of_position.take(goal_p)
        if single.observe_task:
            half = self.start_features.shape[1]
            self.features[rows, :half] = self.start_features.take(model.cell_id(p, k), axis=0)
            self.features[rows, half:] = self.goal_features.take(model.cell_id(goal_p, goal_k),
                                                                 axis=0)
        return p, k

    def drawn(self, i, task):
        goal, heading = task.goal[0][0], float(task.goal[1][0])
        self.goal_position[i] = goal
        self.goal_heading[i] = heading
        if self.tables is not None:
            self.goal_cell[i] = self.tables.goal_cell(goal, heading)
        if task.geodesic is not None:
            self.goal_node[i] = task.geodesic.node_at(*goal.tolist())
        if task.observe_task:
            self.features[i] = self._bounded(task.observation(None)[0], self.low, self.high)

    def start(self, rows, state, ticks, robots=None):
        single, tables = self.single, self.tables
        self.reached[rows] = False
        self.plan_cost[rows] = single.w1 * ticks[rows]  # the drive of a bounce-mode reset
        nodes = self.goal_node[rows] if single.geodesic is not None else None
        if tables is not None:
            goal_p = self.goal_cell[rows, 0]
            tables.fill(goal_p, nodes)
            self.arrival_at[rows] = goal_p * tables.n_cells
            if len(self.off_cell) or (goal_p == tables.off_cell).any():
                self.off_cell = np.flatnonzero(self.goal_cell[:, 0] == tables.off_cell)
        if tables is None or len(self.off_cell):  # what the exact test reads
            self.goal_wrapped[rows] = np.mod(self.goal_heading[rows], 2 * np.pi)
        if single.geodesic is None:
            return
        if tables is not None:
            self.potential_at[rows] = nodes * tables.n_positions
            self.potential_now[rows] = tables.potential.take(
                self.potential_at[rows] + robots.p[rows])
            return
        self.potentials[rows] = [single.goal_potentials(goal) for goal in nodes.tolist()]
        self.potential_now[rows] = self._potentials_at(rows, self._nodes(
            single.geodesic, state.position[rows], None if robots is None else robots.p[rows]))

    def _potentials_at(self, rows: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """Φ of envs ``rows`` at grid nodes ``nodes`` (``self.potentials[rows, nodes]``, gathered
        from the flat array: several times faster than two-axis fancy indexing)."""
        return self.potentials.reshape(-1).take(rows * self.potentials.shape[1] + nodes)

    def _nodes(self, geodesic: GridGeodesic, position: np.ndarray,
               positions: np.ndarray | None) -> np.ndarray:
        """The grid nodes of robots at ``position``, or at position indices ``positions``."""
        if positions is None or self.node_of_position is None:
            return geodesic.node_of(position)
        return self.node_of_position.take(positions)

    def info(self, state, rows=EVERY):
        goal = self.goal_position[rows]  # a copy where ``rows`` is an array
        gap = state.position[rows] - goal
        return {"goal_position": goal.copy() if rows is EVERY else goal,
                "goal_heading": self.goal_heading[rows].copy(),
                "distance_to_goal": np.hypot(gap[:, 0], gap[:, 1]),
                "is_success": self.reached[rows].copy(),
                "plan_cost": self.plan_cost[rows].copy()}

    @staticmethod
    def _bounded(features: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        """``features`` clipped to [``low``, ``high``] (np.clip's arithmetic)."""
        return np.minimum(np.maximum(features, low), high)

    def observation(self):
        return self.features if self.single.observe_task else None

    def step(self, state, events, ticks, robots=None):
        single, tables = self.single, self.tables
        hits, arrivals = self._arrivals(events, robots)
        hit = np.zeros(self.n, dtype=bool)
        hit[hits] = True
        changed = events.angle_changed
        spent = events.ticks.astype(np.float64)
        hit_ticks = events.ticks[hits]
        spent[hits] = np.minimum(hit_ticks, arrivals)
        before = after = None
        if single.geodesic is not None:
            before = self.potential_now
            if tables is not None:
                after = tables.potential.take(self.potential_at + robots.p)
            else:
                after = self._potentials_at(self.rows, self._nodes(
                    single.geodesic, events.end, None if robots is None else robots.p))
            self.potential_now = np.where(hit, 0.0, after)
        reward = single.step_rewards(spent, changed, hit, before, after)
        self.plan_cost = self.plan_cost + single.plan_cost_of(spent, changed)
        self.reached |= hit
        info = self.info(state)
        info["angle_changed"] = changed
        if len(hits):
            to_goal = np.zeros(self.n, dtype=np.int64)
            to_goal[hits] = ticks[hits] - hit_ticks + arrivals
            info["ticks_to_goal"] = (to_goal, hit)
        return reward, self.reached.copy(), info

    def _arrivals(self, events, robots: CellRobots | None) -> tuple[np.ndarray, np.ndarray]:
        """The envs whose robot reached its goal in this step (``events``, a `StepEvents` of
        arrays), and the ticks into the step at which each did (float64)."""
        tables = self.tables
        if tables is None or robots is None:
            return self._exact_arrivals(events, self.rows)
        drive = tables.arrival.take(self.arrival_at + robots.turned)
        near = np.flatnonzero(drive >= 0)
        if len(near):  # the heading half of the test, per (drive bin, goal bin)
            turned = robots.turned.take(near)
            near = near[tables.aligned.take(turned // tables.n_positions * tables.n_bins
                                            + self.goal_cell[near, 1])]
        hits, arrivals = near, events.bumps.take(near) + drive.take(near).astype(np.float64)
        if len(self.off_cell):
            more, later = self._exact_arrivals(events, self.off_cell)
            hits, arrivals = np.concatenate((hits, more)), np.concatenate((arrivals, later))
        return hits, arrivals

    def _exact_arrivals(self, events, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`_arrivals` among envs ``rows`` by the single task's exact test of a lone robot, run
        only where the heading is about within tolerance (headings and wrapped goal headings
        lie in [0, 2π], so their gap needs no wrapping; the margin lies far above rounding) and
        the path passes near the goal."""
        single = self.single
        hits, arrivals = [], []
        gap = np.abs(events.heading.take(rows) - self.goal_wrapped.take(rows))
        tolerance = single.heading_tolerance + 1e-9
        aligned = rows[(gap <= tolerance) | (gap >= 2 * np.pi - tolerance)]
        for i in aligned[self._near_goal(events, aligned)].tolist():
            one = StepEvents(ticks=int(events.ticks[i]), start=events.start[i:i + 1],
                             end=events.end[i:i + 1], heading=events.heading[i:i + 1],
                             bumps=events.bumps[i:i + 1], angles=events.angles[i:i + 1],
                             angle_changed=events.angle_changed[i:i + 1],
                             robot_contact=events.robot_contact[i:i + 1])
            found = single.ticks_to_goal(
                one, (self.goal_position[i:i + 1], self.goal_heading[i:i + 1]))
            if found is not None:
                hits.append(i)
                arrivals.append(found)
        return np.array(hits, dtype=np.int64), np.array(arrivals, dtype=np.float64)

    def _near_goal(self, events: StepEvents, rows: np.ndarray) -> np.ndarray:
        """(len(rows),) bool: the step's segment of envs ``rows`` comes near the goal (a
        superset of the robots the exact disk test can accept, `passes_near`)."""
        return passes_near(events.start.take(rows, axis=0), events.end.take(rows, axis=0),
                           self.goal_position.take(rows, axis=0),
                           self.single.goal_radius + NEAR_MARGIN)


class CoverageBatch(FreeBatch):
    """`CoverageTask` for N robots: one visit histogram and visited grid per env
    (`CoverageHistograms`)."""

    def __init__(self, task: CoverageTask, n: int, robots: CellRobots | None = None,
                 bounds=None) -> None:
        super().__init__(task, n)
        self.single = task
        self.histograms = CoverageHistograms(task, n)

    def start(self, rows, state, ticks, robots=None):
        h = self.histograms
        h.visits[rows] = 0.0
        h.visited[rows] = False
        row, col = self.single.cells(state.position[rows])
        h.visited[rows, row, col] = True
        h.distance[rows] = self.single.initial_distance

    def info(self, state, rows=EVERY):
        return self.histograms.info(rows)

    def step(self, state, events, ticks, robots=None):
        task = self.single
        robot, points, spent = path_samples(events, tick_length(task.options, events.heading),
                                            task.cell_size / 4)
        reward, info = self.histograms.visit(robot, points, spent)
        return reward, np.zeros(self.n, dtype=bool), info


#: the batched task of each single-robot task name
BATCHED = {"free": FreeBatch, "navigation": NavigationBatch, "coverage": CoverageBatch}
