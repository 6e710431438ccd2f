"""What the single- and multi-drifter environments share: construction, the model they hand
planners, rendering, closing and pickling."""

from __future__ import annotations

from collections.abc import Mapping

from gymnasium import logger

from bounce_gym.cells.drifter import ACTIONS, DrifterCells
from bounce_gym.envs.arguments import TakesArguments, parse
from bounce_gym.envs.drifters.core import DrifterCore
from bounce_gym.envs.drifters.model_cache import sampled_drifter_model
from bounce_gym.envs.drifters.options import DrifterOptions
from bounce_gym.envs.drifters.sampled import DEFAULT_SAMPLES, MAX_PARTICLES, MAX_REFINE
from bounce_gym.envs.render.owner import RENDER_MODES, RendererOwner, checked_render_mode
from bounce_gym.errors import ConfigError
from bounce_gym.flows import FlowField
from bounce_gym.validate import integer

FIELD_STYLES = ("arrows", "streamlines")
#: The cell models `DrifterEnvBase.cell_model` hands planners.
MODEL_KINDS = ("exact", "sampled")


class DrifterEnvBase(TakesArguments[DrifterOptions], RendererOwner):
    """Mixin of `DrifterEnv` and `MultiDrifterEnv`; it comes before the Gymnasium or PettingZoo
    base class so that its ``render``, ``close`` and ``metadata`` win."""

    metadata = {"render_modes": RENDER_MODES, "render_fps": 8}
    options_model = DrifterOptions

    def action_labels(self, agent: str | None = None) -> tuple[str, ...]:
        """What each action of a drifter is (`bounce_gym.cells.drifter.ACTIONS`)."""
        return ACTIONS

    def observation_labels(self, agent: str | None = None) -> tuple[str, ...]:
        """What each index of an observation is (every drifter's observation is laid out
        alike; `bounce_gym.envs.drifters.core`)."""
        return self.core.obs_labels

    @property
    def observes_pose(self) -> bool:
        """Whether the observation holds the drifter's true position (``observe_pose``); the
        last surface fix (``observe_fix``) is what a real drifter senses, not its pose."""
        return bool(self.options.observe_pose)

    def _build(self, kwargs: Mapping, render_mode: str | None, field_style: str,
               clock_steps: int | None, start_key: str, defaults: Mapping | None = None) -> None:
        """Validate the arguments (those of `DrifterOptions` this env takes, with its defaults
        and then ``defaults``: `bounce_gym.envs.arguments.parse`) and build the core;
        ``clock_steps`` None takes it from the options."""
        checked_render_mode(render_mode)
        if field_style not in FIELD_STYLES:
            raise ConfigError(f"field_style: expected one of {list(FIELD_STYLES)}, got "
                              f"{field_style!r}")
        self.options: DrifterOptions = parse(type(self), kwargs, defaults)
        clock = self.options.clock_steps if clock_steps is None else clock_steps
        self.core = DrifterCore(self.options, self.options.n_drifters, clock, start_key)
        self.core.keep_trails = render_mode is not None  # only drawings read the trails
        self.render_mode = render_mode
        self.field_style = field_style
        self._renderer = None
        self._sampled: dict[tuple[int, int, int, int], DrifterCells] = {}

    @property
    def flow(self) -> FlowField:
        """The env's flow field."""
        return self.options.flow

    @property
    def task(self):
        """The task that owns rewards and termination."""
        return self.core.task

    def cell_model(self, kind: str = "exact", samples: int | None = None, seed: int | None = None,
                   horizon: int | None = None, refine: int | None = None) -> DrifterCells:
        """A discrete model of this env for planners.

        ``kind="exact"`` (default): the thesis' model (ch. 5 GCM, ``rho``, ``cell_map``, the
        snapshot at ``start_time``), the one the cell backend steps. ``kind="sampled"``: a
        `SampledDrifterCells` whose drift is estimated from ``samples`` points per cell
        (default `DEFAULT_SAMPLES`, seed ``seed``, default 0) stepped by this env's own backend
        for one decision step, one matrix per step of a time-dependent field up to ``horizon``
        steps (default ``clock_steps``), its states the ``refine`` x ``refine`` sub-cells of
        every cell (default 1: the cells) (`bounce_gym.envs.drifters.sampled`); kept in memory
        and on disk (`bounce_gym.envs.drifters.model_cache`)."""
        if kind not in MODEL_KINDS:
            raise ConfigError(f"kind: expected one of {list(MODEL_KINDS)}, got {kind!r}")
        if kind == "exact":
            given = [name for name, value in (("samples", samples), ("seed", seed),
                                              ("horizon", horizon), ("refine", refine))
                     if value is not None]
            if given:
                raise ConfigError(f"{given[0]}: only a sampled cell model takes it")
            return self.core.model
        samples = integer("samples", DEFAULT_SAMPLES if samples is None else samples, 2,
                          MAX_PARTICLES)
        if samples % 2:
            raise ConfigError(f"samples: expected an even number (two halves for the "
                              f"convergence check), got {samples}")
        seed = integer("seed", 0 if seed is None else seed, 0)
        horizon = integer("horizon", self.core.clock_steps if horizon is None else horizon, 1)
        refine = integer("refine", 1 if refine is None else refine, 1, MAX_REFINE)
        key = (samples, seed, horizon, refine)
        if key not in self._sampled:
            self._sampled[key] = sampled_drifter_model(self.core.model, self.options, samples, seed,
                                               horizon, refine)
        return self._sampled[key]

    def _render_layer(self) -> int:
        """The layer whose current is drawn."""
        return 0

    def render(self):
        if self.render_mode is None:
            logger.warn("render() called with render_mode=None; pass render_mode to the env")
            return None
        from bounce_gym.envs.render.flow_view import FlowRenderer, draw_drifters

        if self._renderer is None:
            self._renderer = FlowRenderer(self.options.flow, style=self.field_style)
        frame = draw_drifters(self._renderer, self.core, self._render_layer())
        if self.render_mode == "human":
            self._renderer.show(frame, self.metadata["render_fps"])
            return None
        return frame

