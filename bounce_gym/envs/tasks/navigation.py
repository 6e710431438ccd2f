"""Navigation: reach a goal pose."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from bounce_gym.cells.geodesic import GridGeodesic
from bounce_gym.cells.outcomes import GOAL_SLACK
from bounce_gym.envs.tasks.base import StepEvents, Task, _normalised, pose_option, tick_length_at
from bounce_gym.errors import ConfigError
from bounce_gym.validate import flag, number

#: the ``reward`` option of `NavigationTask`
REWARDS = ("progress", "sparse", "plan_cost")
#: the default discount of the ``progress`` shaping: none, as the episode return is reported
DEFAULT_GAMMA = 1.0
#: the most floats `NavigationTask.goal_potentials` keeps (2^24: 128 MiB)
POTENTIAL_CACHE_FLOATS = 1 << 24


class NavigationTask(Task):
    """Reach a goal pose: within ``goal_radius`` of the goal point, heading within tolerance.

    Args:
        start: ``{"position": [x, y], "heading": radians}``; None draws one per episode
            (uniformly in the free space, or — on the cell backend — a random cell centre and
            bin heading).
        goal: as ``start``.
            Both can also be given per episode through ``reset(options={"start": ..., "goal": ...})``.
        goal_radius: size of the goal region (default: one step length), from 1e-4 times the
            world's diameter to the diameter.
        heading_tolerance_deg: heading tolerance at the goal (default 22.5°, half a 45° bin).
        reward: ``"progress"`` (default), ``"sparse"`` or ``"plan_cost"`` — see below.
        goal_bonus: reward on arrival (default 1 for ``sparse`` and ``progress``; 100 for
            ``plan_cost``, the value that reward always had).
        tick_cost: ``sparse`` and ``progress`` only: cost per tick until the goal (default 0).
        gamma: ``progress`` only: the discount γ of the shaping term, in (0, 1] (default 1:
            the shaping is exact for the undiscounted episode return, which evaluation reports;
            an agent's own discount makes it exact for that agent's discounted return instead).
        w1: the plan-cost weight per tick of Alam, Bobadilla & Shell (2017), Sec. IV-A, Alg. 1
            (thesis §3.4.1, Alg. 3.1); default 1, as in the papers (Sec. V-A).
        w2: the weight instead of w1 for a bump that changes the bounce angle; the first angle
            is free. Default 100, as in the papers (Sec. V-A).
        observe_task: append the start and goal poses (normalised) to the observation — the
            planners of the papers know both, so a fair RL agent needs them too.

    Rewards (per env step; "ticks" are the ticks of the step up to the goal):

    * ``"sparse"``: ``goal_bonus`` on arrival, minus ``tick_cost`` per tick.
    * ``"progress"``: the sparse reward plus potential-based shaping
      F = γ·Φ(s') − Φ(s) (Ng, Harada & Russell 1999, Theorem 1), which leaves the optimal
      policies of the sparse reward unchanged: a return discounted by γ differs from the sparse
      one by γ^T·Φ(s_T) − Φ(s_0), where Φ(s_0) does not depend on the policy and Φ(s_T) = 0 at
      the goal; with γ = 1 the undiscounted returns differ by exactly Φ(s_T) − Φ(s_0), so on
      the same start an episode that reaches the goal (1 − Φ(s_0)) always outscores one that
      does not (at most −Φ(s_0)).
      Φ(s) = −d(s) / d_max ∈ [−1, 0], where d is the geodesic distance from the robot's
      position to the goal point through the free cells of the env's grid (cell size =
      ``step_length``, king moves under the env's ``corner_rule``, `GridGeodesic`) and d_max the
      largest such distance of the episode's goal; cells the goal cannot be reached from have
      Φ = −1, and Φ = 0 once the goal is reached (the terminal state). On the cell backend
      that grid is the one the robot moves on; on the continuous backends a point maps to the
      cell that holds it (or the nearest free cell), so Φ is the cell-level approximation of the
      continuous geodesic distance.
    * ``"plan_cost"``: minus the papers' plan cost — −w1 per tick and −(w2 − w1) more per change
      of bounce angle — plus ``goal_bonus`` on arrival. Not the default: its optimum depends on
      the bonus and on the horizon rather than on the goal (docs/choices/learning_tasks.md, "The navigation
      reward").

    Whatever the reward, ``info["plan_cost"]`` is the papers' cost of the trajectory so far,
    w1 per tick since the episode began (the drive of a bounce-mode reset included) plus
    (w2 − w1) per change of bounce angle, up to the goal: on arrival it equals the roadmap
    weight of the path taken, so the planner's is its plan's weight.

    The goal counts as reached when the robot's straight path of a step passes through the goal
    region while its heading is within tolerance; only the ticks up to that point are charged.
    """

    name = "navigation"
    option_keys = frozenset({"start", "goal"})

    def __init__(self, start: Mapping | None = None, goal: Mapping | None = None,
                 goal_radius: float | None = None, heading_tolerance_deg: float = 22.5,
                 reward: str = "progress", goal_bonus: float | None = None,
                 tick_cost: float = 0.0, gamma: float | None = None,
                 w1: float = 1.0, w2: float = 100.0, observe_task: bool = True) -> None:
        self._fixed = {"start": start, "goal": goal}
        for key in ("start", "goal"):
            if self._fixed[key] is not None:
                pose_option(self._fixed, key, 1)
        heading_tolerance_deg = number("heading_tolerance_deg", heading_tolerance_deg,
                                       minimum=0.0, strict=True)
        if heading_tolerance_deg > 180:
            raise ConfigError(f"heading_tolerance_deg: expected (0, 180], got {heading_tolerance_deg}")
        if goal_radius is not None:
            goal_radius = number("goal_radius", goal_radius, minimum=0.0, strict=True)
        w1, w2 = number("w1", w1), number("w2", w2)
        if not (w1 >= 0 and w2 >= w1):
            raise ConfigError(f"w1, w2: expected 0 <= w1 <= w2, got w1={w1}, w2={w2}")
        if not isinstance(reward, str) or reward not in REWARDS:
            raise ConfigError(f"reward: expected one of {list(REWARDS)}, got {reward!r}")
        self.reward = reward
        self.goal_radius_arg = goal_radius
        self.heading_tolerance = math.radians(heading_tolerance_deg)
        self.w1, self.w2 = w1, w2
        self.goal_bonus = (number("goal_bonus", goal_bonus) if goal_bonus is not None
                           else 100.0 if reward == "plan_cost" else 1.0)
        self.tick_cost = number("tick_cost", tick_cost, minimum=0.0)
        if reward == "plan_cost" and self.tick_cost:
            raise ConfigError("tick_cost: the 'plan_cost' reward charges w1 per tick; tick_cost "
                              "is for the 'sparse' and 'progress' rewards")
        if gamma is not None and reward != "progress":
            raise ConfigError(f"gamma: only the 'progress' reward discounts (its shaping); got "
                              f"gamma={gamma!r} with reward={reward!r}")
        self.gamma = number("gamma", DEFAULT_GAMMA if gamma is None else gamma,
                            minimum=0.0, strict=True)
        if self.gamma > 1.0:
            raise ConfigError(f"gamma: expected a number in (0, 1], got {self.gamma!r}")
        self.observe_task = flag("observe_task", observe_task)

    def configure(self, core) -> None:
        super().configure(core)
        options = self.options
        if options.n_robots != 1:
            raise ConfigError("task 'navigation' is a single-robot task (n_robots must be 1)")
        self.goal_radius = float(self.goal_radius_arg or options.step_length)
        if self.goal_radius_arg is not None:
            options.world.check_length("task_kwargs.goal_radius", self.goal_radius)
        # on the cell backend, random starts and goals are cells (centre and bin heading): the
        # papers' x_I and x_G
        self._cells = core.cell_model() if options.backend == "cell" else None
        for key, pose in self._fixed.items():
            if pose is not None:
                position = pose_option(self._fixed, key, 1)[0]
                if not options.world.contains(position, options.robot_radius).all():
                    raise ConfigError(f"task_kwargs.{key}: position {position[0].tolist()} is "
                                      "not in the free space")
        #: the grid Φ is measured on (``progress`` only)
        self.geodesic = None
        self._potentials_by_goal: dict[int, np.ndarray] = {}  # `goal_potentials`' cache
        if self.reward == "progress":
            options.world.check_grid("step_length (the grid of reward 'progress')",
                                     options.step_length)
            free = options.world.occupancy(options.step_length, options.robot_radius)
            if not free.any():
                raise ConfigError("reward: 'progress' measures distances between cells of size "
                                  "step_length, and no such cell is free for this robot; use "
                                  "'sparse' or a smaller step_length")
            self.geodesic = GridGeodesic(free, options.step_length, options.world.bounds[:2],
                                         options.corner_rule)

    @property
    def observation_labels(self) -> tuple[str, ...]:
        """The start pose, then the goal pose: x and y scaled to [-1, 1] over the world's
        bounds, cos θ, sin θ (`pose_features`)."""
        if not self.observe_task:
            return ()
        return tuple(f"{pose} {part}" for pose in ("start", "goal")
                     for part in ("x", "y", "cos θ", "sin θ"))

    def start_poses(self, rng, options):
        chosen = {k: pose_option(options, k, 1) or pose_option(self._fixed, k, 1)
                  for k in ("start", "goal")}
        world, radius = self.options.world, self.options.robot_radius
        for key in ("start", "goal"):
            if chosen[key] is None and self._cells is not None:
                p, k = self.random_cell(rng)
                chosen[key] = (self._cells.centres[[p]], np.array([k * self._cells.bin_width]))
            elif chosen[key] is None:
                chosen[key] = (world.sample_free(rng, 1, radius), rng.uniform(0, 2 * np.pi, 1))
            elif not world.contains(chosen[key][0], radius).all():
                raise ConfigError(f"{key} position {chosen[key][0][0].tolist()} is not in the "
                                  "free space")
        self.start, self.goal = chosen["start"], chosen["goal"]
        return self.start

    @property
    def random_cells(self) -> bool:
        """Whether, without reset options, every episode's start and goal are random cells of
        the cell backend (`random_cell`, the start's draw first)."""
        return self._cells is not None and all(pose is None for pose in self._fixed.values())

    def random_cell(self, rng: np.random.Generator) -> tuple[np.int64, np.int64]:
        """A random start or goal cell on the cell backend, (position index, bin) as NumPy
        integers, drawn from ``rng`` as `start_poses` draws it."""
        # ``integers(0, n, None, np.int64)`` is ``integers(n)`` spelled out: the same draws,
        # without the keyword and default arguments' handling (a batch of N envs calls it
        # four times per reset)
        cells, draw = self._cells, rng.integers
        return draw(0, cells.n_positions, None, np.int64), draw(0, cells.n_bins, None, np.int64)

    def reset(self, state, rng, options):
        self.reached = False
        self.plan_cost = self.w1 * int(state.ticks)  # the drive of a bounce-mode reset
        if self.geodesic is not None:
            #: Φ of every node of the grid for this episode's goal
            self.potentials = self.goal_potentials(int(self.geodesic.node_of(self.goal[0][0])[0]))
            #: Φ(s) of the robot's current state
            self.potential_now = self.potential(state.position[0])
        return self._info(state)

    def goal_potentials(self, goal_node: int) -> np.ndarray:
        """Φ of every node of the grid (a read-only array) for a goal in node ``goal_node`` of
        `geodesic` (``progress`` reward). Computed once per goal node and kept: the last
        `POTENTIAL_CACHE_FLOATS` // n_nodes goal nodes seen (at most n_nodes)."""
        cache = self._potentials_by_goal
        if goal_node in cache:
            return cache[goal_node]
        distance = self.geodesic.distances_to_node(goal_node)
        finite = np.isfinite(distance)
        scale = float(distance[finite].max())
        potentials = np.full(len(distance), -1.0)
        potentials[finite] = -distance[finite] / scale if scale > 0 else 0.0
        potentials.flags.writeable = False
        n_nodes = self.geodesic.n_nodes
        if len(cache) >= max(1, min(n_nodes, POTENTIAL_CACHE_FLOATS // n_nodes)):
            del cache[next(iter(cache))]  # the goal first seen longest ago
        cache[goal_node] = potentials
        return potentials

    def potential(self, position: np.ndarray) -> float:
        """Φ of a robot at ``position`` that has not reached the goal, for this episode's goal
        (``progress`` reward; see the class docstring)."""
        if self.geodesic is None:
            raise ConfigError(f"potential: only the 'progress' reward has one (reward is "
                              f"{self.reward!r})")
        x, y = position
        return float(self.potentials[self.geodesic.node_at(float(x), float(y))])

    def step_rewards(self, ticks: np.ndarray, changed: np.ndarray, hit: np.ndarray,
                     potential_before: np.ndarray | None, potential_after: np.ndarray | None
                     ) -> np.ndarray:
        """Rewards of steps (arrays, one entry per robot or env) that charged ``ticks``, changed
        the bounce angle where ``changed`` and reached the goal where ``hit``; ``potential_*``
        (``progress`` only) is Φ before and after the step (where not ``hit``). The single and
        the batched env both compute their rewards here, so they agree to the last bit."""
        if self.reward == "plan_cost":
            reward = -self.w1 * ticks - (self.w2 - self.w1) * changed
        else:
            reward = -self.tick_cost * ticks
        reward = reward + self.goal_bonus * hit
        if self.reward == "progress":
            reward = reward + (self.gamma * np.where(hit, 0.0, potential_after)
                               - potential_before)
        return reward

    def plan_cost_of(self, ticks: np.ndarray, changed: np.ndarray) -> np.ndarray:
        """The papers' plan cost of steps that charged ``ticks`` and changed the angle where
        ``changed`` (arrays; what ``info["plan_cost"]`` adds up)."""
        return self.w1 * ticks + (self.w2 - self.w1) * changed

    def _info(self, state) -> dict:
        gap = float(np.hypot(*(state.position[0] - self.goal[0][0])))
        return {"goal_position": self.goal[0][0].copy(), "goal_heading": float(self.goal[1][0]),
                "distance_to_goal": gap, "is_success": self.reached,
                "plan_cost": self.plan_cost}

    def ticks_to_goal(self, events: StepEvents, goal: tuple | None = None) -> float | None:
        """Ticks into the step of a lone robot (``events``) at which it first enters the goal
        region with its heading within tolerance, else None. ``goal``: (position (1, 2),
        heading (1,)), default this episode's — the batched env passes each env's own."""
        goal_position, goal_heading = self.goal if goal is None else goal
        if not self.heading_within(events.heading[0], goal_heading[0]):
            return None
        p0, p1, g = events.start[0], events.end[0], goal_position[0]
        seg = p1 - p0
        length = float(np.hypot(*seg))
        rel = p0 - g
        radius = self.goal_radius + GOAL_SLACK  # the closed disk, robust to rounding
        if rel @ rel <= radius**2:
            s = 0.0
        elif length == 0:
            return None
        else:
            d = seg / length
            b = float(rel @ d)
            disc = b * b - (float(rel @ rel) - radius**2)
            if disc < 0:
                return None
            s = -b - math.sqrt(disc)  # where the segment's line enters the goal disk
            if s < 0 or s > length:
                return None  # the disk lies behind the start, or beyond the end
        per_tick = tick_length_at(self.options, float(events.heading[0]))
        drive = math.ceil(s / per_tick - 1e-9)
        return float(events.bumps[0] + drive)

    def heading_within(self, heading, goal_heading):
        """Whether headings (radians, floats or arrays) are within ``heading_tolerance`` of the
        goal headings, the arrival test's heading half."""
        err = (heading - goal_heading + np.pi) % (2 * np.pi) - np.pi
        return np.abs(err) <= self.heading_tolerance

    def step(self, state, events):
        changed = np.array([bool(events.angle_changed[0])])
        arrive = self.ticks_to_goal(events)
        hit = np.array([arrive is not None])
        ticks = np.array([events.ticks if arrive is None else min(events.ticks, arrive)],
                         dtype=np.float64)
        before = after = None
        if self.geodesic is not None:
            before = np.array([self.potential_now])
            after = np.array([self.potential(state.position[0])])
            self.potential_now = 0.0 if arrive is not None else float(after[0])
        reward = self.step_rewards(ticks, changed, hit, before, after)
        self.plan_cost = self.plan_cost + float(self.plan_cost_of(ticks, changed)[0])
        if arrive is not None:
            self.reached = True
        info = self._info(state)
        if arrive is not None:
            info["ticks_to_goal"] = int(state.ticks - events.ticks + arrive)
        info["angle_changed"] = bool(changed[0])
        return reward, np.array([self.reached]), info

    def observation(self, state):
        if not self.observe_task:
            return np.zeros((1, 0), dtype=np.float32)
        feats = (self.pose_features(*self.start), self.pose_features(*self.goal))
        return np.concatenate(feats, axis=1).astype(np.float32)

    def pose_features(self, position: np.ndarray, heading: np.ndarray) -> np.ndarray:
        """(m, 4) float64 observation features of poses (positions (m, 2), headings (m,)): the
        normalised position, then the heading's cosine and sine; the observation is those of
        the start and of the goal, cast to float32."""
        trig = [[math.cos(h), math.sin(h)] for h in np.asarray(heading).tolist()]
        return np.concatenate((_normalised(self.options.world, position),
                               np.array(trig).reshape(-1, 2)), axis=1)

    def render_layers(self):
        return {"goal": (*self.goal[0][0], self.goal_radius, float(self.goal[1][0]),
                         self.heading_tolerance)}


