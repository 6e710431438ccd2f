"""A particle belief over a robot's pose at its bumps, moved by the env's own dynamics.

Monte Carlo localization (Thrun, Burgard & Fox, *Probabilistic Robotics*, 2005, §4.3 and §8.3)
for a robot that senses only its bumps and its clock. The belief is a set of weighted pose
particles: contact poses (position, heading) at the particles' last bumps, moved by
`BounceDynamics` robots that ignore each other (``robot_collisions="ignore"``) with the env's
backend, rule, noise, radius, step length and physics.

* **Motion model.** At a bump every particle is placed at its pose, executes the commanded
  bounce angle and drives to its own next contact (`bounce_gym.dynamics.bump_sampler.
  simulate_bumps`, the seam of the sampled GCM): the simulator itself, so each particle draws
  its own executed rotation from the env's noise model, and turns that take time, motors and
  sliding are simulated as the env does (the sampling motion model of §4.3, with the real
  dynamics in place of an odometry formula). A pose that does not read as a contact when
  placed (on the dynamic physics, a robot that braked off its wall) explains no clock.
* **Measurement model.** The clock at the bump (ticks since the last one, read as the robot reads
  it: capped at ``max_clock``). A particle whose clock equals the robot's has likelihood 1, one
  within ``tolerance`` ticks ``slack`` (defaults 1 tick, 0.05), any other 0. The tolerance
  keeps a group of particles around the true pose alive through one bump that none of them
  reproduces exactly (finitely many particles only approximate the set of consistent poses).
* **Roughening.** Before every bump each particle's heading is perturbed by a normal error of
  standard deviation ``jitter`` (default 0.5°): artificial process noise against particle
  deprivation (§4.3.4). A billiard separates nearby poses quickly, and the set of poses that
  agree with a long clock history is thin; without the perturbation the particles near the
  true pose all disagree with the robot after some bumps while a group elsewhere that happens
  to agree takes the whole mass — a confident wrong claim (measured on lab_localization_a
  without noise: 3 wrong claims in 50 episodes without it, 1 in 200 with it).
* **Resampling** (low-variance resampling, §4.3.4) only when the effective sample size
  1 / Σ w² falls below half the particle count: while every particle explains the clocks the
  weights stay as they are, so resampling noise cannot drift the mass of two equally
  consistent groups of poses onto one of them.
* **Depletion.** When no particle explains the clock the belief restarts from the global prior
  (the sensor-reset idea of augmented MCL, §8.3.5, taken to its end: everything is forgotten);
  `restarts` counts it. A share ``restart`` of the particles may also be redrawn from the prior
  at every update (0 by default: such particles would sit in wrong states and hold mass there).
* **Prior.** Global localization: the robot starts at a uniform pose of the free space with a
  uniform heading and drives to its first contact (what a bounce-mode reset does); the particles
  are such drives, kept where their clock equals the clock the robot read after its reset.

The belief is read as mass per decision state (cell × heading bin of a `CellModel` at the bump,
`bounce_gym.cells.bump_states`). Particles are kept as pose arrays between updates (exactly the
contacts the simulator computed, which round-trip as starts); resampling indexes them, and
every prediction re-places the particles in fresh simulators (pymunk: physics spaces of a few
robots each, `bump_sampler.BATCH`). Any backend with continuous headings is supported
(`supported`). Where the backend drives robots independently and turns them instantly (the
kinematic backend) the particles instead stay the robots of one simulator between bumps and
resampling permutes its robot state: the same filter, without the cost of placing every
particle again at every bump (about two thirds of an update's time on the lab map).
"""

from __future__ import annotations

import copy
from dataclasses import fields

import numpy as np

from bounce_gym.cells.bump_states import BumpStates
from bounce_gym.cells.model import CellModel
from bounce_gym.dynamics.bump_sampler import default_max_ticks, reset_drives, simulate_bumps
from bounce_gym.dynamics.simulator import BounceDynamics
from bounce_gym.errors import ConfigError

#: default number of particles
DEFAULT_PARTICLES = 10_000
#: default roughening (radians, standard deviation) of every particle's heading before a bump
DEFAULT_JITTER = float(np.radians(0.5))
#: default ticks either side of the clock read that a particle may be off by
DEFAULT_TOLERANCE = 1
#: default likelihood of a particle off by 1 … ``tolerance`` ticks (one off by 0 has 1)
DEFAULT_SLACK = 0.05
#: prior poses drawn per batch (times the particle count) while filling the prior
_PRIOR_BATCH = 4
#: batches tried before the prior gives up on the clock read at reset
_PRIOR_TRIES = 50


def supported(dynamics: BounceDynamics) -> bool:
    """Whether the particle belief can move particles with ``dynamics``: continuous headings."""
    return dynamics.backend.bin_width is None


class ParticleBelief:
    """The particle belief of the module docstring.

    Args:
        model: the cell model whose cell numbers are the decision states.
        dynamics: keyword arguments of `BounceDynamics` with the ``world`` (backend, rule, noise,
            radius, step_length, backend_options).
        n_particles: particles kept.
        max_clock: the largest clock the robot reads (clocks are capped there).
        tolerance, slack: ticks either side of the clock read that still count, with weight
            ``slack`` (module docstring).
        jitter: standard deviation of the roughening of every heading before a bump
            (radians; None: `DEFAULT_JITTER`).
        restart: share of particles redrawn from the prior at every update.
        max_ticks: the longest simulated drive (None: `bump_sampler.default_max_ticks`); a
            particle that does not bump again within it explains no clock.

    ``reset(rng, clock)`` or ``reset_at(rng, position, heading)``; ``update(angle, clock)``;
    ``position``, ``heading`` (the particles' poses at their last bump), ``states`` (decision
    state of every particle, −1 for one not at a contact), ``weight``, ``mass()``
    (state → mass), ``max_mass``, ``most_likely``, ``entropy``, ``expected_entropy(angles)``.
    """

    def __init__(self, model: CellModel, dynamics: dict, n_particles: int = DEFAULT_PARTICLES,
                 max_clock: int | None = None, tolerance: int = DEFAULT_TOLERANCE,
                 slack: float = DEFAULT_SLACK,
                 jitter: float | None = None, restart: float = 0.0,
                 max_ticks: int | None = None) -> None:
        if isinstance(n_particles, bool) or not isinstance(n_particles, int | np.integer) \
                or n_particles < 1:
            raise ConfigError(f"particles: expected an integer >= 1, got {n_particles!r}")
        if not 0.0 <= float(slack) <= 1.0 or not 0.0 <= float(restart) < 1.0:
            raise ConfigError(f"slack, restart: expected numbers in [0, 1] and [0, 1), got "
                              f"{slack!r}, {restart!r}")
        self.model, self.n = model, int(n_particles)
        self.states_of = BumpStates(model)
        self.dynamics = dict(dynamics)
        self.jitter = DEFAULT_JITTER if jitter is None else float(jitter)
        self.max_clock = max_clock
        self.max_ticks = default_max_ticks(self.dynamics) if max_ticks is None else int(max_ticks)
        self.tolerance, self.slack, self.restart = int(tolerance), float(slack), float(restart)
        probe = self._simulator(1)
        #: particles kept as the robots of one simulator (module docstring)
        self.in_place = probe.backend.drives_independently and not probe.backend.turns_take_time
        if not supported(probe):
            raise ConfigError(f"particle belief: backend {dynamics.get('backend')!r} is not "
                              "supported (it needs continuous headings)")
        self.restarts = 0

    # -- construction -------------------------------------------------------------------------
    def _simulator(self, m: int) -> BounceDynamics:
        params = dict(self.dynamics)
        return BounceDynamics(params.pop("world"), m, robot_collisions="ignore", **params)

    def _read(self, clock: np.ndarray) -> np.ndarray:
        clock = np.asarray(clock, dtype=np.int64)
        return clock if self.max_clock is None else np.minimum(clock, self.max_clock)

    def _drives(self, point: np.ndarray, heading: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Robots at start poses drive to their first contact: states (−1: none), contact
        points, headings, clocks."""
        return reset_drives(self.model, self.dynamics, point, heading, self.rng, self.max_ticks)

    def _prior(self, clock: int | None, n: int) -> tuple[np.ndarray, ...]:
        """``n`` uniform start poses driven to their first contact, where the drive reads
        ``clock`` (None: any) — or, if no drawn pose reads it, the nearest clock any does:
        start points and headings, bump points, headings and states."""
        kept: list[tuple[np.ndarray, ...]] = []
        best = np.inf  # the least clock gap of the poses kept so far
        for _ in range(_PRIOR_TRIES):
            state = self._simulator(_PRIOR_BATCH * n).reset(self.rng)
            z, point, heading, ticks = self._drives(state.position, state.heading)
            gap = np.zeros(len(z)) if clock is None \
                else np.abs(self._read(ticks) - self._read(clock)).astype(np.float64)
            gap[z < 0] = np.inf
            least = gap.min(initial=np.inf)
            if least < best:  # only the nearest clock is kept: memory stays bounded
                kept, best = [], least
            if least == best and np.isfinite(least):
                keep = gap == least
                kept.append((state.position[keep], state.heading[keep], point[keep],
                             heading[keep], z[keep]))
            if best == 0 and sum(len(part[-1]) for part in kept) >= n:
                break
        if not kept:
            raise ConfigError("particle belief: no start pose drives to a contact")
        poses = [np.concatenate(part) for part in zip(*kept, strict=True)]
        pick = self.rng.choice(len(poses[0]), n, replace=len(poses[0]) < n)
        return tuple(part[pick] for part in poses)

    def reset(self, rng: np.random.Generator, clock: int | None = None) -> None:
        """Global localization: the prior of the module docstring, conditioned on the ``clock``
        read after the reset drive (None: not conditioned)."""
        self.rng = rng
        self.restarts = 0
        self._place(*self._prior(clock, self.n))

    def reset_at(self, rng: np.random.Generator, position: np.ndarray,
                 heading: np.ndarray) -> None:
        """Particles driven to their first contact from the given start poses (n, 2), (n,)."""
        self.rng = rng
        self.restarts = 0
        position = np.asarray(position, dtype=np.float64).reshape(-1, 2)
        self.n = len(position)
        heading = np.asarray(heading, dtype=np.float64).reshape(-1)
        self._place(position, heading, *self._drive_starts(position, heading))

    def _drive_starts(self, position: np.ndarray, heading: np.ndarray) -> tuple[np.ndarray, ...]:
        """Bump points, headings and states of start poses driven to their first contact
        (nothing driven where the particles live in one simulator: `_place` drives them)."""
        if self.in_place:
            return None, None, None
        z, point, final, _ = self._drives(position, heading)
        return point, final, z

    def _place(self, start: np.ndarray, start_heading: np.ndarray, position: np.ndarray | None,
               heading: np.ndarray | None, states: np.ndarray | None) -> None:
        """The particles at their first contact: driven there from the start poses in one
        simulator (`in_place`), else the bump poses and states given."""
        self.weight = np.full(len(start), 1.0 / len(start))
        if self.in_place:
            self.sim = self._simulator(len(start))
            state = self.sim.reset(self.rng, start, start_heading)
            self.sim.backend.drive_each(state)
            self._refresh()
        else:
            self.position, self.heading, self.states = position, heading, states

    def _refresh(self) -> None:
        """The decision states of the particles in the simulator (`in_place`)."""
        state = self.sim.state
        self.position, self.heading = state.position, state.heading
        self.states = self.states_of.of(state.position, state.heading, state.contact_normal)
        self.states[~state.blocked] = -1

    # -- the filter ---------------------------------------------------------------------------
    def _predict(self, angle: float, heading: np.ndarray, rng: np.random.Generator
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Every particle bumps with ``angle`` from its position (with ``heading``) and drives
        on, in fresh simulators: its clock, next decision state (−1: no next bump), point and
        heading there."""
        n = len(heading)
        out = simulate_bumps(self.model, np.array([float(angle)]), np.zeros(n, dtype=np.int64),
                             self.position, heading, rng, self.dynamics, self.max_ticks)
        return self._read(out.ticks), out.next_state, out.end, out.heading

    def _bounce(self, sim: BounceDynamics, angle: float) -> np.ndarray:
        """Every particle of ``sim`` (`in_place`) bumps with ``angle`` and drives on; clocks."""
        sim.bounce_each(np.full(sim.n_robots, float(angle)))
        return self._read(sim.state.clock)

    def update(self, angle: float, clock: int) -> None:
        """The robot bounced by ``angle`` (radians, commanded) and read ``clock`` at its next
        bump."""
        if self.restart > 0:
            self._redraw(self.rng.random(self.n) < self.restart)
        heading = self.heading
        if self.jitter > 0:  # roughening: every particle's heading, before its bump
            heading = (heading + self.rng.normal(0.0, self.jitter, self.n)) % (2 * np.pi)
        if self.in_place:
            self.heading[...] = heading
            ticks = self._bounce(self.sim, angle)
            arrived = self.sim.state.blocked
        else:
            ticks, states, end, final = self._predict(angle, heading, self.rng)
            arrived = states >= 0
        gap = np.abs(ticks - self._read(clock))
        weight = np.where(gap == 0, 1.0, np.where(gap <= self.tolerance, self.slack, 0.0))
        weight[~arrived] = 0.0
        weight *= self.weight
        if weight.sum() <= 0:
            self.restarts += 1
            self._place(*self._prior(None, self.n))
            return
        self.weight = weight / weight.sum()
        if self.in_place:
            self._refresh()
        else:
            self.position, self.heading, self.states = end, final, states
        if 1.0 / np.square(self.weight).sum() < 0.5 * self.n:
            self._resample(self.weight)

    def _redraw(self, which: np.ndarray) -> None:
        """Particles ``which`` replaced by prior poses (at their first contact)."""
        if not which.any():
            return
        start, start_heading, point, heading, z = self._prior(None, int(which.sum()))
        if self.in_place:
            fresh = self._simulator(len(start))
            state = fresh.reset(self.rng, start, start_heading)
            fresh.backend.drive_each(state)
            mine = self.sim.state
            for name in _per_robot(mine):
                getattr(mine, name)[which] = getattr(state, name)
            self._refresh()
        else:
            self.position[which], self.heading[which], self.states[which] = point, heading, z
        self.weight[which] = self.weight[~which].mean() if (~which).any() else 1.0
        self.weight /= self.weight.sum()

    def _resample(self, weight: np.ndarray) -> None:
        """Low-variance resampling (Thrun et al. 2005, Table 4.4): the poses indexed (the
        simulator's robot state permuted where the particles live in it)."""
        cumulative = np.cumsum(weight / weight.sum())
        cumulative[-1] = 1.0
        marks = (self.rng.random() + np.arange(self.n)) / self.n
        pick = np.searchsorted(cumulative, marks, side="right")
        if self.in_place:
            state = self.sim.state
            for name in _per_robot(state):
                values = getattr(state, name)
                values[...] = values[pick]
            self._refresh()
        else:
            self.position, self.heading = self.position[pick], self.heading[pick]
            self.states = self.states[pick]
        self.weight = np.full(self.n, 1.0 / self.n)

    # -- reading the belief -------------------------------------------------------------------
    def mass(self) -> tuple[np.ndarray, np.ndarray]:
        """The decision states holding particles and their mass (summing to 1 over the
        particles at a contact)."""
        states, inverse = np.unique(self.states, return_inverse=True)
        return states, np.bincount(inverse.ravel(), weights=self.weight)

    @property
    def max_mass(self) -> float:
        states, mass = self.mass()
        return float(mass[states >= 0].max(initial=0.0))

    @property
    def most_likely(self) -> int:
        states, mass = self.mass()
        mass = np.where(states >= 0, mass, -1.0)
        return int(states[np.argmax(mass)])

    @property
    def entropy(self) -> float:
        """Entropy (bits) of the mass over decision states."""
        return _entropy(self.states, self.weight)

    def expected_entropy(self, angles: np.ndarray) -> np.ndarray:
        """For every angle: the expected entropy (bits) of the belief over decision states
        after the next bump, over the clocks it would read (each particle simulated from its
        pose with a copy of the generator, so the belief's own stream is not advanced)."""
        out = np.zeros(len(angles))
        for i, angle in enumerate(np.asarray(angles, dtype=np.float64)):
            if self.in_place:
                sim = copy.deepcopy(self.sim, memo={id(self.dynamics["world"]):
                                                    self.dynamics["world"]})
                ticks = self._bounce(sim, angle)
                state = self.states_of.of(sim.state.position, sim.state.heading,
                                          sim.state.contact_normal)
            else:
                ticks, state = self._predict(angle, self.heading, copy.deepcopy(self.rng))[:2]
            for t in np.unique(ticks):
                seen = ticks == t
                out[i] += self.weight[seen].sum() * _entropy(state[seen], self.weight[seen])
        return out


def _per_robot(state) -> list[str]:
    """The fields of a `RobotState` that hold one entry per robot (not the shared tick count)."""
    return [f.name for f in fields(state) if isinstance(getattr(state, f.name), np.ndarray)]


def _entropy(values: np.ndarray, weight: np.ndarray) -> float:
    """Entropy (bits) of the weighted values."""
    _, inverse = np.unique(values, return_inverse=True)
    p = np.bincount(inverse.ravel(), weights=weight)
    p = p[p > 0] / p.sum()
    return float(-(p * np.log2(p)).sum())
