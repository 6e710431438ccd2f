"""The simulation core of the drifter envs: a fleet, its task, what each drifter senses.

Per drifter the observation is (float32, every value in [0, 1]):

* ``layer`` — its layer / (L - 1) (0 with one layer): a profiling float knows its depth;
* ``clock`` — steps since reset / ``clock_steps``, reading 1 from then on;
* with ``observe_fix``: ``fix_x, fix_y`` — where it last was at the surface (a GPS fix is only
  had there; at reset, where it was deployed), and ``fresh`` — 1 if it is at the surface now
  (the fix is its current position), else 0;
* with ``observe_pose``: ``x, y`` — its true position (privileged); `DrifterCore.observed_pose`
  reads the position, layer and step back from an observation;
* the task's features (reach and stay: the region's mean x, y and layer).

Positions are normalised over the grid's cells: 0 and 1 are the outer edges of the outer cells.
The true state is in ``info``.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence

import numpy as np

from bounce_gym.cells.drifter import ACTIONS, DRIFT, DrifterCells
from bounce_gym.envs.drifters.backends import CellFleet, ContinuousFleet
from bounce_gym.envs.drifters.options import DrifterOptions
from bounce_gym.envs.drifters.regions import parse_region
from bounce_gym.envs.drifters.tasks import make_drifter_task
from bounce_gym.envs.reset_options import checked_reset_options
from bounce_gym.errors import ActionError, ConfigError

TRAIL_LENGTH = 64
#: info entries with one row per drifter (the multi-drifter env gives each agent its row)
PER_DRIFTER = ("cell", "state", "position", "layer", "action_mask", "illegal_action",
               "is_success", "distance_to_goal", "in_region", "steps_in_region")


class DrifterCore:
    """N drifters, their task and their senses.

    Args:
        options: the validated arguments.
        n_drifters: fleet size.
        clock_steps: steps at which the normalised clock reads 1.
        start_key: the argument / reset option placing the drifters: ``"start"`` (one region,
            every drifter drawn from it) or ``"deploy"`` (a list with one region per drifter).
    """

    def __init__(self, options: DrifterOptions, n_drifters: int, clock_steps: int,
                 start_key: str) -> None:
        self.options = options
        field = options.flow
        self.model = DrifterCells(field, options.rho, t=options.start_time,
                                  step=options.cell_map)
        if options.backend == "cell":
            self.fleet = CellFleet(self.model)
        else:
            self.fleet = ContinuousFleet(self.model, options.start_time, options.step_seconds,
                                         options.substeps, options.diffusivity,
                                         options.land_rule)
        self.n = n_drifters
        self.clock_steps = clock_steps
        self.start_key = start_key
        self._lo = np.array([_edge(field.x, 0), _edge(field.y, 0)])
        self._span = np.array([_edge(field.x, -1), _edge(field.y, -1)]) - self._lo
        self._top = max(self.model.n_layers - 1, 1)  # the layer that observes as 1
        self.task = make_drifter_task(options, self.model, self.normalise)
        self.default_start = options.start if start_key == "start" else options.deploy
        self._check_placement(self.default_start, start_key)
        #: what each index of a drifter's observation is (the module docstring)
        self.obs_labels = _observation_labels(options, clock_steps, self.task.observation_labels)
        self.obs_low = np.zeros(len(self.obs_labels), dtype=np.float32)
        self.obs_high = np.ones(len(self.obs_labels), dtype=np.float32)
        self.option_keys = frozenset({start_key}) | self.task.option_keys
        #: whether steps extend the trails and visited cells (only drawings read them)
        self.keep_trails = False
        self.steps = 0

    # -- geometry ---------------------------------------------------------------------------
    def normalise(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions mapped to [0, 1] over the grid's cells."""
        return (x - self._lo[0]) / self._span[0], (y - self._lo[1]) / self._span[1]

    # -- episode ----------------------------------------------------------------------------
    def reset(self, rng: np.random.Generator, options: Mapping | None,
              strict: bool = True) -> tuple[np.ndarray, dict]:
        """Place the fleet and start an episode. Unknown option keys raise `ConfigError`; with
        ``strict=False`` (PettingZoo's API test passes arbitrary options) they only warn."""
        options = checked_reset_options(options, self.option_keys, strict)
        self.task.reset(options)
        spec = options.get(self.start_key)
        where = self.start_key if spec is None else f"options.{self.start_key}"
        if spec is None:
            spec = self.default_start
        self._check_placement(spec, where)
        states, points = self._place(spec, rng, where)
        self.fleet.reset(states, points, rng)
        self.steps = 0
        positions = self.fleet.positions()
        layers = self.fleet.layers()
        self.fix = np.column_stack(self.normalise(positions[:, 0], positions[:, 1]))
        self.trails = [deque([p.copy()], maxlen=TRAIL_LENGTH) for p in positions]
        self.visited = np.zeros(self.model.index.shape, dtype=bool)
        self._visit(states)
        self._legal = self.fleet.legal()
        info = self._info(states, positions, layers, np.zeros(self.n, dtype=bool),
                          self.task.start(states, positions))
        return self.observation(positions, layers), info

    def step(self, actions: np.ndarray, rng: np.random.Generator
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
        """Advance one step with actions (N,) in {0 drift, 1 up, 2 down}."""
        legal = self._legal
        illegal = ~legal[np.arange(self.n), actions]
        if illegal.any():
            if self.options.illegal_action == "error":
                k = int(np.flatnonzero(illegal)[0])
                raise self.illegal(k, int(actions[k]))
            actions = np.where(illegal, DRIFT, actions)
        self.fleet.step(actions, rng)
        self.steps += 1
        states = self.fleet.cell_states()
        positions = self.fleet.positions()
        layers = self.fleet.layers()
        rewards, terminated, task_info = self.task.step(states, positions)
        surface = layers == 0
        if surface.any():
            fx, fy = self.normalise(positions[surface, 0], positions[surface, 1])
            self.fix[surface] = np.column_stack((fx, fy))
        if self.keep_trails:
            for trail, p in zip(self.trails, positions, strict=True):
                trail.append(p.copy())
            self._visit(states)
        self._legal = self.fleet.legal()
        info = self._info(states, positions, layers, illegal, task_info)
        return self.observation(positions, layers), rewards, terminated, info

    def legal(self) -> np.ndarray:
        """(N, 3) bool, the legal actions now."""
        return self._legal.copy()

    def is_legal(self, k: int, action: int) -> bool:
        """Whether drifter ``k`` may take ``action`` now."""
        return bool(self._legal[k, action])

    def illegal(self, k: int, action: int, who: str = "action") -> ActionError:
        """The error for drifter ``k`` taking the illegal ``action`` (with
        ``illegal_action="error"``)."""
        return ActionError(f"{who}: {ACTIONS[action]} is illegal for drifter {k} in layer "
                           f"{int(self.fleet.layers()[k])} (no water there; legal actions: "
                           f"{np.flatnonzero(self._legal[k]).tolist()})")

    # -- placement --------------------------------------------------------------------------
    def _check_placement(self, spec: object, where: str) -> None:
        """A deploy list has one entry per drifter (each one a region)."""
        if self.start_key == "deploy" and spec is not None and (
                isinstance(spec, str | Mapping) or not isinstance(spec, Sequence)
                or len(spec) != self.n):
            raise ConfigError(f"{where}: expected a list of {self.n} regions (one per drifter), "
                              f"got {spec!r}")

    def _place(self, spec: object, rng: np.random.Generator, where: str
               ) -> tuple[np.ndarray, list]:
        """Start states (N,) and exact start points (None where a drifter starts at its
        cell's centre)."""
        forbidden = self.task.forbidden_starts()
        if spec is None:  # deployed at the surface (thesis §5.3.2), anywhere
            surface = np.setdiff1d(self.model.layer_states(0), forbidden)
            if not len(surface):
                raise ConfigError(f"{where}: no surface cell outside the goal to start from")
            replace = len(surface) < self.n
            return rng.choice(surface, self.n, replace=replace), [None] * self.n
        specs = [spec] * self.n if self.start_key == "start" else list(spec)
        states, points = np.zeros(self.n, dtype=np.int64), []
        for k, item in enumerate(specs):
            label = where if self.start_key == "start" else f"{where}[{k}]"
            region = parse_region(item, self.model, label)
            allowed = np.setdiff1d(region.states, forbidden)
            if not len(allowed):
                raise ConfigError(f"{label}: every cell of it lies in the goal, which is "
                                  "absorbing; start elsewhere")
            states[k] = allowed[0] if len(allowed) == 1 else rng.choice(allowed)
            points.append(region.point)
        return states, points

    # -- sensing ----------------------------------------------------------------------------
    def observation(self, positions: np.ndarray, layers: np.ndarray) -> np.ndarray:
        """(N, d) float32 observations (module docstring)."""
        parts = [layers[:, None] / self._top, np.full((self.n, 1),
                                                     min(self.steps / self.clock_steps, 1.0))]
        if self.options.observe_fix:
            parts += [self.fix, (layers == 0)[:, None]]
        if self.options.observe_pose:
            parts.append(np.column_stack(self.normalise(positions[:, 0], positions[:, 1])))
        if self.task.observation_size:
            parts.append(self.task.observation(self.n))
        obs = np.concatenate(parts, axis=1, dtype=np.float32)
        # a drifter on the outer edge of the grid can round a hair outside [0, 1]
        return np.clip(obs, 0.0, 1.0, out=obs)

    def observed_pose(self, observations: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """What drifters know from their own (n, d) ``observations`` alone (with
        ``observe_pose``): their positions x, y (field coordinates), layers, and steps since
        reset (from the clock, exact below ``clock_steps``)."""
        if not self.options.observe_pose:
            raise ConfigError("observe_pose: the observation carries no position; build the env "
                              "with observe_pose=True")
        obs = np.asarray(observations, dtype=np.float64)
        layer = np.rint(obs[:, 0] * self._top).astype(np.int64)
        steps = np.rint(obs[:, 1] * self.clock_steps).astype(np.int64)
        k = 2 + 3 * self.options.observe_fix
        x = self._lo[0] + obs[:, k] * self._span[0]
        y = self._lo[1] + obs[:, k + 1] * self._span[1]
        return x, y, layer, steps

    def _info(self, states, positions, layers, illegal, task_info: dict) -> dict:
        info = {
            "cell": self.model.cells[states].copy(),
            "state": states.copy(),
            "position": positions,
            "layer": layers.copy(),
            "steps": self.steps,
            "action_mask": self._legal.astype(np.int8),
            "illegal_action": illegal,
        }
        if self.options.backend == "continuous":
            info["time"] = float(self.fleet.time)
        info.update(task_info)
        return info

    def _visit(self, states: np.ndarray) -> None:
        layer, j, i = self.model.cells[states].T
        self.visited[layer, j, i] = True


def action_code(action: object, who: str = "action") -> int:
    """``action`` as an int in {0 drift, 1 up, 2 down}; anything else raises `ActionError`."""
    value = np.asarray(action)
    if value.shape != () or value.dtype.kind not in "iu" or not 0 <= int(value) <= 2:
        raise ActionError(f"{who}: expected 0 (drift), 1 (up) or 2 (down), got {action!r}")
    return int(value)


def _edge(nodes: np.ndarray, end: int) -> float:
    """The outer edge of the first (end 0) or last (end -1) cell along an axis."""
    if end == 0:
        return float(nodes[0] - 0.5 * (nodes[1] - nodes[0]))
    return float(nodes[-1] + 0.5 * (nodes[-1] - nodes[-2]))


def _observation_labels(options: DrifterOptions, clock_steps: int,
                        task_labels: Sequence[str]) -> tuple[str, ...]:
    """What each index of a drifter's observation is, in order (every value in [0, 1])."""
    labels = ["layer / (L − 1)", f"clock: steps / {clock_steps} (then 1)"]
    if options.observe_fix:
        labels += ["last surface fix: x", "last surface fix: y", "fresh: at the surface now"]
    if options.observe_pose:
        labels += ["position (privileged): x", "position (privileged): y"]
    return (*labels, *(f"task: {label}" for label in task_labels))
