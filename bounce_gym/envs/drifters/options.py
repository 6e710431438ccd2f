"""The keyword arguments of the drifter environments, declared once: `DrifterOptions`.

`DrifterEnv` and `MultiDrifterEnv` take the fields of `DrifterOptions` as keyword arguments —
each field's type, default and meaning are in the model (and in the "Arguments" table of the
env pages of the docs); each env leaves out the few it does not take and replaces a default or
two (`bounce_gym.envs.arguments`). An unknown argument raises `TypeError` naming it; a bad value
raises `ConfigError` naming the argument and what is allowed. `bounce_gym.envs.arguments.json_schema`
gives an env's JSON Schema.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    Field,
    SkipValidation,
    ValidationInfo,
    WithJsonSchema,
    field_validator,
    model_validator,
)

from bounce_gym import flows
from bounce_gym.cells.drifter import STEPS
from bounce_gym.dynamics.advection import LAND_RULES
from bounce_gym.envs.arguments import Accepts, Arguments, Flag, Integer, Real, needs
from bounce_gym.errors import BounceGymError, ConfigError, MissingExtraError
from bounce_gym.flows import FlowField

Backend = Literal["cell", "continuous"]
TaskName = Literal["reach", "stay", "cover"]
BACKENDS = Backend.__args__
#: Largest fleet of the multi-drifter env (each drifter is a PettingZoo agent).
MAX_DRIFTERS = 10_000
#: arguments only the continuous backend takes
CONTINUOUS_ONLY = ("step_seconds", "substeps", "diffusivity", "land_rule")
#: arguments only some tasks take
TASK_ONLY = {"goal": ("reach",), "reward": ("reach",), "region": ("stay", "cover")}
#: A region of cells (`bounce_gym.envs.drifters.regions`): ``(layer, j, i)`` or a dict of a form.
RegionSpec = tuple[int, int, int] | dict[str, Any]


class DrifterOptions(Arguments):
    """The validated arguments of the drifter envs (the flow as a `FlowField`, the start time
    and step duration resolved; the regions stay as given: the core resolves them on its
    model)."""

    flow: Annotated[FlowField, Accepts(SkipValidation[str | os.PathLike | FlowField]),
                    WithJsonSchema(
        {"type": "string"}), Field(description=(
            "The current: a zoo name (`bounce_gym.flows.flow_names()`), the path of a NetCDF file "
            "(read as data by netCDF4/xarray with `bounce_gym.flows.load_flow`; nothing in it is "
            "executed) or a `FlowField`."))] = "scb_like"
    flow_kwargs: Annotated[SkipValidation[dict[str, Any] | None], Field(description=(
        "For a zoo name: its builder's keyword arguments; for a file: {'mapping': {...}, "
        "'max_values': n} (`load_flow`'s variable and dimension names, and the most values the "
        "file may declare, default 5e7 and then at most 4 per byte of the file or 2^22 in "
        "all); none for a `FlowField`."))] = None
    backend: Annotated[Backend, Field(description=(
        "'cell': the discrete model of Alam's thesis ch. 5 (`DrifterCells`) stepped exactly, "
        "one cell transition per step; 'continuous': the RK4 `Drifters` dynamics in the "
        "field's own time, `step_seconds` per step in `substeps` RK4 steps."))] = "cell"
    rho: Annotated[Real, Field(gt=0.0, le=1.0, description=(
        "The cell model's probability of perfect motion (every backend hands this model to "
        "planners: `env.unwrapped.cell_model()`)."))] = 0.8
    cell_map: Annotated[Literal[STEPS], Field(description=(
        "The cell model's unit-step map: 'euler' or 'flowline'."))] = "euler"
    start_time: Annotated[Real | None, Field(description=(
        "Seconds: the snapshot the cell model is built from and the time the continuous "
        "drifters start at, within the field's time range (the continuous backend holds the "
        "last snapshot after it ends). None: the first snapshot; a static field takes only "
        "None."))] = None
    step_seconds: Annotated[Real | None, Field(gt=0.0, description=(
        "Continuous backend: seconds per step. None: the median over water cells of the time "
        "the start snapshot's current needs to cross one cell, 1 / |(u/dx, v/dy)|, so a step "
        "is about one step of the cell model. Given: from 1e-4 times that time to that time "
        "times the cells along the field's longer side (the median current crossing the "
        "field once), when the start snapshot has a current."))] = None
    substeps: Annotated[Integer, Field(ge=1, le=10_000, description=(
        "Continuous backend: RK4 steps per step."))] = 4
    diffusivity: Annotated[Real, Field(ge=0.0, description=(
        "Continuous backend: horizontal diffusivity in m²/s (random-walk spreading), at most "
        "L² / (2 step_seconds) with L the field's diagonal in metres: a step's spread "
        "sqrt(2 K step_seconds) is at most the field's size."))] = 0.0
    land_rule: Annotated[Literal[LAND_RULES], Field(description=(
        "Continuous backend: what a drifter that would move onto land does "
        "(`bounce_gym.dynamics.advection`)."))] = "stay"
    illegal_action: Annotated[Literal["drift", "error"], Field(description=(
        "An up or down move without water there: 'drift' (the drifter stays in its layer and "
        "drifts; `info['illegal_action']` is True) or 'error' (`ActionError`). "
        "`info['action_mask']` and `action_masks()` give the legal actions."))] = "drift"
    observe_fix: Annotated[Flag, Field(description=(
        "Add the last surface position fix (x, y in [0, 1]) and a flag that is 1 when the fix "
        "was taken now, at the surface."))] = False
    observe_pose: Annotated[Flag, Field(description=(
        "Add the true position (x, y in [0, 1]) to the observation."))] = False
    clock_steps: Annotated[Integer, Field(ge=1, description=(
        "Steps at which the normalised clock reads 1 (single drifter: the registered horizon; "
        "the fleet uses `max_cycles`)."))] = 200
    task: Annotated[TaskName, Field(description=(
        "Single drifter: 'reach' a goal, 'stay' in a region or 'cover' it; the fleet covers "
        "the surface."))] = "reach"
    goal: Annotated[SkipValidation[RegionSpec], Field(description=(
        "Reach: the goal region (`bounce_gym.envs.drifters.regions`); the default is the 3 x 3 "
        "surface cells around row 5, column 5."))] = {"cell": (0, 5, 5), "halo": 1}
    region: Annotated[SkipValidation[RegionSpec | None], Field(description=(
        "Stay (required) and cover (default: the surface): the region of cells."))] = None
    reward: Annotated[Literal["success", "thesis"], Field(description=(
        "Reach: 'success' (1 on reaching the goal, else 0) or 'thesis' (100 on reaching it, "
        "else -1; thesis Eq. 5.10)."))] = "success"
    start: Annotated[SkipValidation[RegionSpec | None], Field(description=(
        "The region the drifter starts in (None: a random surface water cell outside the "
        "goal)."))] = None
    n_drifters: Annotated[Integer, Field(ge=1, le=MAX_DRIFTERS, description=(
        "Fleet size (multi-drifter env; default the length of `deploy` when it is a list)."
    ))] = 4
    deploy: Annotated[SkipValidation[Sequence[RegionSpec] | None], Field(description=(
        "One region per drifter to deploy it in (None: random surface cells, distinct while "
        "there are enough)."))] = None

    @model_validator(mode="before")
    @classmethod
    def _field(cls, data: Mapping) -> dict:
        """The flow as a `FlowField`, with its keyword arguments (the fields below need it)."""
        flow = data.get("flow", cls.model_fields["flow"].default)
        return {**data, "flow": resolve_flow(flow, data.get("flow_kwargs"))}

    @field_validator("start_time")
    @classmethod
    def _start(cls, value: float | None, info: ValidationInfo) -> float | None:
        [field] = needs(info, "flow")
        return _start_time(field, value)

    @field_validator(*CONTINUOUS_ONLY)
    @classmethod
    def _continuous_only(cls, value: object, info: ValidationInfo) -> object:
        [backend] = needs(info, "backend")
        if backend == "cell" and value != cls.model_fields[info.field_name].default:
            raise ConfigError(f"{info.field_name}: only the continuous backend takes it (the "
                              "cell backend steps one cell transition of the model)")
        if info.field_name == "step_seconds" and backend == "continuous" and value is None:
            return crossing_time(*needs(info, "flow", "start_time"))
        return value

    @model_validator(mode="after")
    def _scales(self) -> DrifterOptions:
        """``step_seconds`` and ``diffusivity`` within the field's own scales (their
        descriptions)."""
        if self.backend != "continuous":
            return self
        field, step = self.flow, float(self.step_seconds)
        if "step_seconds" in self.model_fields_set:
            try:
                crossing = crossing_time(field, self.start_time)
            except ConfigError:  # no current: nothing moves but by diffusion
                crossing = None
            if crossing is not None:
                low, high = 1e-4 * crossing, crossing * max(field.shape)
                if not low <= step <= high:
                    raise ConfigError(
                        f"step_seconds: expected seconds in [{low:.3g}, {high:.3g}] (1e-4 times "
                        f"the {crossing:.3g} s the median current of flow {field.name!r} needs to "
                        f"cross a cell, to the time it needs to cross the field), got {step!r}")
        dx, dy = field.metric_spacing()
        size = float(np.hypot(dx.sum(axis=1).max(), dy.sum(axis=0).max()))  # metres
        top = size**2 / (2.0 * step)
        if self.diffusivity > top:
            raise ConfigError(
                f"diffusivity: expected m²/s in [0, {top:.3g}] (a step's spread sqrt(2 K "
                f"step_seconds) at most the {size:.3g} m across flow {field.name!r}), got "
                f"{self.diffusivity!r}")
        return self

    @model_validator(mode="after")
    def _task_arguments(self) -> DrifterOptions:
        for name, tasks in TASK_ONLY.items():
            if name in self.model_fields_set and self.task not in tasks:
                raise ConfigError(f"{name}: only the {' and '.join(tasks)} task takes it, the "
                                  f"task is {self.task!r}")
        return self



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
        except MissingExtraError as exc:  # the same type: callers can tell what to install
            raise MissingExtraError(f"flow: {exc}") from None
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


def _start_time(field: FlowField, t: float | None) -> float | None:
    if field.time is None:
        if t is not None:
            raise ConfigError(f"start_time: the flow {field.name!r} is static; leave start_time "
                              f"None, got {t!r}")
        return None
    if t is None:
        return float(field.time[0])
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
