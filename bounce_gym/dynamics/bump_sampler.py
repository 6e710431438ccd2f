"""Sample points of a generalized cell mapping, simulated by the env's own dynamics.

`sample_outcomes` places many robots (``robot_collisions="ignore"``: each is an independent
sample point) at poses drawn from every decision state of a `CellModel` — on the ``cell``
backend the cell's own centre and bin heading, elsewhere the bump sections of
`bounce_gym.cells.sections` — lets each bump once with one angle of Φ through `BounceDynamics`
(the rule, the noise and the backend of the env, so rotations that take time or slip are
simulated as the env does) and records where and after how many ticks of its clock each one
bumps next (`bounce_gym.cells.outcomes.BumpOutcomes`). The kinematic backend drives all robots
to their own contacts in one vectorised call; the others are stepped tick by tick, and a robot
is done at the end of the first tick in which it is blocked again.

`first_bumps` simulates the drive of a bounce-mode reset from a known start pose the same way:
the initial distribution of the decision state.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.cells.bump_states import BumpStates
from bounce_gym.cells.model import CellModel
from bounce_gym.cells.outcomes import BumpOutcomes
from bounce_gym.cells.sections import BumpSections
from bounce_gym.dynamics.simulator import BounceDynamics


def bump_cells(model: CellModel, sections: BumpSections | None,
               offset: float | None) -> np.ndarray:
    """The decision states a robot can be in at a bump: the blocked cells of the cell model
    (``sections`` None), else the states of positive measure (at the fixed heading ``offset``
    when one is given, `BumpSections.fixed_heading`)."""
    if sections is None:
        return np.flatnonzero((model.targets < 0).ravel())
    measure = sections.measure if offset is None else sections.fixed_heading(offset)[1]
    return np.flatnonzero(measure > 0)


def sample_outcomes(model: CellModel, angles: np.ndarray, samples: int,
                    rng: np.random.Generator, dynamics: dict, max_ticks: int,
                    offset: float | None = None) -> BumpOutcomes:
    """``samples`` sample points of every decision state and angle, simulated (module docstring).

    Args:
        model: the cell model whose cell numbers are the decision states.
        angles: (|Φ|,) bounce angles in radians.
        samples: sample points per state and angle.
        rng: the generator of the poses and of the dynamics' noise.
        dynamics: keyword arguments of `BounceDynamics` (world first, as ``world``): backend,
            rule, noise, radius, step_length, backend_options, physics, physics_params.
        max_ticks: a sample not bumping again within this many ticks is lost (next state −1).
        offset: headings exactly at bin + ``offset`` (radians; see `BumpSections`); None
            spreads them over the bin.
    """
    angles = np.asarray(angles, dtype=np.float64).reshape(-1)
    on_grid = dynamics.get("backend") == "cell"
    sections = None if on_grid else BumpSections(model)
    cells = bump_cells(model, sections, offset)
    per_state = samples * len(angles)
    if on_grid:
        point, heading = model.configuration(np.repeat(cells, per_state))
    elif offset is None:
        point, heading, _ = sections.sample(cells, per_state, rng)
    else:
        point, heading, _ = sections.sample_heading(cells, per_state, rng, offset)
    state = np.repeat(cells, per_state)
    action = np.tile(np.repeat(np.arange(len(angles)), samples), len(cells))
    params = dict(dynamics)
    world = params.pop("world")
    sim = BounceDynamics(world, len(state), robot_collisions="ignore", **params)
    start = np.array(point, dtype=np.float64)
    sim.reset(rng, start, heading)
    # poses on the boundary of the free space that do not read as contacts (round-off at a
    # grazing angle) are no sample points of a bump
    ok = sim.state.blocked.copy()
    end, final, ticks, done = _drive(sim, angles[action], max_ticks)
    states = BumpStates(model)
    nxt = np.where(done, states.of(end, final, sim.state.contact_normal), -1)
    return BumpOutcomes(model.n_cells, angles, state[ok], action[ok], nxt[ok], ticks[ok],
                        start[ok], end[ok], final[ok])


def _drive(sim: BounceDynamics, params: np.ndarray, max_ticks: int
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every robot bumps with its angle and drives to its next contact: end points, headings,
    clocks and whether it got there within ``max_ticks``."""
    state = sim.state
    if sim.backend.drives_independently and not sim.backend.turns_take_time:
        ticks = sim.bounce_each(params)
        return state.position.copy(), state.heading.copy(), ticks, np.ones(len(ticks), bool)
    m = sim.n_robots
    end, heading = np.zeros((m, 2)), np.zeros(m)
    ticks, done = np.zeros(m, dtype=np.int64), np.zeros(m, dtype=bool)
    normal = np.zeros((m, 2))
    for _ in range(max_ticks):
        sim.tick(params)
        new = state.blocked & ~done
        end[new], heading[new] = state.position[new], state.heading[new]
        ticks[new], normal[new] = state.clock[new], state.contact_normal[new]
        done |= new
        if done.all():
            break
    state.contact_normal[:] = normal  # the contacts at the recorded bumps
    return end, heading, ticks, done


def first_bumps(model: CellModel, position: np.ndarray, heading: float, n: int,
                rng: np.random.Generator, dynamics: dict) -> tuple[np.ndarray, np.ndarray]:
    """The decision states and clocks of ``n`` simulated robots after the drive of a
    bounce-mode reset from the pose (``position``, ``heading``)."""
    params = dict(dynamics)
    world = params.pop("world")
    sim = BounceDynamics(world, n, robot_collisions="ignore", **params)
    sim.reset(rng, np.repeat(np.asarray(position, dtype=np.float64).reshape(1, 2), n, axis=0),
              np.full(n, float(heading)))
    sim.drive_to_contact()
    if not sim.state.blocked.all():  # robots in step: drive the rest to their contacts
        for _ in range(model.n_cells * 4):
            if sim.state.blocked.all():
                break
            sim.backend.drive(sim.state, 1, until_first_block=False)
    state = sim.state
    return BumpStates(model).of(state.position, state.heading, state.contact_normal), \
        state.clock.copy()
