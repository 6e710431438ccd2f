"""What the environments draw: robots with their headings, bumpers, latched contacts and (under
``physics="dynamic"``) motion phases, their recent trails, and the task's layers."""

from __future__ import annotations

import numpy as np

from bounce_gym.envs.core import BounceCore


def draw_core(renderer, core: BounceCore) -> np.ndarray:
    """One RGB frame of the core's current state (see `bounce_gym.envs.render.renderer`)."""
    from bounce_gym.envs.render.renderer import RenderLayers

    state = core.state
    layers = RenderLayers(
        trails=[np.array(trail) for trail in core.trails],
        labels=[f"{core.task.name}  tick {state.ticks}  bumps {int(state.bumps.sum())}"],
        **core.task.render_layers(),
    )
    return renderer.draw(state.position, state.heading, core.options.robot_radius, layers,
                         blocked=state.blocked, bumpers=bumpers(core))


def bumpers(core: BounceCore):
    """The core's robots' `Bumpers`, as its motion backend reports them: each latched contact
    lies on the robot's rim, one radius from its centre against the contact normal."""
    from bounce_gym.envs.render.renderer import Bumpers

    backend, state = core.dynamics.backend, core.state
    pressed, normal = backend.bumpers(state)
    contacts = state.position - core.options.robot_radius * normal
    return Bumpers(arc=backend.bumper_arc, pressed=pressed, contacts=contacts,
                   phases=backend.phase_names())
