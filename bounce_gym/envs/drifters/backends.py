"""How a fleet of profiling drifters moves: on the cells of the model, or through the flow.

Both backends hold N drifters and answer the same questions (positions, layers, cell-model
states, legal actions) so that tasks, observations and drawings do not care which one runs.

* `CellFleet`: the discrete model of thesis ch. 5 (`DrifterCells`) exactly — one step is one
  transition drawn with `DrifterCells.sample` from the env's generator: drift follows the
  layer's GCM row, up and down move to the same (j, i) one layer shallower or deeper. A drifter
  sits at its cell's centre.
* `ContinuousFleet`: `bounce_gym.dynamics.Drifters` — one step applies the actions (an
  instant change of layer) and then advects for ``step_seconds`` seconds in ``substeps`` RK4
  steps (plus diffusion from the env's generator), in the field's own time; after the field's
  last snapshot the flow holds it. Its cell is the cell of its nearest node.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.cells.drifter import DrifterCells
from bounce_gym.dynamics.advection import Drifters


class CellFleet:
    """N drifters stepped on the cells of ``model``."""

    def __init__(self, model: DrifterCells) -> None:
        self.model = model
        self.states = np.zeros(0, dtype=np.int64)

    @property
    def time(self) -> float | None:
        """The snapshot time of the model (the cell backend has no clock of its own)."""
        return self.model.t

    def reset(self, states: np.ndarray, points: list, rng: np.random.Generator) -> None:
        """Place the drifters in ``states`` (exact points are their cells here)."""
        self.states = np.array(states, dtype=np.int64)

    def positions(self) -> np.ndarray:
        """(N, 2) positions in the field's coordinates (the cell centres)."""
        x, y = self.model.centre(self.states)
        return np.column_stack((x, y))

    def layers(self) -> np.ndarray:
        return self.model.cells[self.states, 0]

    def cell_states(self) -> np.ndarray:
        return self.states

    def legal(self) -> np.ndarray:
        """(N, 3) bool, the legal actions of every drifter."""
        return self.model.legal[self.states]

    def step(self, actions: np.ndarray, rng: np.random.Generator) -> None:
        if len(self.states) == 1:  # one drifter: the same draw without array overheads
            self.states = np.array([self.model.sample_one(int(self.states[0]), int(actions[0]),
                                                          rng)])
        else:
            self.states = self.model.sample(self.states, actions, rng)


class ContinuousFleet:
    """N drifters carried by the flow (`Drifters`), their steps of ``step_seconds``."""

    def __init__(self, model: DrifterCells, start_time: float | None, step_seconds: float,
                 substeps: int, diffusivity: float, land_rule: str) -> None:
        self.model = model
        self.start_time = start_time
        self.step_seconds = step_seconds
        self.substeps = substeps
        self.diffusivity = diffusivity
        self.land_rule = land_rule
        self.drifters: Drifters | None = None

    @property
    def time(self) -> float:
        """The field time of the drifters, seconds."""
        return self.drifters.t

    def reset(self, states: np.ndarray, points: list, rng: np.random.Generator) -> None:
        """Place the drifters at the centres of ``states``, or at ``points[n]`` where that is
        not None; diffusion draws from ``rng``."""
        x, y = self.model.centre(np.asarray(states))
        for n, point in enumerate(points):
            if point is not None:
                x[n], y[n] = point
        self.drifters = Drifters(self.model.field, x, y, self.model.cells[states, 0],
                                 t=self.start_time, land_rule=self.land_rule,
                                 diffusivity=self.diffusivity, rng=rng, outside="hold")

    def positions(self) -> np.ndarray:
        return np.column_stack((self.drifters.x, self.drifters.y))

    def layers(self) -> np.ndarray:
        return self.drifters.layer

    def cell_states(self) -> np.ndarray:
        d = self.drifters
        return self.model.state_at_point(d.x, d.y, d.layer)

    def legal(self) -> np.ndarray:
        return self.drifters.legal_actions()

    def step(self, actions: np.ndarray, rng: np.random.Generator) -> None:
        self.drifters.apply_actions(actions)
        dt = self.step_seconds / self.substeps
        for _ in range(self.substeps):
            self.drifters.step(dt)
