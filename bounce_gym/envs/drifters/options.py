"""The drifter environments' constructor arguments: one table, one parser.

`DrifterEnv` and `MultiDrifterEnv` take the keyword arguments of `ARGUMENTS` (with the defaults
listed there); each env names the few it does not take. An unknown argument raises `TypeError`
naming it; a bad value raises `ConfigError` naming the argument and what is allowed.

* ``flow``: a zoo name (`bounce_gym.flows.flow_names`), the path of a NetCDF file (read with
  `bounce_gym.flows.load_flow`: the file is parsed as data by netCDF4/xarray, nothing in it is
  executed) or a `FlowField`; ``flow_kwargs``: the zoo builder's keyword arguments, or for a
  file ``{"mapping": {...}, "max_values": n}`` (`load_flow`'s variable/dimension mapping and
  cap on the values the file may declare, default 5·10^7); none for a field.
* ``backend``: ``"cell"`` (the discrete model of thesis ch. 5, `DrifterCells`, stepped exactly:
  one step = one cell transition drawn from the model) or ``"continuous"`` (the `Drifters` RK4
  dynamics in the field's own time: one step = ``step_seconds`` seconds in ``substeps`` RK4
  steps).
* ``rho`` (default 0.8), ``cell_map`` (``"euler"`` | ``"flowline"``): the cell model's
  perfect-motion probability and unit-step map (`DrifterCells`); every backend hands this model
  to planners (``env.unwrapped.cell_model()``).
* ``start_time``: seconds; the snapshot the cell model is built from and the time the
  continuous drifters start at (default: the field's first snapshot; None for a static field).
  The continuous backend holds the last snapshot after the field's time range ends.
* continuous only: ``step_seconds`` (default: the median over water cells of the time the
  start snapshot's current needs to cross one cell, 1 / |(u / dx, v / dy)| — so one step is
  about one cell step of the cell model), ``substeps`` (default 4), ``diffusivity`` (m²/s,
  default 0), ``land_rule`` (``"stay"`` | ``"slide"``, `bounce_gym.dynamics.advection`).
* ``illegal_action``: what an up/down move without water there does: ``"drift"`` (default: the
  drifter stays in its layer and drifts; ``info["illegal_action"]`` is True) or ``"error"``
  (`ActionError`). ``info["action_mask"]`` and ``action_masks()`` give the legal actions.
* ``observe_fix`` (default False): add the last surface position fix (x, y in [0, 1]) and a
  flag that is 1 when the fix was taken now (the drifter is at the surface);
  ``observe_pose`` (default False): add the true position (x, y in [0, 1]).
* ``clock_steps``: steps at which the normalised clock reads 1 (single-drifter env, default
  200, the registered horizon; the multi-drifter env uses ``max_cycles``).
* ``task``: single drifter ``"reach"`` (default), ``"stay"`` or ``"cover"``; the fleet covers
  the surface. ``goal`` (reach; default ``{"cell": (0, 5, 5), "halo": 1}``, the 3 x 3 surface
  cells around row 5, column 5), ``region`` (stay: required; cover: default the surface) and
  ``start`` / ``deploy`` (default: random surface cells) are regions of cells
  (`bounce_gym.envs.drifters.regions`); ``reward`` (reach): ``"success"`` (default: 1 on
  reaching the goal, else 0) or ``"thesis"`` (Eq. 5.10: 100 on reaching it, else -1).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bounce_gym import flows
from bounce_gym.cells.drifter import STEPS
from bounce_gym.dynamics.advection import LAND_RULES
from bounce_gym.errors import BounceGymError, ConfigError
from bounce_gym.flows import FlowField
from bounce_gym.validate import flag, integer, keyword_arguments, number

BACKENDS = ("cell", "continuous")
ILLEGAL_ACTIONS = ("drift", "error")
REWARDS = ("success", "thesis")
#: Largest fleet of the multi-drifter env (each drifter is a PettingZoo agent).
MAX_DRIFTERS = 10_000
#: arguments only the continuous backend takes
CONTINUOUS_ONLY = ("step_seconds", "substeps", "diffusivity", "land_rule")

#: Every constructor argument, with its default (the multi-drifter env changes a few).
ARGUMENTS: dict[str, object] = {
    "flow": "scb_like",
    "flow_kwargs": None,
    "backend": "cell",
    "rho": 0.8,
    "cell_map": "euler",
    "start_time": None,
    "step_seconds": None,
    "substeps": 4,
    "diffusivity": 0.0,
    "land_rule": "stay",
    "illegal_action": "drift",
    "observe_fix": False,
    "observe_pose": False,
    "clock_steps": 200,
    "task": "reach",
    "goal": {"cell": (0, 5, 5), "halo": 1},
    "region": None,
    "reward": "success",
    "start": None,
    "n_drifters": 4,
    "deploy": None,
}


@dataclass(frozen=True)
class DrifterOptions:
    """Validated arguments (the regions stay as given; the core resolves them on its model)."""

    field: FlowField
    backend: str
    rho: float
    cell_map: str
    start_time: float | None
    step_seconds: float | None  # None on the cell backend
    substeps: int
    diffusivity: float
    land_rule: str
    illegal_action: str
    observe_fix: bool
    observe_pose: bool
    clock_steps: int
    task: str
    goal: object
    region: object
    reward: str
    start: object
    n_drifters: int
    deploy: object


def _choice(name: str, value: object, allowed: Sequence[str]) -> str:
    if not isinstance(value, str) or value not in allowed:
        raise ConfigError(f"{name}: expected one of {list(allowed)}, got {value!r}")
    return value


def resolve_flow(flow: object, flow_kwargs: object) -> FlowField:
    """A `FlowField` from a zoo name, a NetCDF path or a field (see the module docstring)."""
    if flow_kwargs is None:
        flow_kwargs = {}
    if not isinstance(flow_kwargs, Mapping) or not all(isinstance(k, str) for k in flow_kwargs):
        raise ConfigError(f"flow_kwargs: expected a dict of keyword arguments, got "
                          f"{flow_kwargs!r}")
    if isinstance(flow, FlowField):
        if flow_kwargs:
            raise ConfigError("flow_kwargs: a FlowField is used as it is; flow_kwargs apply to "
                              "a zoo name or a file")
        return flow
    if isinstance(flow, os.PathLike) or (isinstance(flow, str) and Path(flow).suffix):
        unknown = sorted(set(flow_kwargs) - {"mapping", "max_values"})
        if unknown:
            raise ConfigError(f"flow_kwargs: a NetCDF file takes only 'mapping' and "
                              f"'max_values', got {unknown}")
        try:
            return flows.load_flow(flow, **flow_kwargs)
        except BounceGymError as exc:
            raise ConfigError(f"flow: {exc}") from None
    if isinstance(flow, str):
        if flow not in flows.flow_names():
            raise ConfigError(f"flow: unknown zoo flow {flow!r}; zoo names are "
                              f"{flows.flow_names()} (a file path needs its suffix, e.g. .nc)")
        try:
            return flows.get_flow(flow, **flow_kwargs)
        except BounceGymError as exc:
            raise ConfigError(f"flow_kwargs: {exc}") from None
    raise ConfigError(f"flow: expected a zoo name, a NetCDF path or a FlowField, got "
                      f"{type(flow).__name__}")


def _start_time(field: FlowField, value: object) -> float | None:
    if field.time is None:
        if value is not None:
            raise ConfigError(f"start_time: the flow {field.name!r} is static; leave start_time "
                              f"None, got {value!r}")
        return None
    if value is None:
        return float(field.time[0])
    t = number("start_time", value)
    if not field.time[0] <= t <= field.time[-1]:
        raise ConfigError(f"start_time: expected seconds in the field's time range "
                          f"[{field.time[0]:g}, {field.time[-1]:g}], got {t:g}")
    return t


def crossing_time(field: FlowField, t: float | None) -> float:
    """The median over water cells (all layers) of the time the current at time ``t`` needs
    to cross one cell, 1 / |(u / dx, v / dy)|; cells without current are left out."""
    u, v = field.snapshot(t)
    dx, dy = field.metric_spacing()
    rate = np.hypot(u / dx, v / dy)[field.water]
    rate = rate[rate > 0]
    if not len(rate):
        raise ConfigError(f"step_seconds: the flow {field.name!r} has no current at the start "
                          "time, so no default step duration; give step_seconds")
    return float(np.median(1.0 / rate))


def parse_options(kwargs: Mapping, defaults: Mapping | None = None, fixed: Sequence[str] = (),
                  who: str = "the environment") -> DrifterOptions:
    """Validate a drifter env's keyword arguments; ``defaults`` replaces some of `ARGUMENTS`,
    the names in ``fixed`` may not be given; ``who`` names the env in the `TypeError` for an
    unknown argument."""
    values = keyword_arguments(ARGUMENTS, kwargs, defaults, fixed, who)
    backend = _choice("backend", values["backend"], BACKENDS)
    rho = number("rho", values["rho"], minimum=0.0, strict=True)
    if rho > 1:
        raise ConfigError(f"rho: expected a probability in (0, 1], got {rho!r}")
    field = resolve_flow(values["flow"], values["flow_kwargs"])
    start_time = _start_time(field, values["start_time"])
    if backend == "cell":
        given = [k for k in CONTINUOUS_ONLY if k in kwargs and kwargs[k] != ARGUMENTS[k]]
        if given:
            raise ConfigError(f"{given[0]}: only the continuous backend takes it (the cell "
                              "backend steps one cell transition of the model)")
    step_seconds = None
    if backend == "continuous":
        step_seconds = (crossing_time(field, start_time) if values["step_seconds"] is None
                        else number("step_seconds", values["step_seconds"], minimum=0.0,
                                    strict=True))
    task = _choice("task", values["task"], ("reach", "stay", "cover"))
    for name, tasks in (("goal", ("reach",)), ("reward", ("reach",)),
                        ("region", ("stay", "cover"))):
        if name in kwargs and task not in tasks:
            raise ConfigError(f"{name}: only the {' and '.join(tasks)} task takes it, the task "
                              f"is {task!r}")
    return DrifterOptions(
        field=field,
        backend=backend,
        rho=rho,
        cell_map=_choice("cell_map", values["cell_map"], STEPS),
        start_time=start_time,
        step_seconds=step_seconds,
        substeps=integer("substeps", values["substeps"], 1, 10_000),
        diffusivity=number("diffusivity", values["diffusivity"], minimum=0.0),
        land_rule=_choice("land_rule", values["land_rule"], LAND_RULES),
        illegal_action=_choice("illegal_action", values["illegal_action"], ILLEGAL_ACTIONS),
        observe_fix=flag("observe_fix", values["observe_fix"]),
        observe_pose=flag("observe_pose", values["observe_pose"]),
        clock_steps=integer("clock_steps", values["clock_steps"], 1),
        task=task,
        goal=values["goal"],
        region=values["region"],
        reward=_choice("reward", values["reward"], REWARDS),
        start=values["start"],
        n_drifters=integer("n_drifters", values["n_drifters"], 1, MAX_DRIFTERS),
        deploy=values["deploy"],
    )
