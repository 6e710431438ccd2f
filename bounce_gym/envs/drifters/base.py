"""What the single- and multi-drifter environments share: construction, the model they hand
planners, rendering, closing and pickling."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from gymnasium import logger

from bounce_gym.cells.drifter import DrifterCells
from bounce_gym.envs.drifters.core import DrifterCore
from bounce_gym.envs.drifters.options import parse_options
from bounce_gym.envs.render.owner import RendererOwner
from bounce_gym.errors import ConfigError
from bounce_gym.flows import FlowField

RENDER_MODES = ["human", "rgb_array"]
FIELD_STYLES = ("arrows", "streamlines")


class DrifterEnvBase(RendererOwner):
    """Mixin of `DrifterEnv` and `MultiDrifterEnv`; it comes before the Gymnasium or PettingZoo
    base class so that its ``render``, ``close`` and ``metadata`` win."""

    metadata = {"render_modes": RENDER_MODES, "render_fps": 8}

    def _build(self, kwargs: Mapping, render_mode: str | None, field_style: str,
               n_drifters: int | None, clock_steps: int | None, start_key: str,
               defaults: Mapping | None = None, fixed: Sequence[str] = ()) -> None:
        """Validate the arguments and build the core; ``n_drifters`` and ``clock_steps`` None
        take them from the options."""
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ConfigError(f"render_mode: expected None or one of {RENDER_MODES}, "
                              f"got {render_mode!r}")
        if field_style not in FIELD_STYLES:
            raise ConfigError(f"field_style: expected one of {list(FIELD_STYLES)}, got "
                              f"{field_style!r}")
        self.options = parse_options(kwargs, defaults, fixed, who=type(self).__name__)
        n = self.options.n_drifters if n_drifters is None else n_drifters
        clock = self.options.clock_steps if clock_steps is None else clock_steps
        self.core = DrifterCore(self.options, n, clock, start_key)
        self.core.keep_trails = render_mode is not None  # only drawings read the trails
        self.render_mode = render_mode
        self.field_style = field_style
        self._renderer = None

    @property
    def flow(self) -> FlowField:
        """The env's flow field."""
        return self.options.field

    @property
    def task(self):
        """The task that owns rewards and termination."""
        return self.core.task

    def cell_model(self) -> DrifterCells:
        """The discrete model of this env (thesis ch. 5 GCM, ``rho``, ``cell_map``, the
        snapshot at ``start_time``): the model the cell backend steps, for planners on every
        backend."""
        return self.core.model

    def _render_layer(self) -> int:
        """The layer whose current is drawn."""
        return 0

    def render(self):
        if self.render_mode is None:
            logger.warn("render() called with render_mode=None; pass render_mode to the env")
            return None
        from bounce_gym.envs.render.flow_view import FlowRenderer, draw_drifters

        if self._renderer is None:
            self._renderer = FlowRenderer(self.options.field, style=self.field_style)
        frame = draw_drifters(self._renderer, self.core, self._render_layer())
        if self.render_mode == "human":
            self._renderer.show(frame, self.metadata["render_fps"])
            return None
        return frame

