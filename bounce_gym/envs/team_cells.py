"""`TeamCells`: B teams of m robots on the cell backend's grid, kept as (B, m) arrays of cells.

On the cell backend a robot is a position index ``p`` and an orientation bin ``k`` of the
`CellModel`, and each robot's *plan* — the cell it moves to on its next tick, or −1 where it is
blocked — is a table lookup (`CellModel.targets`) followed, when robots collide, by the grid
conflict rules of `bounce_gym.cells.resolve_moves`, which takes a batch of joint states: one call
plans every team. A robot with no target is ``blocked``, so its next tick is a bump.

One tick of a team (`bounce_gym.dynamics.BounceDynamics.tick` on the `CellBackend`): every
robot that is not blocked moves to its planned cell (clock + 1), every blocked robot rotates in
place by its action's angle (a bump: bump count + 1, clock 0); then every plan is made anew.
A *command tick* (`BounceDynamics.turn`, a team where some robot chose a turn command) moves
nobody: the robots that chose a turn rotate by it, every clock gains one tick, nobody bumps.
The rotations are whole bins, looked up per robot, action and bin in a table built with the
bounce rule itself, so the bins are those the backend snaps its headings to.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.cells import resolve_moves
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.dynamics.rules import wrap
from bounce_gym.dynamics.state import NO_CONTACT


class TeamCells:
    """B teams of the m robots of ``dynamics`` (its cell backend), stepped tick by tick.

    ``choices``: per robot, the radians of its discrete actions — its bounce angles Φ_i, then
    ``n_turns`` turn commands (the last ``n_turns`` entries of every robot's choices).

    Attributes (every array (B, m) unless noted):
        p, k: each robot's position index and bin.
        clock, bumps: its clock and bump count.
        blocked, contact_robot: whether its next tick is a bump, and the robot that blocks it
            (−1 where a wall does or nothing).
        target: its planned cell (−1 where blocked).
    """

    def __init__(self, dynamics: BounceDynamics, choices: list[np.ndarray], n_turns: int,
                 n_teams: int) -> None:
        backend = dynamics.backend
        model = self.model = backend.model
        self.collide = backend.collide
        self.close = backend.close
        m = dynamics.n_robots
        self.n_choices = np.array([len(c) for c in choices])
        self.n_bounce = self.n_choices - n_turns
        width = max(self.n_choices)
        bins = np.arange(model.n_bins)
        heading = bins * model.bin_width
        normal = np.column_stack((-np.cos(heading), -np.sin(heading)))
        #: per robot i, action a and bin k, at (i · width + a) · n_bins + k: the bin it turns to
        turned = np.zeros((m, width, model.n_bins), dtype=np.int64)
        for i, angles in enumerate(choices):
            for a, angle in enumerate(angles.tolist()):
                if a < self.n_bounce[i]:  # the bounce rule, the angle checked as the dynamics do
                    params = np.full(model.n_bins, dynamics.parameters(angle)[0])
                    turned[i, a] = model.bin_of(dynamics.rule(heading, normal, params))
                else:  # a turn command: `BounceDynamics.turn` on whole bins
                    turned[i, a] = model.bin_of(wrap(heading + angle))
        self.turned = turned.ravel()
        #: where robot i's actions start in ``turned``
        self.action_base = (np.arange(m) * width)[None, :]
        self.flat_targets = model.targets.ravel()
        shape = (n_teams, m)
        self.p = np.zeros(shape, dtype=np.int64)
        self.k = np.zeros(shape, dtype=np.int64)
        self.clock = np.zeros(shape, dtype=np.int64)
        self.bumps = np.zeros(shape, dtype=np.int64)
        self.blocked = np.zeros(shape, dtype=bool)
        self.contact_robot = np.full(shape, NO_CONTACT, dtype=np.int64)
        self.target = np.full(shape, -1, dtype=np.int64)

    def place(self, rows: np.ndarray, p: np.ndarray, k: np.ndarray) -> None:
        """Start teams ``rows`` afresh in cells (``p``, ``k``), (len(rows), m) each."""
        self.p[rows] = p
        self.k[rows] = k
        self.clock[rows] = 0
        self.bumps[rows] = 0
        self.target[rows], self.blocked[rows], self.contact_robot[rows] = self._plan(p, k)

    def commanded(self, actions: np.ndarray) -> np.ndarray:
        """(B, m) bool: the robots whose action is a turn command."""
        return actions >= self.n_bounce

    def tick(self, actions: np.ndarray, command: np.ndarray | None
             ) -> tuple[np.ndarray, np.ndarray]:
        """One tick of every team with discrete ``actions`` (B, m); ``command`` (B,) marks the
        teams whose tick is a command tick (None: none). Returns the (B, m) masks of the robots
        that moved and of those that bumped."""
        turns = self.turned.take(((self.action_base + actions) * self.model.n_bins) + self.k)
        bump = self.blocked
        if command is None:
            drive = ~bump
            rotate = bump
        else:
            stepping = ~command[:, None]
            bump = bump & stepping
            drive = ~self.blocked & stepping
            rotate = bump | (self.commanded(actions) & command[:, None])
        self.p = np.where(drive, self.target, self.p)
        self.k = np.where(rotate, turns, self.k)
        self.clock = np.where(bump, 0, self.clock + 1)
        self.bumps = self.bumps + bump
        self.target, self.blocked, self.contact_robot = self._plan(self.p, self.k)
        return drive, bump

    def _plan(self, p: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(target, blocked, contact_robot) of robots in cells (``p``, ``k``): the cell backend's
        plan (`CellBackend.update_contacts`) of every team at once."""
        target = self.flat_targets.take(k * self.model.n_positions + p)
        if not self.collide:
            blocked = target < 0
            return target, blocked, np.full(p.shape, NO_CONTACT, dtype=np.int64)
        stays, blocker, _ = resolve_moves(p, target, self.model.position_rc, self.close)
        target = np.where(stays, -1, target)
        blocked = target < 0
        return target, blocked, np.where(blocked, blocker, NO_CONTACT)
