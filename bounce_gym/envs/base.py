"""What the single- and multi-robot environments share: construction from their declared arguments
(`bounce_gym.envs.options.EnvOptions`), the discrete model they hand planners, rendering, closing
and pickling."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from gymnasium import logger

from bounce_gym.cells import CellModel
from bounce_gym.dynamics.sampled_model import SampledModel
from bounce_gym.envs.arguments import TakesArguments, parse
from bounce_gym.envs.core import BounceCore
from bounce_gym.envs.options import EnvOptions
from bounce_gym.envs.render.owner import RENDER_MODES, RendererOwner, checked_render_mode
from bounce_gym.envs.tasks import make_task
from bounce_gym.errors import ConfigError

#: what each index of an observation is: one label per index of a ``Box``, or per key of a
#: ``Dict`` observation the labels of that key's ``Box``
ObservationLabels = tuple[str, ...] | dict[str, tuple[str, ...]]


class EnvBase(TakesArguments[EnvOptions], RendererOwner):
    """Mixin of `BounceEnv` and the multi-robot envs; it comes before the Gymnasium or
    PettingZoo base class so that its ``render``, ``close`` and ``metadata`` win."""

    metadata = {"render_modes": RENDER_MODES, "render_fps": 10}
    options_model = EnvOptions

    def _build(self, kwargs: Mapping, render_mode: str | None, tasks: Sequence[str]) -> None:
        """Validate ``render_mode`` and the keyword arguments (those of `EnvOptions` this env
        takes, with its defaults: `bounce_gym.envs.arguments.parse`), then build the core with
        the task."""
        checked_render_mode(render_mode)
        self.options: EnvOptions = parse(type(self), kwargs)
        self.core = BounceCore(self.options,
                               make_task(self.options.task, self.options.task_kwargs, tasks))
        self.core.keep_trails = render_mode is not None  # only drawings read the trails
        self.render_mode = render_mode
        self._renderer = None

    @property
    def world(self):
        """The env's `World`."""
        return self.options.world

    @property
    def task(self):
        """The task that owns reward and termination (shared by every robot)."""
        return self.core.task

    def action_labels(self, agent: str | None = None) -> tuple[str, ...]:
        """What each action of a robot (``agent``; None: the lone robot) is: per discrete action
        its bounce angle, then its turn commands; for continuous actions the angles the one
        number maps onto."""
        robot = 0 if agent is None else self.agent_index[agent]
        if self.options.action_type == "continuous":
            low, high = np.degrees(self.options.angle_range[robot])
            return (f"bounce angle: a ∈ [-1, 1] maps linearly onto [{low:g}°, {high:g}°]",)
        return (*(f"bounce angle {angle:g}°" for angle in np.degrees(self.options.angles[robot])),
                *(f"turn in place by {angle:g}° (a command tick)"
                  for angle in np.degrees(self.options.turn_angles)))

    def observation_labels(self, agent: str | None = None) -> ObservationLabels:
        """What each index of an observation is (every robot's observation is laid out
        alike; `bounce_gym.envs.core`); an env whose observation is a ``Dict`` gives them per
        key."""
        return self.core.obs_labels

    @property
    def observes_pose(self) -> bool:
        """Whether the observation holds the robot's true pose during the episode (a
        privileged observation: ``privileged=True``), not just contact, clock and the task's
        givens."""
        return bool(self.options.privileged)

    @property
    def robot_state(self):
        """The true `RobotState` of every robot (poses, contacts, clocks), for planners and
        evaluation; the robots themselves sense only what the observation holds. Read it, do
        not write it."""
        return self.core.state

    def cell_model(self, n_bins: int | None = None, corner_rule: str | None = None,
                   kind: str = "exact", **sampling) -> CellModel | SampledModel:
        """The discrete cell-to-cell model of this env, for planners (see
        `BounceCore.cell_model`): the cell backend's own model, else one built once at cell
        size = ``step_length`` for the robot radius with ``n_bins`` orientation bins and
        ``corner_rule`` (default: the env's ``cell_bins`` and ``corner_rule``).

        ``kind="sampled"`` returns instead the generalized cell mapping estimated from this
        env's own dynamics over that model's states (`BounceCore.sampled_model`; ``sampling``:
        ``samples``, ``seed``, ``heading_offset``, ``cache``)."""
        if kind == "sampled":
            return self.core.sampled_model(n_bins=n_bins, corner_rule=corner_rule, **sampling)
        if kind != "exact":
            raise ConfigError(f"kind: expected 'exact' or 'sampled', got {kind!r}")
        if sampling:
            raise ConfigError(f"cell_model: {sorted(sampling)} are options of kind='sampled'")
        return self.core.cell_model(n_bins, corner_rule)

    def render(self):
        if self.render_mode is None:
            logger.warn("render() called with render_mode=None; pass render_mode to the env")
            return None
        from bounce_gym.envs.render.renderer import Renderer
        from bounce_gym.envs.render.view import draw_core

        if self._renderer is None:
            self._renderer = Renderer(self.world)
        frame = draw_core(self._renderer, self.core)
        if self.render_mode == "human":
            self._renderer.show(frame, self.metadata["render_fps"])
            return None
        return frame

