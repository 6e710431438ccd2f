"""Navigation with continuous bounce angles, closed loop from contact and clock.

With Φ = {45°, 90°, 135°} a noise-free robot started at a pose meets the walls only on the
lattice of poses its start and Φ generate, and many goals lie off it; the env's continuous
action (``action_type="continuous"``: any angle of its range, 45°–135° by default) has no such
lattice. `ContinuousNavigationPlanner` chooses each bounce angle from that range:

* at reset it reads the episode's start and goal poses (what the task appends to the
  observation) and predicts the drive of the reset from the start (simulated);
* its belief is the package's particle belief (`bounce_gym.dynamics.particles.ParticleBelief`:
  Monte Carlo localization, Thrun, Burgard & Fox, *Probabilistic Robotics*, 2005, §4.3, with
  augmented-MCL recovery and sensor resetting, §8.3.5), started at the start pose and moved
  through the same motion model (the tabulated bump map on pymunk's dynamic physics) by the
  angle it executed, weighted by the clock it reads: ``draws`` particles with rotation noise,
  one exact pose without (no roughening, no injection). A belief that loses the robot recovers
  from the clocks instead of following a wrong pose for the rest of the episode. Bumps whose
  clock not every particle explained are counted in ``surprises``;
* it decides from the belief's most likely pose (of the particles in the most likely decision
  state, the one nearest their mean), by the search over bump poses with a fine
  grid of angles and the goal shots in the noise-free simulator
  (`baselines.navigation.angle_search`, its poses ranked by `ShotField`): it follows the plan
  found while the belief's most likely pose is the one the plan expects (within
  ``PLAN_DISTANCE`` radii and ``PLAN_HEADING``) and searches again from that pose otherwise
  (in a noisy world: after a rotation error that the clock revealed).
  When a search finds no plan within its budget, the next one starts from the most promising
  pose it reached (where the noise-free world takes the robot along the way there), and so on
  until one finds a plan or ``episode_searches`` fruitless searches in a row are spent; the
  robot follows the chained way. In a noise-free world this replans from the exact pose at every
  bump where needed; in a noisy one it is determinised replanning (the most likely outcome
  taken as certain, replanned on surprise; Yoon, Fern & Givan, FF-Replan, ICAPS 2007).

On an env with discrete actions it is the same planner restricted to Φ: the search tries Φ's
angles only (no grid, no shots) and ``act`` returns the index of the angle chosen (the
navigation family's row "search planner": closed loop from contact and clock where the
papers' roadmap runs open loop).

It reads only its observation (the clock) in `act`, never ``info``. ``predicted_success`` is its
estimate, at its first decision, of the probability of reaching the goal within the episode:
without noise, 1 when the chained searches found a plan (exact: the world is deterministic and
the plan was simulated in it) and 0 when they found none; with noise, the share q of ``draws``
simulated robots (drawn from the belief, each with its own rotation errors) that the chained
plan takes to the goal open loop, turned into the probability that one of the
k = ⌊steps left / plan length⌋ attempts that fit in the episode succeeds, 1 − (1 − q)^k — a model that takes the attempts as
independent and each failed one as costing a whole plan's bumps.
"""

from __future__ import annotations

import math

import numpy as np

from baselines.navigation.angle_search import AngleBudget, AnglePlan, search_angles
from baselines.navigation.motion import continuous_action, executed_angle
from baselines.navigation.reachability import noise_free
from baselines.navigation.sampled import DEFAULT_HORIZON
from baselines.navigation.shots import GoalRegion, ShotField, turn_gap
from baselines.policy import Policy
from bounce_gym.dynamics.bump_sampler import default_max_ticks
from bounce_gym.dynamics.bump_table import bump_motion
from bounce_gym.dynamics.noise import Exact
from bounce_gym.dynamics.particles import ParticleBelief
from bounce_gym.errors import ConfigError

#: the weight of `turn_gap` (world units per radian) beside `ShotField.distance`
TURN_WEIGHT = 1.0
#: how near (robot radii, radians) the belief's most likely pose must be to the pose a plan
#: expects for the plan to be followed on
PLAN_DISTANCE, PLAN_HEADING = 0.25, math.radians(2.0)


class ContinuousNavigationPlanner(Policy):
    """Navigation with continuous bounce angles (module docstring).

    Args:
        seed: seed of its random draws (the search's frontier, the belief's rotation errors).
        horizon: steps to plan for (None: the env's registered episode length).
        grid_deg: step of the grid of angles the search tries from every pose (degrees).
        shots: angles inside every pose's shot interval the search also tries.
        frontier: poses kept per level of the search.
        search_bumps: levels (bumps) of one search.
        search_nodes: poses one search expands at most.
        episode_searches: searches that expanded poses and found no plan, in a row (since the
            last that found one) at most; without a plan, and once they are spent for the rest
            of the episode, it bounces by random angles of its range (it bounds the time an
            unreachable goal costs).
        draws: in a noisy world, the belief's particles and the simulated robots of the
            success estimate.
        field_cell: side of the grid of `ShotField` (world units).
    """

    name = "continuous-angle planner"

    def __init__(self, seed: int = 0, horizon: int | None = None, grid_deg: float = 2.0,
                 shots: int = 3, frontier: int = 300, search_bumps: int = 20,
                 search_nodes: int = 6_000, episode_searches: int = 8, draws: int = 256,
                 field_cell: float = 0.25) -> None:
        if not 0.0 < grid_deg <= 90.0:
            raise ConfigError(f"grid_deg: expected a step in (0, 90] degrees, got {grid_deg!r}")
        self.seed, self.horizon, self.grid_deg = int(seed), horizon, float(grid_deg)
        self.shots, self.frontier = int(shots), int(frontier)
        self.search_bumps, self.search_nodes = int(search_bumps), int(search_nodes)
        self.episode_searches = int(episode_searches)
        self.draws, self.field_cell = int(draws), float(field_cell)
        self.predicted_success: float | None = None

    # -- episode ------------------------------------------------------------------------------
    def reset(self, env) -> None:
        env = getattr(env, "unwrapped", env)
        task, options = env.task, env.options
        if getattr(task, "name", None) != "navigation":
            raise ConfigError("ContinuousNavigationPlanner needs an env with task='navigation'")
        if options.step_mode != "bounce":
            raise ConfigError("ContinuousNavigationPlanner needs step_mode='bounce'")
        if options.bounce_rule != "relative":
            raise ConfigError("ContinuousNavigationPlanner aims its shots under the relative "
                              f"bounce rule, not {options.bounce_rule!r}")
        #: the env's discrete angles Φ (radians), or None for the continuous range
        self.phi = np.asarray(options.angles[0], dtype=np.float64) \
            if options.action_type == "discrete" else None
        self.range = options.angle_range[0] if self.phi is None \
            else (float(self.phi.min()), float(self.phi.max()))
        self.goal = GoalRegion(np.asarray(task.goal[0][0], dtype=np.float64),
                               float(task.goal[1][0]), task.goal_radius, task.heading_tolerance)
        model = env.cell_model()
        self.motion = bump_motion(model, options.robot_dynamics)
        self.exact_motion = bump_motion(model, noise_free(options.robot_dynamics))
        self.max_ticks = default_max_ticks(options.robot_dynamics)
        self.deterministic = isinstance(options.noise, Exact)
        self.radius = float(options.robot_radius)
        self.field = ShotField(options.world, options.robot_radius, self.goal, self.field_cell)
        lo, hi = self.range
        if self.phi is None:
            grid = np.linspace(lo, hi, max(2, round(math.degrees(hi - lo) / self.grid_deg) + 1))
            self.budget = AngleBudget(grid, self.shots, self.frontier, self.search_bumps,
                                      self.search_nodes)
        else:  # only Φ's angles can be executed: no grid, no shots between them
            self.budget = AngleBudget(self.phi, 0, self.frontier, self.search_bumps,
                                      self.search_nodes)
        spec_steps = getattr(getattr(env, "spec", None), "max_episode_steps", None)
        self.steps_total = int(self.horizon or spec_steps or DEFAULT_HORIZON)
        self.rng = np.random.default_rng(self.seed)
        n = 1 if self.deterministic else self.draws
        self.belief = ParticleBelief(
            model, options.robot_dynamics, n, max_clock=options.max_clock,
            jitter=0.0 if self.deterministic else None, max_ticks=self.max_ticks,
            motion=self.motion,
            **({"alpha_slow": 0.0, "alpha_fast": 0.0} if self.deterministic else {}))
        self.belief.reset_at(self.rng, np.repeat(np.asarray(task.start[0][0], dtype=np.float64)
                                                 .reshape(1, 2), n, axis=0),
                             np.full(n, float(task.start[1][0])))
        self._angle: float | None = None  # the last angle executed
        self._clock_index = 1 if env.core.observes_contact else 0
        self._max_clock = options.max_clock
        self.plan: AnglePlan | None = None
        self._k = 0
        self.predicted_success = None
        self.surprises = self.searches = self.failures = self.steps = 0

    def _clock(self, observation) -> int:
        return int(round(float(np.asarray(observation).reshape(-1)[self._clock_index])
                         * self._max_clock))

    # -- belief -------------------------------------------------------------------------------
    def _pose(self) -> tuple[np.ndarray, float]:
        """The belief's most likely pose: of the particles in its most likely decision state,
        the one nearest their weighted mean position."""
        belief = self.belief
        mine = np.flatnonzero(belief.states == belief.most_likely)
        if len(mine) == 0:
            mine = np.arange(len(belief.weight))
        weight = belief.weight[mine]
        mean = weight @ belief.position[mine] / weight.sum()
        best = mine[np.argmin(np.hypot(*(belief.position[mine] - mean).T))]
        return belief.position[best], float(belief.heading[best])

    def _hits(self, out) -> np.ndarray:
        g = self.goal
        return out.goal_hits(g.point, g.heading, g.radius, g.tolerance)

    # -- decisions ----------------------------------------------------------------------------
    def _score(self, point: np.ndarray, heading: np.ndarray) -> np.ndarray:
        return self.field.distance(point) + TURN_WEIGHT * turn_gap(heading, self.goal,
                                                                   self.range)

    def _on_plan(self, point: np.ndarray, heading: float) -> bool:
        plan, k = self.plan, self._k
        if plan is None or k >= len(plan.angles):
            return False
        turn = abs(math.remainder(plan.headings[k] - heading, 2 * math.pi))
        return (math.dist(plan.points[k], point) <= PLAN_DISTANCE * self.radius
                and turn <= PLAN_HEADING)

    def _decide(self) -> float:
        """The next angle: the plan's, searched again from the most likely pose when that is
        not the pose the plan expects."""
        point, heading = self._pose()
        if not self._on_plan(point, heading):
            self.plan, self._k = None, 0
            if self.failures < self.episode_searches:
                self.plan = self._search(point, heading)
        if self.predicted_success is None:
            self.predicted_success = self._predicted()
        if self.plan is None or self._k >= len(self.plan.angles):  # no way: bounce at random
            return float(self.rng.uniform(*self.range) if self.phi is None
                         else self.rng.choice(self.phi))
        angle = float(self.plan.angles[self._k])
        self._k += 1
        return angle

    def _search(self, point: np.ndarray, heading: float) -> AnglePlan:
        """A plan from the bump pose: the search's, and while it finds none (and fruitless
        searches and steps are left) the way to its most promising pose followed by a search
        from there, which the noise-free world makes the pose the robot will be at."""
        left = self.steps_total - self.steps
        plan = self._search_once(point, heading, left)
        while (not plan.found and 0 < len(plan.angles) < left
               and self.failures < self.episode_searches):
            way = self._search_once(plan.end_point, plan.end_heading, left - len(plan.angles))
            if len(way.angles) == 0:
                break
            plan = plan.then(way)
        return plan

    def _search_once(self, point: np.ndarray, heading: float, bumps: int) -> AnglePlan:
        plan = search_angles(self.exact_motion, point, heading, self.goal,
                             self.range if self.phi is None else None, self.budget, bumps,
                             self._score, self.rng, self.max_ticks)
        self.searches += 1
        self.failures = 0 if plan.found else self.failures + int(len(plan.angles) > 0)
        return plan

    def _predicted(self) -> float:
        """The success estimate at the first decision (module docstring)."""
        plan = self.plan
        if not plan.found:
            return 0.0
        if self.deterministic:
            return 1.0
        belief = self.belief
        pick = self.rng.choice(len(belief.weight), self.draws, p=belief.weight)
        point, heading = belief.position[pick], belief.heading[pick]
        done = np.zeros(self.draws, dtype=bool)
        for angle in plan.angles:
            out = self.motion.bumps(np.full(len(point), angle), np.arange(len(point)), point,
                                    heading, self.rng, self.max_ticks)
            done |= self._hits(out)
            point, heading = out.end, out.heading
        q = float(done.mean())
        attempts = max(1, (self.steps_total - self.steps) // len(plan.angles))
        return 1.0 - (1.0 - q) ** attempts

    def act(self, observation, info):
        del info  # the robot's own observation only
        if self._angle is not None:  # the reset drive's clock tells nothing: no rotation
            self.belief.update(self._angle, self._clock(observation))
            self.surprises += int(self.belief.likelihood < 1.0)
        angle = self._decide()
        self.steps += 1
        if self.phi is not None:
            index = int(np.argmin(np.abs(self.phi - angle)))
            self._angle = float(self.phi[index])
            return index
        action = continuous_action(np.array([angle]), self.range)
        self._angle = float(executed_angle(action, self.range)[0])
        return action
