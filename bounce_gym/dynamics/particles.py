"""A particle belief over a robot's pose at its bumps, moved by the env's own dynamics.

Monte Carlo localization (Thrun, Burgard & Fox, *Probabilistic Robotics*, 2005, §4.3 and §8.3)
for a robot that senses only its bumps and its clock. The belief is a set of weighted pose
particles: contact poses (position, heading) at the particles' last bumps.

* **Motion model.** Particles move only through a ``motion`` object with the two methods of
  `bounce_gym.dynamics.bump_table.BumpMotion` (the default, `bump_motion`): ``bumps`` (every
  particle executes the commanded bounce angle and drives to its own next contact) and
  ``reset_drives`` (start poses drive to their first contact). Every particle draws its own
  executed rotation from the env's noise model (the sampling motion model of §4.3, with the
  real dynamics in place of an odometry formula); the drive is simulated with `BounceDynamics`
  robots that ignore each other and share the env's backend, rule, noise, radius, step length
  and physics — or, on pymunk's dynamic physics, read from the tabulated bump map of those
  drives (`bounce_gym.dynamics.bump_table`, about 300 times faster). A pose that does not read
  as a contact when placed explains no clock.
* **Measurement model.** The clock at the bump (ticks since the last one, read as the robot reads
  it: capped at ``max_clock``). A particle whose clock equals the robot's has likelihood 1, one
  within ``tolerance`` ticks ``slack`` (defaults 1 tick, 0.05), any other 0. The tolerance
  keeps a group of particles around the true pose alive through one bump that none of them
  reproduces exactly.
* **Roughening.** Before every bump each particle's heading is perturbed by a normal error of
  standard deviation ``jitter`` (default 0.5°): artificial process noise against particle
  deprivation (§4.3.4). A billiard separates nearby poses quickly, and the set of poses that
  agree with a long clock history is thin.
* **Resampling** (low-variance resampling, §4.3.4, Table 4.4) when the effective sample size
  falls below half the particle count, or when particles are injected (below): while every
  particle explains the clocks the weights stay as they are, so resampling noise cannot drift
  the mass of two equally consistent groups of poses onto one of them.
* **Effective sample size** ``ess`` = 1 / Σ w² of the weights right after the measurement, before
  any resampling. Resampling makes every weight equal and would hide how few particles carried
  the mass; after the next roughened bump the copies are distinct hypotheses again, each tested
  by the clock, so the ESS of the next measurement counts them honestly. The claims of
  `bounce_gym.envs.tasks.localization.ParticleClaims` need it above a floor.
* **Recovery: augmented MCL with sensor resetting.** The average likelihood of a measurement
  under the predicted belief, w_avg = Σ w p(clock | particle), feeds a short- and a long-term
  average, w_fast and w_slow (rates ``alpha_fast`` > ``alpha_slow``; both start at the first
  w_avg), and a share max(0, 1 − w_fast / (κ w_slow)) of the particles is replaced by fresh
  ones at the resampling (augmented MCL, §8.3.5, Table 8.3, which has κ = 1). A sudden run of
  clocks the belief explains worse than it used to — the robot was kidnapped, or the particles
  near the true pose died — so brings in new hypotheses, while a belief that explains the
  clocks as well as ever gets none. The dead band κ = ``inject_below`` (default 0.5) is ours:
  here w_avg swings from bump to bump (a robot whose rotation error few particles drew, a long
  drive that spreads the particles' clocks: single bumps at 0.1–0.3 amid 1.0 were seen on the
  lab map), and with κ = 1 every such swing injected a share of particles, which holds the
  mass of a well localized belief below a 0.99 claim (tests/dynamics/test_particles.py,
  seeds 1 and 2, 40 noise-free bumps: the true state held 0.84 and 0.71 with κ = 1 and
  alpha_fast = 0.5, 0.995 and 0.98 with the defaults). With κ = 0.5 injection needs w_fast
  below half of w_slow, a run of bad bumps. The fresh particles are not uniform poses, which the next clock would almost all
  refute, but poses drawn consistent with the latest measurement (sensor resetting, Lenser &
  Veloso 2000): global-prior contact poses that bounce with the commanded angle and read the
  robot's clock at their next bump. When no particle explains a clock at all (w_avg = 0) the
  whole set is drawn that way and both averages restart (`depletions` counts it). The
  defaults (`DEFAULT_ALPHA_SLOW`, `DEFAULT_ALPHA_FAST`) were chosen on the tuning seeds
  (benchmarks/particle_tuning.py); ``alpha_fast == alpha_slow`` turns injection off.
* **Prior.** Global localization: the robot starts at a uniform pose of the free space with a
  uniform heading and drives to its first contact (what a bounce-mode reset does); the particles
  are such drives, kept where their clock equals the clock the robot read after its reset.

The belief is read as mass per decision state (cell × heading bin of a `CellModel` at the bump,
`bounce_gym.cells.bump_states`). Particles are kept as pose arrays between updates (exactly the
contacts the motion returned), with the decision state each had before the last bump
(``previous``, −1 for a fresh particle), so a claim on a state can be followed to the states its
particles reached (`successors`). Any backend with continuous headings is supported
(`supported`); nothing here depends on which one.
"""

from __future__ import annotations

import copy

import numpy as np

from bounce_gym.cells.model import CellModel
from bounce_gym.dynamics.bump_sampler import default_max_ticks
from bounce_gym.dynamics.bump_table import bump_motion
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
#: default rate of the long-term average likelihood w_slow (augmented MCL)
DEFAULT_ALPHA_SLOW = 0.05
#: default rate of the short-term average likelihood w_fast (augmented MCL)
DEFAULT_ALPHA_FAST = 0.3
#: default share of w_slow below which w_fast must fall before particles are injected
DEFAULT_INJECT_BELOW = 0.5
#: prior poses drawn per batch (times the particles wanted) while filling the prior
_PRIOR_BATCH = 4
#: the fewest prior poses drawn in one batch (a few injected particles still get a fair pool)
_PRIOR_MIN = 256
#: batches tried before the prior settles for the nearest clock it found
_PRIOR_TRIES = 50


def supported(dynamics: BounceDynamics) -> bool:
    """Whether the particle belief can move particles with ``dynamics``: continuous headings."""
    return dynamics.backend.bin_width is None


class ParticleBelief:
    """The particle belief of the module docstring.

    Args:
        model: the cell model whose cell numbers are the decision states.
        dynamics: keyword arguments of `BounceDynamics` with the ``world`` (backend, rule, noise,
            radius, step_length, backend_options); the prior's start poses are drawn with it.
        n_particles: particles kept.
        max_clock: the largest clock the robot reads (clocks are capped there).
        tolerance, slack: ticks either side of the clock read that still count, with weight
            ``slack`` (module docstring).
        jitter: standard deviation of the roughening of every heading before a bump
            (radians; None: `DEFAULT_JITTER`).
        alpha_slow, alpha_fast: rates of the long- and short-term average likelihoods of
            augmented MCL, 0 ≤ alpha_slow ≤ alpha_fast ≤ 1 (equal: no injection).
        inject_below: κ, the dead band of the injection (module docstring), in (0, 1].
        max_ticks: the longest drive (None: `bump_sampler.default_max_ticks`); a particle that
            does not bump again within it explains no clock.
        motion: the motion model (None: `bump_motion` of ``model`` and ``dynamics``: the
            tabulated bump map on pymunk's dynamic physics, the simulator elsewhere).

    ``reset(rng, clock)`` or ``reset_at(rng, position, heading)``; ``update(angle, clock)``;
    ``position``, ``heading`` (the particles' poses at their last bump), ``states`` (decision
    state of every particle, −1 for one not at a contact), ``previous``, ``weight``, ``ess``,
    ``likelihood`` (w_avg of the last update), ``injected`` (fresh particles at the last
    update), ``depletions``, ``mass()`` (state → mass), ``max_mass``, ``most_likely``,
    ``successors(state)``, ``entropy``, ``expected_entropy(angles)``.
    """

    def __init__(self, model: CellModel, dynamics: dict, n_particles: int = DEFAULT_PARTICLES,
                 max_clock: int | None = None, tolerance: int = DEFAULT_TOLERANCE,
                 slack: float = DEFAULT_SLACK, jitter: float | None = None,
                 alpha_slow: float = DEFAULT_ALPHA_SLOW, alpha_fast: float = DEFAULT_ALPHA_FAST,
                 inject_below: float = DEFAULT_INJECT_BELOW, max_ticks: int | None = None, motion=None) -> None:
        if isinstance(n_particles, bool) or not isinstance(n_particles, int | np.integer) \
                or n_particles < 1:
            raise ConfigError(f"particles: expected an integer >= 1, got {n_particles!r}")
        if not 0.0 <= float(slack) <= 1.0:
            raise ConfigError(f"slack: expected a number in [0, 1], got {slack!r}")
        if not 0.0 <= float(alpha_slow) <= float(alpha_fast) <= 1.0:
            raise ConfigError(f"alpha_slow, alpha_fast: expected 0 <= alpha_slow <= alpha_fast "
                              f"<= 1, got {alpha_slow!r}, {alpha_fast!r}")
        if not 0.0 < float(inject_below) <= 1.0:
            raise ConfigError(f"inject_below: expected a number in (0, 1], got {inject_below!r}")
        self.model, self.n = model, int(n_particles)
        self.dynamics = dict(dynamics)
        self.motion = bump_motion(model, self.dynamics) if motion is None else motion
        self.jitter = DEFAULT_JITTER if jitter is None else float(jitter)
        self.max_clock = max_clock
        self.max_ticks = default_max_ticks(self.dynamics) if max_ticks is None else int(max_ticks)
        self.tolerance, self.slack = int(tolerance), float(slack)
        self.alpha_slow, self.alpha_fast = float(alpha_slow), float(alpha_fast)
        self.inject_below = float(inject_below)
        if not supported(self._simulator(1)):
            raise ConfigError(f"particle belief: backend {dynamics.get('backend')!r} is not "
                              "supported (it needs continuous headings)")
        self.depletions = 0
        #: the simulator whose uniform start poses the prior draws (`_prior`), made on first use
        self._sampler: BounceDynamics | None = None

    # -- construction -------------------------------------------------------------------------
    def _simulator(self, m: int) -> BounceDynamics:
        params = dict(self.dynamics)
        return BounceDynamics(params.pop("world"), m, robot_collisions="ignore", **params)

    def _read(self, clock: np.ndarray) -> np.ndarray:
        clock = np.asarray(clock, dtype=np.int64)
        return clock if self.max_clock is None else np.minimum(clock, self.max_clock)

    def _bumps(self, angle: float, point: np.ndarray, heading: np.ndarray,
               rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        """Every pose bumps with ``angle`` and drives on: clocks read, next decision states
        (−1: no next bump), points and headings there."""
        out = self.motion.bumps(np.array([float(angle)]), np.zeros(len(heading), dtype=np.int64),
                                point, heading, rng, self.max_ticks)
        return self._read(out.ticks), out.next_state, out.end, out.heading

    def _prior(self, clock: int | None, n: int, angle: float | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``n`` uniform start poses driven to their first contact — and, with an ``angle``,
        bounced once more with it —, kept where the last drive reads ``clock`` (None: any), or,
        if no drawn pose reads it, the nearest clock any does: points, headings, states."""
        kept: list[tuple[np.ndarray, ...]] = []
        best = np.inf  # the least clock gap of the poses kept so far
        batch = max(_PRIOR_BATCH * n, _PRIOR_MIN)
        if self._sampler is None or self._sampler.n_robots != batch:
            self._sampler = self._simulator(batch)  # draws the start poses only, kept
        for _ in range(_PRIOR_TRIES):
            position, start_heading = self._sampler.draw_poses(self.rng)
            z, point, heading, ticks = self.motion.reset_drives(
                position, start_heading, self.rng, self.max_ticks)
            if angle is not None:  # sensor resetting: poses that explain the latest clock
                ticks, z, point, heading = self._bumps(angle, point, heading, self.rng)
            gap = np.zeros(len(z)) if clock is None \
                else np.abs(self._read(ticks) - self._read(clock)).astype(np.float64)
            gap[z < 0] = np.inf
            least = gap.min(initial=np.inf)
            if least < best:  # only the nearest clock is kept: memory stays bounded
                kept, best = [], least
            if least == best and np.isfinite(least):
                keep = gap == least
                kept.append((point[keep], heading[keep], z[keep]))
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
        self.depletions = 0
        self._place(*self._prior(clock, self.n))

    def reset_at(self, rng: np.random.Generator, position: np.ndarray,
                 heading: np.ndarray) -> None:
        """Particles driven to their first contact from the given start poses (n, 2), (n,)."""
        self.rng = rng
        self.depletions = 0
        position = np.asarray(position, dtype=np.float64).reshape(-1, 2)
        self.n = len(position)
        heading = np.asarray(heading, dtype=np.float64).reshape(-1)
        z, point, final, _ = self.motion.reset_drives(position, heading, rng, self.max_ticks)
        self._place(point, final, z)

    def _place(self, position: np.ndarray, heading: np.ndarray, states: np.ndarray) -> None:
        """A fresh set of equally weighted particles; the likelihood averages start over."""
        self.position, self.heading, self.states = position, heading, states
        self.previous = np.full(len(states), -1, dtype=np.int64)
        self.weight = np.full(len(states), 1.0 / len(states))
        self.ess, self.injected, self.likelihood = float(len(states)), 0, 1.0
        self.w_slow = self.w_fast = None

    # -- the filter ---------------------------------------------------------------------------
    def update(self, angle: float, clock: int) -> None:
        """The robot bounced by ``angle`` (radians, commanded) and read ``clock`` at its next
        bump."""
        heading = self.heading
        if self.jitter > 0:  # roughening: every particle's heading, before its bump
            heading = (heading + self.rng.normal(0.0, self.jitter, self.n)) % (2 * np.pi)
        ticks, states, end, final = self._bumps(angle, self.position, heading, self.rng)
        gap = np.abs(ticks - self._read(clock))
        weight = np.where(gap == 0, 1.0, np.where(gap <= self.tolerance, self.slack, 0.0))
        weight[states < 0] = 0.0
        weight *= self.weight
        average = self.likelihood = float(weight.sum())  # w_avg (module docstring)
        if average <= 0:  # depletion: every particle drawn anew from the latest clock
            self.depletions += 1
            self._place(*self._prior(clock, self.n, angle))
            self.ess = 0.0
            return
        self.previous, self.states = self.states, states
        self.position, self.heading = end, final
        self.weight = weight / average
        self.ess = float(1.0 / np.square(self.weight).sum())
        fresh = self._fresh_count(average)
        if fresh > 0 or self.ess < 0.5 * self.n:
            self._resample(self.weight, self.n - fresh)
            if fresh > 0:
                self._inject(*self._prior(clock, fresh, angle))
        self.injected = fresh

    def _fresh_count(self, average: float) -> int:
        """Augmented MCL (Table 8.3): the averages follow w_avg; particles to inject,
        Binomial(n, max(0, 1 − w_fast / (κ w_slow)))."""
        if self.w_slow is None:
            self.w_slow = self.w_fast = average
        self.w_slow += self.alpha_slow * (average - self.w_slow)
        self.w_fast += self.alpha_fast * (average - self.w_fast)
        share = max(0.0, 1.0 - self.w_fast / (self.inject_below * self.w_slow))
        return int(self.rng.binomial(self.n, share)) if share > 0 else 0

    def _inject(self, position: np.ndarray, heading: np.ndarray, states: np.ndarray) -> None:
        """Fresh particles appended to the resampled ones (all weights equal)."""
        self.position = np.concatenate((self.position, position))
        self.heading = np.concatenate((self.heading, heading))
        self.states = np.concatenate((self.states, states))
        self.previous = np.concatenate((self.previous, np.full(len(states), -1)))
        self.weight = np.full(self.n, 1.0 / self.n)

    def _resample(self, weight: np.ndarray, m: int | None = None) -> None:
        """Low-variance resampling (Thrun et al. 2005, Table 4.4) of ``m`` particles (None:
        all), equally weighted."""
        m = self.n if m is None else m
        cumulative = np.cumsum(weight / weight.sum())
        cumulative[-1] = 1.0
        marks = (self.rng.random() + np.arange(m)) / max(m, 1)
        pick = np.searchsorted(cumulative, marks, side="right")
        self.position, self.heading = self.position[pick], self.heading[pick]
        self.states, self.previous = self.states[pick], self.previous[pick]
        self.weight = np.full(m, 1.0 / max(m, 1))

    # -- reading the belief -------------------------------------------------------------------
    def _by_state(self, where: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The decision states holding particles (of those ``where``) and their mass."""
        states = self.states if where is None else self.states[where]
        weight = self.weight if where is None else self.weight[where]
        held = np.bincount(states + 1, minlength=1) > 0
        mass = np.bincount(states + 1, weights=weight, minlength=1)
        return np.flatnonzero(held) - 1, mass[held]

    def mass(self) -> tuple[np.ndarray, np.ndarray]:
        """The decision states holding particles (−1: particles not at a contact) and their
        mass (summing to 1)."""
        return self._by_state()

    def successors(self, state: int) -> tuple[np.ndarray, np.ndarray]:
        """Where the particles that were in ``state`` before the last bump are now: decision
        states and their mass (of the whole belief)."""
        return self._by_state(self.previous == state)

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
        return _entropy(self.mass()[1])

    def expected_entropy(self, angles: np.ndarray) -> np.ndarray:
        """For every angle: the expected entropy (bits) of the belief over decision states
        after the next bump, over the clocks it would read — the conditional entropy
        H(state | clock) = H(state, clock) − H(clock) of the particles simulated from their
        poses (with a copy of the generator, so the belief's own stream is not advanced)."""
        out = np.zeros(len(angles))
        for i, angle in enumerate(np.asarray(angles, dtype=np.float64)):
            ticks, states = self._bumps(angle, self.position, self.heading,
                                        copy.deepcopy(self.rng))[:2]
            joint = ticks * (self.model.n_cells + 1) + states + 1
            out[i] = _entropy(_masses(joint, self.weight)) - _entropy(_masses(ticks, self.weight))
        return out


def _masses(values: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """The weight of every distinct value."""
    _, inverse = np.unique(values, return_inverse=True)
    return np.bincount(inverse.ravel(), weights=weight)


def _entropy(mass: np.ndarray) -> float:
    """Entropy (bits) of the masses (normalised)."""
    p = mass[mass > 0] / mass.sum()
    return float(-(p * np.log2(p)).sum())
