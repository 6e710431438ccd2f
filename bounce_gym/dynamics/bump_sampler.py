"""Sample points of a generalized cell mapping, simulated by the env's own dynamics.

`sample_outcomes` places many robots (``robot_collisions="ignore"``: each is an independent
sample point) at poses drawn from every decision state of a `CellModel` — on the ``cell``
backend the cell's own centre and bin heading, elsewhere the bump sections of
`bounce_gym.cells.sections` — lets each bump once with one angle of Φ through `BounceDynamics`
(the rule, the noise and the backend of the env, so rotations that take time or slip are
simulated as the env does) and records where and after how many ticks of its clock each one
bumps next (`bounce_gym.cells.outcomes.BumpOutcomes`). The kinematic backend drives all robots
to their own contacts in one vectorised call; the others (pymunk) are stepped tick by tick in
batches of `BATCH` robots, and a robot is done at the end of the first tick in which it is
blocked again (it then stays where it stopped while the rest of its batch drives on). A pose
that does not read as a contact when placed is no sample point; on the dynamic physics those
are the few bump poses where a robot braked off its contact (sliding past a corner) and came
to rest clear of it. The poses are then redrawn
from where the robots arrived (`ROUNDS`).

`reset_drives` simulates the drive of a bounce-mode reset from start poses in the free space the
same way (`first_bumps`: from one known start pose, the initial distribution of the decision
state).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from bounce_gym.cells.bump_states import BumpStates
from bounce_gym.cells.model import CellModel
from bounce_gym.cells.outcomes import BumpOutcomes
from bounce_gym.cells.sections import BumpSections
from bounce_gym.dynamics.simulator import BounceDynamics

#: Rounds of re-sampling. The sections' measure spreads the poses of a state along its walls,
#: while robots arrive at some poses far more often (a robot driving along a wall ends in the
#: corner; without noise, robots started at cell centres meet the walls only at a lattice of
#: points). So the poses of a state are drawn from a pool of poses where robots actually
#: arrived in it — first the reset drives from every cell centre and bin, then the arrivals of
#: every round — and a share `EXPLORE` (all, for a state no robot arrived in yet) from the
#: sections. The outcomes are those of the last round.
ROUNDS = 6
#: how far (in world tolerances) a pose drawn on the sections is moved into the free space:
#: below the backends' contact tolerance (10 tolerances), so it still touches the wall
INSET = 2.0
#: the largest distance between `World.eroded`'s chords and the arcs they approximate, in R
CHORD_SAG = 1.5e-3
EXPLORE = 0.0
#: Robots simulated in one physics space where the backend steps them together (pymunk): a
#: space steps at every event of every robot in it, so the work per robot grows with the
#: batch; robots ignore each other, so a batch changes no sample point's physics
BATCH = 8


def default_max_ticks(dynamics: dict) -> int:
    """The default bound on a simulated drive: four drives across the world's diameter."""
    step = dynamics.get("step_length", 1.0)
    return 4 * (math.ceil(dynamics["world"].diameter / step) + 1)


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
                    offset: float | None = None, rounds: int = ROUNDS,
                    explore: float = EXPLORE) -> BumpOutcomes:
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
        rounds: rounds of re-sampling from the arrivals (see `ROUNDS`); the outcomes are
            those of the last round.
        explore: the share of each round's poses still drawn from the sections.
    """
    angles = np.asarray(angles, dtype=np.float64).reshape(-1)
    on_grid = dynamics.get("backend") == "cell"
    sections = None if on_grid else BumpSections(model)
    measured = bump_cells(model, sections, offset)
    if on_grid:
        state, action = _units(measured, samples, len(angles))
        point, heading = model.configuration(state)
        return _simulate(model, angles, state, action, point, heading, rng, dynamics, max_ticks)
    # the pool of arrivals: first the reset drives from the centre of every free cell of the
    # robot's step (where the cell-backend starts of the tasks lie) with every bin's heading
    centre, start_heading = _step_grid_starts(model, dynamics.get("step_length", 1.0))
    start_heading = start_heading + (offset if offset is not None else rng.uniform(
        -0.5 * model.bin_width, 0.5 * model.bin_width, len(start_heading)))
    pool = reset_drives(model, dynamics, centre, start_heading, rng, max_ticks)[:3]
    for _ in range(rounds + 1):
        pool_state, pool_end, pool_heading = pool
        # the states of positive measure, and those robots arrived in (a corner's vertex)
        cells = np.union1d(measured, pool_state[pool_state >= 0])
        state, action = _units(cells, samples, len(angles))
        point, heading = np.zeros((len(state), 2)), np.zeros(len(state))
        drawn = np.isin(state, measured)
        sampler = sections.sample if offset is None else functools.partial(
            sections.sample_heading, offset=offset)
        drawn_point, heading[drawn], normal = sampler(cells[np.isin(cells, measured)],
                                                      samples * len(angles), rng)
        # a hair into the free space (within the backends' contact tolerance): a disk's centre
        # exactly on the eroded boundary may read as outside it by round-off
        drawn_point = drawn_point + INSET * model.world.tol * normal
        # on the chords that stand for a disk's arcs around corners (inside the arc by up to
        # `CHORD_SAG` R) the pose is moved onto the arc's side; it then rarely reads as a
        # contact and is dropped, while the pool brings the poses where robots really touch
        outside = ~model.world.contains(drawn_point, model.robot_radius)
        drawn_point[outside] += CHORD_SAG * model.robot_radius * normal[outside]
        point[drawn] = drawn_point
        order = np.argsort(pool_state, kind="stable")
        first = np.searchsorted(pool_state[order], state, side="left")
        count = np.searchsorted(pool_state[order], state, side="right") - first
        reuse = (count > 0) & ((rng.random(len(state)) >= explore) | ~drawn)
        pick = order[first[reuse] + (rng.random(int(reuse.sum())) * count[reuse]).astype(
            np.int64)]
        point[reuse], heading[reuse] = pool_end[pick], pool_heading[pick]
        out = _simulate(model, angles, state, action, point, heading, rng, dynamics,
                        max_ticks)
        arrived = out.next_state >= 0
        pool = (np.concatenate((pool_state, out.next_state[arrived])),
                np.concatenate((pool_end, out.end[arrived])),
                np.concatenate((pool_heading, out.heading[arrived])))
    return out


def _units(cells: np.ndarray, samples: int, n_angles: int) -> tuple[np.ndarray, np.ndarray]:
    """The state and angle of every sample point: ``samples`` per state and angle."""
    per_state = samples * n_angles
    return (np.repeat(cells, per_state),
            np.tile(np.repeat(np.arange(n_angles), samples), len(cells)))


def _step_grid_starts(model: CellModel, step: float) -> tuple[np.ndarray, np.ndarray]:
    """The centres of the free cells of side ``step`` × every bin's heading."""
    world = model.world
    free = world.occupancy(step, model.robot_radius)
    rc = np.argwhere(free)
    xmin, ymin = world.bounds[:2]
    centre = np.column_stack((xmin + (rc[:, 1] + 0.5) * step, ymin + (rc[:, 0] + 0.5) * step))
    heading = np.arange(model.n_bins) * model.bin_width
    return np.repeat(centre, model.n_bins, axis=0), np.tile(heading, len(centre))


def _parts(dynamics: dict, n: int) -> list[slice]:
    """The batches of ``n`` robots simulated together: all at once where the backend drives
    robots independently (one vectorised call), else `BATCH` at a time."""
    params = dict(dynamics)
    probe = BounceDynamics(params.pop("world"), 1, robot_collisions="ignore", **params)
    size = max(n, 1) if probe.backend.drives_independently else BATCH
    return [slice(lo, min(lo + size, n)) for lo in range(0, n, size)]


def _simulator(dynamics: dict, n: int) -> BounceDynamics:
    params = dict(dynamics)
    return BounceDynamics(params.pop("world"), n, robot_collisions="ignore", **params)


@dataclass(frozen=True)
class RestDrives:
    """Robots placed at rest that drove straight to their first contact (`drive_from_rest`),
    one entry per robot.

    Attributes:
        blocked: whether it was blocked within the limit.
        end, heading, normal: (n, 2) where it stopped, (n,) its heading there and (n, 2) the
            normal of the contact it latched (into the free space).
        clock: ticks from the start to the end of the tick in which it was blocked (0: blocked
            where it was placed).
        odometer: distance it drove.
    """

    blocked: np.ndarray
    end: np.ndarray
    heading: np.ndarray
    normal: np.ndarray
    clock: np.ndarray
    odometer: np.ndarray


def drive_from_rest(dynamics: dict, point: np.ndarray, heading: np.ndarray,
                    rng: np.random.Generator, max_ticks: int) -> RestDrives:
    """Robots placed at rest at (``point``, ``heading``) drive straight to their first contact,
    as a bounce-mode reset does; each is read at the end of the first tick in which it is
    blocked (its clock then stops counting: blocked robots of a batch otherwise go on counting
    the ticks the others still drive)."""
    point = np.asarray(point, dtype=np.float64)
    heading = np.asarray(heading, dtype=np.float64)
    n = len(point)
    done, end, final = np.zeros(n, dtype=bool), np.zeros((n, 2)), np.zeros(n)
    normal, clock, odometer = np.zeros((n, 2)), np.zeros(n, dtype=np.int64), np.zeros(n)
    for part in _parts(dynamics, n):
        sim = _simulator(dynamics, part.stop - part.start)
        state = sim.reset(rng, point[part], heading[part])
        if sim.backend.drives_independently:
            sim.backend.drive_each(state)
        got = np.zeros(part.stop - part.start, dtype=bool)
        for tick in range(max_ticks + 1):
            new = state.blocked & ~got
            idx = np.arange(part.start, part.stop)[new]
            end[idx], final[idx], normal[idx] = (state.position[new], state.heading[new],
                                                 state.contact_normal[new])
            clock[idx], odometer[idx] = state.clock[new], state.odometer[new]
            got |= new
            if got.all() or tick == max_ticks:
                break
            sim.backend.drive(state, 1, until_first_block=False)
        done[part] = got
        rest = np.arange(part.start, part.stop)[~got]
        end[rest], final[rest] = state.position[~got], state.heading[~got]
        clock[rest], odometer[rest] = state.clock[~got], state.odometer[~got]
    return RestDrives(done, end, final, normal, clock, odometer)


def reset_drives(model: CellModel, dynamics: dict, point: np.ndarray, heading: np.ndarray,
                  rng: np.random.Generator, max_ticks: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Robots placed at poses in the free space drive straight to their first contact, as a
    bounce-mode reset does (`drive_from_rest`): their decision states (−1: none within
    ``max_ticks``), contact points, headings and clocks."""
    out = drive_from_rest(dynamics, point, heading, rng, max_ticks)
    z = BumpStates(model).of(out.end, out.heading, out.normal)
    return np.where(out.blocked, z, -1), out.end, out.heading, out.clock


def simulate_bumps(model: CellModel, angles: np.ndarray, action: np.ndarray, point: np.ndarray,
                   heading: np.ndarray, rng: np.random.Generator, dynamics: dict,
                   max_ticks: int) -> BumpOutcomes:
    """Robots at bump poses (``point``, ``heading``) bump with ``angles[action]`` and drive to
    their next bump: one outcome per robot, in order (a pose that is not in contact keeps its
    place: next state −1, no ticks, its end its start)."""
    state = BumpStates(model).of(point, heading, np.zeros_like(point))
    return _simulate(model, angles, np.maximum(state, 0), action, point, heading, rng, dynamics,
                     max_ticks, keep_all=True)


def _simulate(model: CellModel, angles: np.ndarray, state: np.ndarray, action: np.ndarray,
              point: np.ndarray, heading: np.ndarray, rng: np.random.Generator,
              dynamics: dict, max_ticks: int, keep_all: bool = False) -> BumpOutcomes:
    """One robot per (state, action, pose): bump with the angle, drive to the next bump;
    poses not in contact are dropped (``keep_all``: kept, with next state −1)."""
    start = np.array(point, dtype=np.float64)
    heading = np.asarray(heading, dtype=np.float64)
    n = len(state)
    ok, done = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    end, final, normal = np.zeros((n, 2)), np.zeros(n), np.zeros((n, 2))
    ticks = np.zeros(n, dtype=np.int64)
    for part in _parts(dynamics, n):
        sim = _simulator(dynamics, part.stop - part.start)
        sim.reset(rng, start[part], heading[part])
        # poses on the boundary of the free space that do not read as contacts (round-off at
        # a grazing angle) are no sample points of a bump
        ok[part] = sim.state.blocked
        end[part], final[part], ticks[part], done[part], normal[part] = _drive(
            sim, angles[action[part]], max_ticks)
    nxt = np.where(done, BumpStates(model).of(end, final, normal), -1)
    if keep_all:
        nxt = np.where(ok, nxt, -1)
        end, ticks = np.where(ok[:, None], end, start), np.where(ok, ticks, 0)
        ok = np.ones(len(ok), dtype=bool)
    return BumpOutcomes(model.n_cells, angles, state[ok], action[ok], nxt[ok], ticks[ok],
                        start[ok], end[ok], final[ok])


def _drive(sim: BounceDynamics, params: np.ndarray, max_ticks: int
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every robot bumps with its angle and drives to its next contact: end points, headings,
    clocks, whether it got there within ``max_ticks``, and the contact normals there.

    Robots that drive one at a time (the kinematic backend) do so in one call. Elsewhere the
    bump tick is one `BounceDynamics.tick` and the drive goes on tick by tick through the
    backend alone, so a robot that has bumped again stays blocked where it stopped (no further
    bump of it is simulated) while the others drive on."""
    state = sim.state
    if sim.backend.drives_independently and not sim.backend.turns_take_time:
        ticks = sim.bounce_each(params)
        return (state.position.copy(), state.heading.copy(), ticks,
                np.ones(len(ticks), dtype=bool), state.contact_normal.copy())
    m = sim.n_robots
    end, heading = np.zeros((m, 2)), np.zeros(m)
    ticks, done = np.zeros(m, dtype=np.int64), np.zeros(m, dtype=bool)
    normal = np.zeros((m, 2))
    sim.tick(params)
    for tick in range(max_ticks):
        new = state.blocked & ~done
        end[new], heading[new] = state.position[new], state.heading[new]
        ticks[new], normal[new] = state.clock[new], state.contact_normal[new]
        done |= new
        if done.all() or tick == max_ticks - 1:
            break
        sim.backend.drive(state, 1, until_first_block=False)
    return end, heading, ticks, done, normal


def first_bumps(model: CellModel, position: np.ndarray, heading: float, n: int,
                rng: np.random.Generator, dynamics: dict, max_ticks: int
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The decision states, contact points, headings and clocks of ``n`` simulated robots
    after the drive of a bounce-mode reset from the pose (``position``, ``heading``)."""
    point = np.repeat(np.asarray(position, dtype=np.float64).reshape(1, 2), n, axis=0)
    return reset_drives(model, dynamics, point, np.full(n, float(heading)), rng, max_ticks)
