"""`BounceDynamics`: m bouncing robots in a world — bounce rule, noise and a motion backend.

The tick (the papers' clock unit, thesis Eq. 2.4; bumps rotate in place, a choice where the papers
are open: docs/choices/cell_model.md, "Bumps rotate in place and take one tick"):
every robot does one of two things per tick,

* a robot that is **blocked** (touching a wall or robot it faces) spends the tick rotating by its
  bounce rule with the angle it was given — a *bump tick*: its bump count rises and its clock
  resets to 0;
* every other robot **drives** ``step_length`` (less if it touches something first and stops) —
  its clock rises by 1.

A rotation that still faces the boundary leaves the robot blocked, so the next tick is another
bump: corners give several bumps in a row, as in the papers' observation strings. Bounce-mode
stepping (`bounce`) is tick stepping that only stops where some robot needs a new angle.

On a backend whose rotations take time (``physics="dynamic"``, `MotionBackend.turns_take_time`)
the bump tick *starts* the rotation, which the backend executes at a finite turn rate over as many
ticks as it needs (the clock counts them), and a turn command lasts until the commanded turns are
done; see `bounce_gym.dynamics.backends.pymunk_dynamic`.
"""

from __future__ import annotations

import math

import numpy as np

from bounce_gym.dynamics.backends.base import MotionBackend
from bounce_gym.dynamics.noise import Exact, NoiseModel, make_noise
from bounce_gym.dynamics.platform import physics_params
from bounce_gym.dynamics.rules import TWO_PI, check_parameters, get_rule, wrap
from bounce_gym.dynamics.state import RobotState
from bounce_gym.errors import ConfigError
from bounce_gym.worlds import World

BACKEND_NAMES = ("kinematic", "pymunk", "cell")
#: The motion models: ``ideal`` (the papers' exact idealisation: unit-speed straight drives,
#: instant rotations) on every backend; ``dynamic`` (rigid bodies, motors, a bumper; the default
#: of the pymunk backend) on pymunk only.
PHYSICS = ("ideal", "dynamic")


def make_backend(name: str, world: World, n_robots: int = 1, radius: float = 0.0,
                 step_length: float = 1.0, robot_collisions: str = "ignore",
                 **options: object) -> MotionBackend:
    """Build a motion backend by name (``kinematic``, ``pymunk`` or ``cell``); imports it on first
    use. ``options`` go to the backend: ``physics`` (`PHYSICS`; pymunk's default is
    ``"dynamic"``, the others have only ``"ideal"``) and, for ``"dynamic"``, ``physics_params``
    (`bounce_gym.dynamics.platform.physics_params`); the cell backend takes ``n_bins``,
    ``corner_rule`` and ``min_sep_cells``."""
    physics = options.pop("physics", None)
    params = options.pop("physics_params", None)
    if physics is not None and physics not in PHYSICS:
        raise ConfigError(f"physics: expected one of {list(PHYSICS)}, got {physics!r}")
    if name == "pymunk" and physics in (None, "dynamic"):
        from bounce_gym.dynamics.backends.pymunk_dynamic import DynamicBackend
        if options:
            raise ConfigError(f"backend_options: physics 'dynamic' takes only physics_params, "
                              f"got {sorted(options)}")
        return DynamicBackend(world, n_robots, radius, step_length, robot_collisions,
                              physics_params(params))
    if physics == "dynamic":
        raise ConfigError(f"physics: backend {name!r} simulates only 'ideal' motion; "
                          "physics='dynamic' needs backend='pymunk'")
    if params is not None:
        raise ConfigError("physics_params: only physics='dynamic' (backend 'pymunk') takes "
                          "physical parameters")
    if name == "kinematic":
        from bounce_gym.dynamics.backends.kinematic import KinematicBackend as Backend
    elif name == "pymunk":
        from bounce_gym.dynamics.backends.pymunk import PymunkBackend as Backend
    elif name == "cell":
        from bounce_gym.dynamics.backends.cell import CellBackend as Backend
    else:
        raise ConfigError(f"backend: unknown backend {name!r}; allowed are {list(BACKEND_NAMES)}")
    if options and name != "cell":
        raise ConfigError(f"backend_options: backend {name!r} takes none, got {sorted(options)}")
    return Backend(world, n_robots, radius, step_length, robot_collisions, **options)


class BounceDynamics:
    """m robots with contact sensors and clocks, moving by a bounce rule.

    Args:
        world: the workspace.
        n_robots: number of robots.
        backend: ``"kinematic"`` (exact, event-driven), ``"pymunk"`` (physics engine) or
            ``"cell"``.
        rule: bounce rule name, see `bounce_gym.dynamics.rules.RULES`.
        noise: actuation noise (`bounce_gym.dynamics.noise.make_noise` accepts the forms).
        radius: robot disk radius (0 = point robot).
        step_length: distance per tick.
        robot_collisions: ``"bounce"`` or ``"ignore"``.
        backend_options: extra arguments of the backend (``cell``: ``n_bins``,
            ``corner_rule``, ``min_sep_cells``).
        physics: ``"ideal"`` or ``"dynamic"`` (`PHYSICS`); None: ``"dynamic"`` on pymunk,
            ``"ideal"`` elsewhere.
        physics_params: with ``"dynamic"``, the physical parameters
            (`bounce_gym.dynamics.platform.physics_params`: a dict or a `PhysicsParams`).

    Randomness comes only from the generator passed to `reset`.
    """

    def __init__(
        self,
        world: World,
        n_robots: int = 1,
        *,
        backend: str = "kinematic",
        rule: str = "relative",
        noise: object = None,
        radius: float = 0.0,
        step_length: float = 1.0,
        robot_collisions: str = "ignore",
        backend_options: dict | None = None,
        physics: str | None = None,
        physics_params: object = None,
    ) -> None:
        self.rule_name = rule
        self.rule = get_rule(rule)
        self.noise: NoiseModel = make_noise(noise)
        options = dict(backend_options or {})
        if physics is not None:
            options["physics"] = physics
        if physics_params is not None:
            options["physics_params"] = physics_params
        self.backend = make_backend(backend, world, n_robots, radius, step_length, robot_collisions,
                                    **options)
        #: scalar fast path for a lone robot on a backend that can drive robots independently
        self._scalar_path = n_robots == 1 and self.backend.drives_independently
        self._lone = np.zeros(1, dtype=np.int64)
        #: Alam's rule on continuous headings without noise: one robot's bump in plain floats
        self._plain_relative = (rule == "relative" and isinstance(self.noise, Exact)
                                and self.backend.bin_width is None)
        #: rotations take time: the backend executes them (bump ticks start them)
        self._timed = self.backend.turns_take_time
        self.rng: np.random.Generator | None = None
        self.state: RobotState | None = None

    @property
    def world(self) -> World:
        return self.backend.world

    @property
    def n_robots(self) -> int:
        return self.backend.n_robots

    def reset(
        self,
        rng: np.random.Generator,
        position: np.ndarray | None = None,
        heading: np.ndarray | None = None,
    ) -> RobotState:
        """Place the robots (uniformly at random where not given) and return the state."""
        position, heading = self.draw_poses(rng, position, heading)
        self.rng = rng
        self.state = RobotState.at(position, heading)
        self.backend.reset(self.state)
        return self.state

    def draw_poses(
        self,
        rng: np.random.Generator,
        position: np.ndarray | None = None,
        heading: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The (m, 2) positions and (m,) headings `reset` places: those given (checked), the
        others drawn from ``rng`` as `reset` draws them."""
        if not isinstance(rng, np.random.Generator):
            raise ConfigError(f"rng: expected a numpy Generator, got {type(rng).__name__}")
        m = self.n_robots
        if position is None:
            position = self.backend.random_positions(rng)
        position = np.asarray(position, dtype=np.float64)
        if position.shape != (m, 2) or not np.all(np.isfinite(position)):
            raise ConfigError(
                f"start position: expected {m} finite (x, y) pairs, got shape {position.shape}"
            )
        if heading is None:
            heading = rng.uniform(0.0, 2 * np.pi, m)
        heading = np.asarray(heading, dtype=np.float64).reshape(-1)
        if heading.shape != (m,) or not np.all(np.isfinite(heading)):
            raise ConfigError(f"start heading: expected {m} finite angles, got {heading.tolist()}")
        return position, heading

    # -- stepping ---------------------------------------------------------------------------
    def tick(self, params: np.ndarray) -> np.ndarray:
        """Advance one tick. ``params`` (m,) are the bounce angles used by robots that bump.

        Returns the (m,) mask of robots whose tick was a bump.
        """
        state = self._require_state()
        params = self.parameters(params)
        bumping = state.blocked.copy()
        if self._timed:  # the rotations start with the tick and take their time
            self._rotate(np.flatnonzero(bumping), params)
            self.backend.drive(state, 1, until_first_block=False)
            return bumping
        self.backend.drive(state, 1, until_first_block=False)
        self._rotate(np.flatnonzero(bumping), params)
        return bumping

    def bounce(self, params: np.ndarray) -> int:
        """Bounce-mode step: one tick (blocked robots rotate), then drive until a robot is blocked.

        Stops at the end of the first tick in which some robot becomes blocked; immediately after
        the first tick if a rotated robot still faces the boundary. Returns the ticks elapsed.
        """
        state = self._require_state()
        params = self.parameters(params)
        if self._timed:  # the bump tick and the drive in one window: turns take ticks
            self._rotate(np.flatnonzero(state.blocked), params)
            return self.backend.drive(state, np.inf, until_first_block=True)
        if self.n_robots == 1 and state.blocked[0]:
            # one robot: the rotation tick (in which a blocked robot does not drive), then the
            # drive to the next contact — on the scalar path where the backend has one
            state.ticks += 1
            self._rotate(self._lone, params)
            if self._scalar_path:
                return 1 + int(self.backend.drive_each(state)[0])
            return 1 + self.backend.drive(state, np.inf, until_first_block=True)
        self.tick(params)
        return 1 + self.backend.drive(state, np.inf, until_first_block=True)

    def turn(self, turns: np.ndarray) -> np.ndarray:
        """A *command tick*: a clock-timed turn (Algorithm 1's neighbour jump, Alam & Bobadilla
        2020, §4.1; docs/choices/multirobot.md, "A neighbour jump is a timed turn").

        Robots with a finite entry in ``turns`` (m,) rotate in place by it (radians,
        counter-clockwise positive; the noise model perturbs the executed heading as for a
        bounce); every other robot waits in place. The tick is not a bump: bump counts are
        unchanged and every clock advances by one tick. A robot that turns to face what it
        touches becomes blocked. Returns the (m,) mask of robots that turned.

        Where rotations take time the command lasts until the turns are done, in whole ticks
        (`MotionBackend.command_turns`), and every clock advances by one per tick.
        """
        state = self._require_state()
        try:
            turns = np.asarray(turns, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            raise ConfigError(f"turns: expected numbers, got {turns!r}") from None
        if turns.shape != (self.n_robots,):
            raise ConfigError(f"turns: expected {self.n_robots} values (NaN = no turn), got "
                              f"{turns.shape[0]}")
        turning = ~np.isnan(turns)
        if np.any(np.isinf(turns)):
            raise ConfigError(f"turns: expected finite angles or NaN, got {turns.tolist()}")
        idx = np.flatnonzero(turning)
        if self._timed:
            rotation = turns[idx]
            if not isinstance(self.noise, Exact):
                rotation = rotation + self.noise.sample(len(idx), self.rng)
            self.backend.command_turns(state, idx, rotation)
            return turning
        heading = state.heading[idx] + turns[idx]
        width = self.backend.bin_width
        if width is not None:
            steps = turns[idx] / width
            if np.any(np.abs(steps - np.rint(steps)) > 1e-6):
                raise ConfigError(f"turns: {np.degrees(turns[idx]).tolist()} degrees are not "
                                  f"whole {math.degrees(width):g}° bins of the cell backend")
            heading = heading + width * self.noise.sample_bins(len(idx), self.rng, width)
        elif not isinstance(self.noise, Exact):
            heading = heading + self.noise.sample(len(idx), self.rng)
        state.heading[idx] = wrap(heading)
        state.clock += 1
        state.ticks += 1
        self.backend.update_contacts(state, np.arange(self.n_robots))
        return turning

    def drive_to_contact(self) -> int:
        """Drive until some robot is blocked (used after reset in bounce mode)."""
        return self.backend.drive(self._require_state(), np.inf, until_first_block=True)

    def bounce_each(self, params: np.ndarray) -> np.ndarray:
        """Every blocked robot rotates, then every robot drives to its *own* next contact.

        For independent robots (``robot_collisions='ignore'``, kinematic backend): m parallel
        single-robot episodes in one vectorised call. Per-robot clocks stay exact; the shared
        ``state.ticks`` is not advanced because the robots are no longer in step.
        Returns the ticks each robot drove.
        """
        if not self.backend.drives_independently:
            raise ConfigError(f"backend {self.backend.name!r} does not drive robots independently")
        state = self._require_state()
        self._rotate(np.flatnonzero(state.blocked), self.parameters(params))
        return self.backend.drive_each(state)

    def rotate(self, robots: np.ndarray, params: np.ndarray) -> None:
        """The bump ticks of ``robots`` alone: each rotates in place by the rule (and the
        noise) with its entry of ``params`` (m,), as in `tick`, and their contacts are updated;
        nobody drives and the global clock stays (`tick` is this plus one tick of driving the
        others; the batched env drives each robot on by itself)."""
        self._require_state()
        self._rotate(np.asarray(robots, dtype=np.int64), self.parameters(params))

    def _rotate(self, idx: np.ndarray, params: np.ndarray) -> None:
        """Bump ticks of robots ``idx``: each rotates by the rule (and the noise) in place."""
        if len(idx) == 0:
            return
        state = self.state
        if self._timed:
            self._begin_turns(idx, params)
            return
        if self._plain_relative and len(idx) == 1:
            # wrap(θ + φ) in plain floats — bit for bit the rule's numpy result, 4 µs cheaper
            i = int(idx[0])
            heading = (float(state.heading[i]) + float(params[i])) % TWO_PI
            state.heading[i] = 0.0 if heading >= TWO_PI else heading
            state.bumps[i] += 1
            state.clock[i] = 0
        else:
            heading = self.rule(state.heading[idx], state.contact_normal[idx], params[idx])
            width = self.backend.bin_width
            if width is not None:  # discrete headings: whole-bin errors, as in the GCM
                heading = wrap(heading + width * self.noise.sample_bins(len(idx), self.rng, width))
            elif not isinstance(self.noise, Exact):
                heading = wrap(heading + self.noise.sample(len(idx), self.rng))
            state.heading[idx] = heading
            state.bumps[idx] += 1
            state.clock[idx] = 0
        self.backend.update_contacts(state, idx)

    def _begin_turns(self, idx: np.ndarray, params: np.ndarray) -> None:
        """Bump ticks on a backend whose rotations take time: the rule and the noise give the
        rotation to execute — counter-clockwise by φ for Alam's relative rule, as the papers'
        robots turn; the shorter way to the rule's heading for the rules set by the boundary
        normal — and the backend starts it."""
        state = self.state
        if self._plain_relative and len(idx) == 1:  # a lone robot's bump in plain floats
            i = int(idx[0])
            state.bumps[i] += 1
            state.clock[i] = 0
            self.backend.begin_turns(state, idx, [float(params[i]) % TWO_PI])
            return
        if self.rule_name == "relative":
            rotation = np.mod(params[idx], TWO_PI)
        else:
            new = self.rule(state.heading[idx], state.contact_normal[idx], params[idx])
            rotation = np.mod(new - state.heading[idx] + np.pi, TWO_PI) - np.pi
        if not isinstance(self.noise, Exact):
            rotation = rotation + self.noise.sample(len(idx), self.rng)
        state.bumps[idx] += 1
        state.clock[idx] = 0
        self.backend.begin_turns(state, idx, rotation)

    def parameters(self, params: object) -> np.ndarray:
        """Bounce parameters as an (m,) float array; a scalar applies to every robot."""
        try:
            values = np.asarray(params, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            raise ConfigError(f"bounce parameters: expected numbers, got {params!r}") from None
        if len(values) == 1:
            lo = hi = float(values[0])
            if self.n_robots > 1:
                values = np.full(self.n_robots, lo)
        elif len(values) == self.n_robots:
            lo, hi = float(values.min()), float(values.max())
        else:
            raise ConfigError(
                f"bounce parameters: expected {self.n_robots} angles (one per robot), "
                f"got {len(values)}"
            )
        # NaN fails every comparison below, so it is rejected too
        if self.rule_name == "relative" and lo == hi:
            valid = 1e-9 < lo % TWO_PI < TWO_PI - 1e-9
        elif self.rule_name == "relative":
            turn = np.mod(values, TWO_PI)
            valid = bool(((turn > 1e-9) & (turn < TWO_PI - 1e-9)).all())
        elif self.rule_name == "specular":
            valid = math.isfinite(lo) and math.isfinite(hi)  # θ is unused but must be a number
        else:
            valid = lo > 0.0 and hi < math.pi
        if not valid:
            check_parameters(self.rule_name, values, field="bounce parameters")  # raises
        width = self.backend.bin_width
        if width is not None:
            steps = values / width
            if np.any(np.abs(steps - np.rint(steps)) > 1e-6):
                raise ConfigError(f"bounce parameters: {np.degrees(values).tolist()} degrees are "
                                  f"not whole {math.degrees(width):g}° bins of the cell backend")
        return values

    def _require_state(self) -> RobotState:
        if self.state is None:
            raise RuntimeError("call reset() before stepping the dynamics")
        return self.state
