"""What the drifters are asked to do: reach a goal, stay in a region, or cover one.

A task sees the fleet through the cell-model states of its drifters (`DrifterCells` numbering,
both backends) and returns per-drifter rewards, terminations and info. Regions are given as in
`bounce_gym.envs.drifters.regions`; each task's region can change per episode through
``reset(options={...})``.

* `ReachTask` (thesis §5.3.2 problem 4, Alg. 5.5): reach the goal region, which is absorbing:
  the episode terminates when the drifter's cell is in it. Reward ``"success"``: 1 on the
  step that reaches it, else 0 — the undiscounted return of an episode is the indicator of
  success, so its mean is the probability of reaching the goal within the horizon, the number
  the model predicts; ``"thesis"``: Eq. 5.10, 100 on the step that reaches it, else -1.
  Observes the goal's mean position and layer.
* `StayTask`: +1 for every step that ends in the region; never terminates. Observes the
  region's mean position and layer.
* `CoverTask`: the number of region cells the fleet visits for the first time in the step
  (a cell counts once however many drifters enter it; the deployment cells are visited at
  reset), split evenly over the drifters; all terminate when every cell is visited. Default
  region: the surface (thesis §5.3.2 problem 1). A visit is counted where a drifter is at the
  end of a step.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from bounce_gym.cells.drifter import DrifterCells
from bounce_gym.envs.drifters.regions import Region, distance_to, parse_region
from bounce_gym.errors import ConfigError


class DrifterTask:
    """Base class: the region bookkeeping every task shares."""

    name = ""
    #: the reset option that replaces the task's region for one episode
    region_key = "region"
    #: what each feature appended to a drifter's observation is (in [0, 1]), in order
    observation_labels: tuple[str, ...] = ()
    #: whether drawings mark the region (a goal or a region to stay in; a region to cover is
    #: shown by its visited cells instead)
    marked = True

    @property
    def observation_size(self) -> int:
        """Number of features appended to each drifter's observation."""
        return len(self.observation_labels)

    def __init__(self, region: object, model: DrifterCells, normalise=None) -> None:
        if region is None:
            raise ConfigError(f"{self.region_key}: the {self.name} task needs one (a cell, "
                              "cells, a position and radius, or a layer)")
        self.model = model
        self.normalise = normalise
        self.default = parse_region(region, model, self.region_key)
        self.region: Region = self.default

    @property
    def option_keys(self) -> frozenset[str]:
        return frozenset({self.region_key})

    def mask(self) -> np.ndarray:
        """(N_states,) bool, the task's region (for drawings)."""
        out = np.zeros(self.model.n_states, dtype=bool)
        out[self.region.states] = True
        return out

    def reset(self, options: Mapping) -> None:
        """Take the episode's region from the reset ``options`` (else the default)."""
        spec = options.get(self.region_key)
        self.region = (self.default if spec is None
                       else parse_region(spec, self.model, f"options.{self.region_key}"))
        self._inside = self.mask()
        if self.observation_size:
            self._features = self._centroid()

    def start(self, states: np.ndarray, positions: np.ndarray) -> dict:
        """The drifters are placed in ``states``; returns the task's info."""
        return {}

    def forbidden_starts(self) -> np.ndarray:
        """States a start may not be in."""
        return np.zeros(0, dtype=np.int64)

    def step(self, states: np.ndarray, positions: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, dict]:
        """Rewards (N,), terminated (N,) and info after a step that left the drifters in
        ``states`` at ``positions``."""
        raise NotImplementedError

    def observation(self, n: int) -> np.ndarray:
        """(n, observation_size) features of the episode's region, the same for every
        drifter."""
        return np.tile(self._features, (n, 1))

    def _centroid(self) -> np.ndarray:
        """(3,): the region's mean position and mean layer, normalised to [0, 1]."""
        cx, cy = self.model.centre(self.region.states)
        x, y = self.normalise(np.array([cx.mean()]), np.array([cy.mean()]))
        top = max(self.model.n_layers - 1, 1)
        layer = self.model.cells[self.region.states, 0].mean() / top
        return np.array([x[0], y[0], layer], dtype=np.float32)


class ReachTask(DrifterTask):
    name = "reach"
    region_key = "goal"
    observation_labels = ("goal: mean x", "goal: mean y", "goal: mean layer")

    def __init__(self, goal: object, model: DrifterCells, reward: str, normalise) -> None:
        super().__init__(goal, model, normalise)
        self.reward = reward

    def forbidden_starts(self):
        """The goal: it is absorbing, so no episode starts in it."""
        return self.region.states

    def start(self, states, positions):
        self._centres = self.model.centre(self.region.states)
        return {"is_success": np.zeros(len(states), dtype=bool),
                "distance_to_goal": self._distance(positions)}

    def step(self, states, positions):
        reached = self._inside[states]
        if self.reward == "thesis":
            rewards = np.where(reached, 100.0, -1.0)
        else:
            rewards = reached.astype(np.float64)
        return rewards, reached, {"is_success": reached,
                                  "distance_to_goal": self._distance(positions)}

    def _distance(self, positions: np.ndarray) -> np.ndarray:
        """(N,) metres from each drifter to the nearest goal cell centre."""
        cx, cy = self._centres
        return distance_to(self.model.field, positions[:, 0], positions[:, 1], cx, cy)


class StayTask(DrifterTask):
    name = "stay"
    observation_labels = ("region: mean x", "region: mean y", "region: mean layer")

    def start(self, states, positions):
        self.steps_in_region = np.zeros(len(states), dtype=np.int64)
        return {"in_region": self._inside[states], "steps_in_region": self.steps_in_region.copy()}

    def step(self, states, positions):
        inside = self._inside[states]
        self.steps_in_region += inside
        return (inside.astype(np.float64), np.zeros(len(states), dtype=bool),
                {"in_region": inside, "steps_in_region": self.steps_in_region.copy()})


class CoverTask(DrifterTask):
    name = "cover"
    marked = False

    def __init__(self, region: object, model: DrifterCells) -> None:
        super().__init__({"layer": 0} if region is None else region, model)

    def start(self, states, positions):
        self.visited = np.zeros(self.model.n_states, dtype=bool)
        self.visited[states[self._inside[states]]] = True
        self.size = int(self._inside.sum())
        self.covered = int(self.visited.sum())
        return self._info(0)

    def step(self, states, positions):
        fresh = np.unique(states[self._inside[states] & ~self.visited[states]])
        self.visited[fresh] = True
        self.covered += len(fresh)
        n = len(states)
        done = self.covered == self.size
        return (np.full(n, len(fresh) / n), np.full(n, done), self._info(len(fresh)))

    def _info(self, new: int) -> dict:
        return {"coverage": self.covered / self.size, "new_cells": new}


def make_drifter_task(options, model: DrifterCells, normalise) -> DrifterTask:
    """The task the options name, bound to ``model``; ``normalise(x, y)`` maps positions to
    [0, 1] for the observed region centroids."""
    if options.task == "reach":
        return ReachTask(options.goal, model, options.reward, normalise)
    if options.task == "stay":
        return StayTask(options.region, model, normalise)
    return CoverTask(options.region, model)
