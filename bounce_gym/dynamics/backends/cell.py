"""The ``cell`` backend: robots step exactly the papers' discrete cell-to-cell model.

Positions are cell centres and headings bin centres of a `bounce_gym.cells.CellModel` built with
cell size = ``step_length`` (and the C-space of ``radius``). One tick moves every unblocked robot to
its king-move target cell; a robot whose target is blocked is ``blocked`` and its next tick is a
bump (the controller rotates it by whole bins). With one robot and exact noise, the tick stream is
exactly the simple cell mapping C of `CellModel.successor`, so analytic plans and filters execute
exactly; with `Reliable` noise the bump rows follow the GCM matrix.

Several robots: the grid conflict rules of `bounce_gym.cells.conflicts` (thesis Eq. 3.9 and
docs/choices/multirobot.md, "Robot–robot conflicts on the grid"), the same function the multi-robot planners
use, with its ``min_sep_cells`` option.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.cells import CellModel, crowded, resolve_moves, too_close
from bounce_gym.dynamics.backends.base import MotionBackend
from bounce_gym.dynamics.state import NO_CONTACT, RobotState
from bounce_gym.errors import ConfigError


class CellBackend(MotionBackend):
    """Discrete motion on the cell grid (see the module docstring).

    Extra args: ``n_bins`` orientation bins (a divisor of 360, default 8), ``corner_rule``
    (see `bounce_gym.cells.model`) and ``min_sep_cells`` (colliding robots: the Chebyshev
    distance at or below which they collide, 0 = the same cell; `bounce_gym.cells.conflicts`).
    """

    name = "cell"
    point_robots_collide = True

    def __init__(self, world, n_robots, radius, step_length, robot_collisions,
                 n_bins: int = 8, corner_rule: str = "target_only",
                 min_sep_cells: int = 0) -> None:
        super().__init__(world, n_robots, radius, step_length, robot_collisions)
        self.model = CellModel(world, step_length, n_bins, radius, corner_rule)
        self.bin_width = self.model.bin_width
        if self.collide and self.model.n_positions < n_robots:
            raise ConfigError(f"n_robots: {n_robots} robots do not fit in "
                              f"{self.model.n_positions} free cells")
        close = too_close(self.model.position_rc, min_sep_cells)  # validates it
        self.min_sep_cells = int(min_sep_cells)
        self.close = close if self.collide and self.min_sep_cells > 0 else None

    # -- placement --------------------------------------------------------------------------
    def random_positions(self, rng: np.random.Generator) -> np.ndarray:
        """Uniformly random free cells (distinct ones when robots collide; at least
        ``min_sep_cells`` + 1 apart, by rejection)."""
        for _ in range(10_000):
            cells = rng.choice(self.model.n_positions, self.n_robots, replace=not self.collide)
            if not (self.collide and crowded(cells, self.close)[0]):
                return self.model.centres[cells].copy()
        raise ConfigError(f"could not place {self.n_robots} robots min_sep_cells = "
                          f"{self.min_sep_cells} apart in world {self.world.name!r}")

    def cells(self, state: RobotState) -> np.ndarray:
        """The cell number of every robot."""
        return self.model.cell_of(state.position, state.heading)

    def reset(self, state: RobotState) -> None:
        self.place(state, np.arange(state.n_robots))

    def place(self, state: RobotState, robots: np.ndarray) -> None:
        """Take over robots ``robots`` of ``state``, just placed, while the others keep their
        poses (`reset` places every robot): snap them to their cells' centres and bin headings
        (`ConfigError` for a pose outside the model's free cells) and set every contact."""
        z = self.model.cell_of(state.position[robots], state.heading[robots])
        if np.any(z < 0):
            bad = int(robots[np.flatnonzero(z < 0)[0]])
            raise ConfigError(f"start position of robot {bad} {state.position[bad].tolist()} is "
                              "not in a free cell of the cell model")
        p, k = self.model.decode(z)
        if self.collide and crowded(self.model.decode(self.cells(state))[0], self.close)[0]:
            raise ConfigError(f"start positions: two robots share a cell or are within "
                              f"min_sep_cells = {self.min_sep_cells} cells")
        state.position[robots] = self.model.centres[p]  # snap to cell centres and bin headings
        state.heading[robots] = k * self.bin_width
        self.update_contacts(state, np.arange(state.n_robots))

    # -- contacts ---------------------------------------------------------------------------
    def _plan(self, state: RobotState) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(position index, target index or -1, blocking robot or -1) for every robot."""
        p, k = self.model.decode(self.cells(state))
        target = self.model.targets[k, p]
        if not self.collide:
            return p, target, np.full(len(p), NO_CONTACT, dtype=np.int64)
        stays, blocker, _ = resolve_moves(p[None], target[None], self.model.position_rc,
                                         self.close)
        return p, np.where(stays[0], -1, target), blocker[0]

    def update_contacts(self, state: RobotState, robots: np.ndarray) -> None:
        if not self.collide and len(robots) < state.n_robots:
            self._update_independent(state, np.asarray(robots, dtype=np.int64))
            return
        # blocking on the grid is a joint property of all robots: recompute for everyone
        state.heading[:] = self.model.bin_of(state.heading) * self.bin_width  # exact bins
        p, target, blocker = self._last_plan = self._plan(state)
        state.blocked[:] = target < 0
        state.contact_robot[:] = np.where(state.blocked, blocker, NO_CONTACT)
        state.contact_edge[:] = NO_CONTACT
        # no wall normals on the grid: the normal points back along the heading
        state.contact_normal[:] = -state.direction

    def _update_independent(self, state: RobotState, robots: np.ndarray) -> None:
        """`update_contacts` of robots that ignore each other: only ``robots`` changed, so only
        their rows of the state and of the kept plan are recomputed (the same arithmetic)."""
        model = self.model
        heading = model.bin_of(state.heading[robots]) * self.bin_width
        state.heading[robots] = heading
        p, k = model.decode(model.cell_of(state.position[robots], heading))
        target = model.targets[k, p]
        plan_p, plan_target, _ = self._last_plan
        plan_p[robots] = p
        plan_target[robots] = target
        state.blocked[robots] = target < 0
        state.contact_robot[robots] = NO_CONTACT
        state.contact_edge[robots] = NO_CONTACT
        normal = np.empty((len(robots), 2))  # `RobotState.direction`'s arithmetic, reversed
        np.cos(heading, out=normal[:, 0])
        np.sin(heading, out=normal[:, 1])
        state.contact_normal[robots] = -normal

    def drive(self, state: RobotState, max_ticks: float, until_first_block: bool) -> int:
        if until_first_block and state.blocked.any():
            return 0
        self._check_drive_window(max_ticks, until_first_block)
        if state.n_robots == 1:
            return self._drive_lone(state, max_ticks, until_first_block)
        ticks = 0
        while ticks < max_ticks:
            # every change of a pose ends in update_contacts, which keeps the plan it computed
            p, target, _ = self._last_plan
            movers = np.flatnonzero(target >= 0)
            if len(movers) == 0 and until_first_block:
                break
            new = self.model.centres[target[movers]]
            state.odometer[movers] += np.hypot(*(new - state.position[movers]).T)
            state.position[movers] = new
            state.clock[movers] += 1
            state.ticks += 1
            ticks += 1
            self.update_contacts(state, np.arange(state.n_robots))
            if until_first_block and state.blocked.any():
                break
        return ticks

    def _drive_lone(self, state: RobotState, max_ticks: float, until_first_block: bool) -> int:
        """`drive` of a lone robot: follow its bin's row of the target map in Python ints and
        write the state once at the end (the same positions, clock and odometer sums)."""
        p, target, _ = self._last_plan
        row = self.model.targets[int(self.model.bin_of(state.heading)[0])]
        path, target = [int(p[0])], int(target[0])
        ticks = 0
        while ticks < max_ticks:
            if target >= 0:
                path.append(target)
                target = int(row[target])
            ticks += 1
            if until_first_block and target < 0:
                break
        if len(path) > 1:
            centres = self.model.centres[path]
            hops = centres[1:] - centres[:-1]
            odometer = float(state.odometer[0])
            for hop in np.hypot(hops[:, 0], hops[:, 1]).tolist():
                odometer += hop  # one addition per tick, as the robots' loop adds them
            state.odometer[0] = odometer
            state.position[0] = centres[-1]
            state.clock[0] += len(path) - 1
        state.ticks += ticks
        if ticks:
            self.update_contacts(state, np.zeros(1, dtype=np.int64))
        return ticks
