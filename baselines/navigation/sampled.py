"""Navigation on the GCM learned from the simulator, closed loop from contact and clock.

`SampledNavigationPlanner` plans on the env's sampled generalized cell mapping
(``env.cell_model(kind="sampled")``, `bounce_gym.dynamics.sampled_model`) instead of the exact
cell model:

* at reset, it reads the episode's start and goal poses (what the task appends to the
  observation), tests every sample point's path against the goal region (the task's goal test,
  `BumpOutcomes.goal_hits`) and solves the finite-horizon stochastic shortest path — most likely
  to reach the goal within the episode's steps, then least expected plan cost
  (`bounce_gym.markov.ssp.ReachPlan`);
* its belief is a set of weighted pose particles (a particle filter, Thrun, Burgard & Fox,
  *Probabilistic Robotics*, 2005, §4.3, with the env's own dynamics as the motion model): first
  the poses after the reset drive from the start pose (simulated), then after every bump the
  belief's poses moved by the angle it used — in a noisy world ``draws`` of them, each drawing
  its own rotation error — kept where their clock equals the clock it reads (the tick
  likelihood; identical poses merged). When no particle explains the clock, it keeps those of
  the nearest clock (`surprises` counts it);
* while the belief is one exact pose in a deterministic world, it searches the simulator
  breadth-first for a shortest plan (`baselines.navigation.search`): the search either finds
  one or proves that no sequence of angles reaches the goal;
* otherwise, at every bump, it looks ``depth`` bumps ahead from ``particles`` poses of the
  belief: every pose simulated under every sequence of angles, branching on the clocks it would
  read, scored by the goal test on the simulated paths and beyond them by simulated rollouts of
  base policies or, with ``rollouts=False``, by the GCM's values
  (`baselines.navigation.lookahead`).

It reads only its observation (the clock) in `act`, never ``info``. ``predicted_success`` is
its probability of reaching the goal within the episode, computed at its first decision: exact
after a search; otherwise the GCM's value, from the belief, of deciding at every bump by a
receding horizon of ``reach`` bumps for the whole episode (`ReachPlan.follow`) — the look-ahead's
own value covers only ``reach`` bumps.

Without rotation noise a relative bounce adds whole bins to the heading, so the heading modulo
the bin width stays that of the start; the model is then sampled at exactly those headings
(``heading_offset``), one model per offset (cached). With noise the headings are spread over
their bins.
"""

from __future__ import annotations

import math

import numpy as np

from baselines.navigation.lookahead import lookahead
from baselines.navigation.policy import _env_angles_deg
from baselines.navigation.search import shortest_plan
from baselines.policy import Policy
from bounce_gym.dynamics.noise import Exact
from bounce_gym.dynamics.sampled_model import DEFAULT_SAMPLES
from bounce_gym.errors import ConfigError
from bounce_gym.markov.ssp import ReachPlan

#: the horizon (steps) when the env has no registered one: BounceNavigation-v0's
DEFAULT_HORIZON = 200


class SampledNavigationPlanner(Policy):
    """Stochastic-shortest-path navigation on the sampled GCM (module docstring).

    Args:
        samples, seed: sample points per state and angle of the model, and its seed.
        horizon: steps to plan for (None: the env's registered episode length).
        particles: the poses of the belief the look-ahead simulates (drawn by weight).
        draws: in a noisy world, the poses of the belief simulated to predict every bump (drawn
            by weight; each draws its own rotation error).
        depth: bumps of look-ahead (`baselines.navigation.lookahead`).
        reach: the receding horizon of each decision: the angle that most likely reaches the
            goal within this many bumps (or the steps left, if fewer) is chosen.
        rollouts: value the look-ahead's leaves by simulated rollouts of base policies (True)
            or by the GCM's success values (False: with ``depth`` 1, the QMDP rule; cheap
            enough for dynamic physics).
        cell_size: side of the model's decision cells (None: the env's step length).
        w1, w2: plan-cost weights (None: the task's).
        cache: the model cache folder (None: the default; False: none).
        search_nodes: at most this many poses expanded by the breadth-first search over the
            simulator used while the belief is one exact pose in a deterministic world, over
            the steps left (0: never search).
    """

    name = "sampled ssp planner"

    def __init__(self, samples: int = DEFAULT_SAMPLES, seed: int = 0, horizon: int | None = None,
                 particles: int = 32, depth: int = 3, reach: int = 20, cell_size: float | None = None,
                 w1: float | None = None, w2: float | None = None, cache=None,
                 search_nodes: int = 20_000, rollouts: bool = True, draws: int = 512) -> None:
        self.samples, self.seed, self.horizon = samples, seed, horizon
        self.particles, self.depth, self.cell_size = int(particles), int(depth), cell_size
        self.reach, self.search_nodes = int(reach), int(search_nodes)
        self.rollouts, self.draws = bool(rollouts), int(draws)
        if self.reach < 1:
            raise ConfigError(f"reach: expected an integer >= 1, got {reach!r}")
        self.w1, self.w2, self.cache = w1, w2, cache
        self.predicted_success: float | None = None

    def _offset(self, env, heading: float) -> float | None:
        options = env.options
        if options.backend == "cell" or options.bounce_rule != "relative" \
                or not isinstance(options.noise, Exact):
            return None
        width = 2 * math.pi / env.cell_model().n_bins
        offset = (heading + 0.5 * width) % width - 0.5 * width
        return round(offset, 12)

    def reset(self, env) -> None:
        env = getattr(env, "unwrapped", env)
        task = env.task
        if getattr(task, "name", None) != "navigation":
            raise ConfigError("SampledNavigationPlanner needs an env with task='navigation'")
        _env_angles_deg(env)  # bounce mode, discrete actions
        start_pos, start_head = task.start[0][0], float(task.start[1][0])
        self._goal = (task.goal[0][0], float(task.goal[1][0]), task.goal_radius,
                      task.heading_tolerance)
        self.model = env.cell_model(kind="sampled", samples=self.samples, seed=self.seed,
                                    heading_offset=self._offset(env, start_head),
                                    cell_size=self.cell_size, cache=self.cache)
        out = self.model.outcomes
        reached = out.goal_hits(*self._goal)
        spec_steps = getattr(getattr(env, "spec", None), "max_episode_steps", None)
        self.steps_total = int(self.horizon or spec_steps or DEFAULT_HORIZON)
        self.plan = ReachPlan(out.per_action(reached.astype(np.float64)),
                              out.matrices(~reached),
                              out.per_action(1.0 + out.ticks), self.steps_total,
                              task.w1 if self.w1 is None else self.w1,
                              task.w2 if self.w2 is None else self.w2)
        self.rng = np.random.default_rng(self.seed)
        self._deterministic = isinstance(env.options.noise, Exact)
        state, point, heading, clocks = self.model.first_states(
            start_pos, start_head, 1 if self._deterministic else self.draws, self.rng)
        self._next = {"ticks": clocks, "end": point, "heading": heading, "state": state,
                      "weight": np.ones(len(clocks))}
        self._route = None if self.search_nodes > 0 else False
        self._clock_index = 1 if env.core.observes_contact else 0
        self._max_clock = env.options.max_clock
        self.predicted_success = None
        self.surprises = 0
        self.steps = 0
        self.last: int | None = None

    def _clock(self, observation) -> int:
        return int(round(float(np.asarray(observation).reshape(-1)[self._clock_index])
                         * self._max_clock))

    def _condition(self, clock: int) -> None:
        """The belief: the predicted particles whose clock is the one read (or the nearest),
        identical poses merged."""
        nxt = self._next
        gap = np.abs(nxt["ticks"] - clock)
        keep = gap == gap.min()
        if gap.min() > 0:
            self.surprises += 1
        point, heading, weight = nxt["end"][keep], nxt["heading"][keep], nxt["weight"][keep]
        state = nxt["state"][keep]
        key = np.round(np.column_stack((point, heading)), 9)  # the poses themselves stay exact
        _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
        weight = np.bincount(inverse.ravel(), weights=weight)
        self.point, self.heading, self.state = point[first], heading[first], state[first]
        self.weight = weight / weight.sum()

    def _draw(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The belief as it is (one exact pose without noise), or in a noisy world ``n`` draws
        from it by weight: points, headings and weights."""
        if self._deterministic:
            return self.point, self.heading, self.weight
        pick = self.rng.choice(len(self.point), n, p=self.weight)
        return self.point[pick], self.heading[pick], np.full(n, 1.0 / n)

    def _predict(self, action: int) -> None:
        """The prediction of the next bump: the belief's poses (in a noisy world ``draws`` of
        them, each drawing its own executed rotation, so that the set spreads as the robot's
        pose may: the sampling motion model, Thrun et al. 2005, §4.3) bump with ``action`` and
        drive on; those that pass through the goal end the episode, so the others are kept
        (all, if none do not)."""
        point, heading, weight = self._draw(self.draws)
        out, hit = self.simulate(np.full(len(point), action), point, heading)
        keep = ~hit if (~hit).any() else np.ones(len(hit), dtype=bool)
        self._next = {"ticks": out.ticks[keep], "end": out.end[keep],
                      "heading": out.heading[keep], "state": out.next_state[keep],
                      "weight": weight[keep]}

    def _followed(self) -> float:
        """The model's success of this planner over the steps left, from the belief: each
        particle's state under the policy that takes, at every bump, the angle best within
        `reach` bumps on the GCM (`ReachPlan.follow`) — the planner's decisions on a belief
        concentrated in one state."""
        value = self.plan.follow(self.reach, self.steps_total - self.steps)
        last = self.plan.n_actions if self.last is None else self.last
        inside = self.state >= 0
        return float((self.weight * np.where(inside, value[np.maximum(self.state, 0), last], 0.0)
                      ).sum())

    def simulate(self, action, point, heading):
        """Robots at bump poses bump with angles ``action`` and drive on, in this episode's
        model: their outcomes and which of them pass through the goal."""
        out = self.model.step(action, point, heading, self.rng)
        return out, out.goal_hits(*self._goal)

    def _searched(self) -> tuple[int, float] | None:
        """The next angle and its success probability from the breadth-first search of the
        simulator from the one exact pose of the belief (`baselines.navigation.search`): the
        next angle of a shortest plan (success 1), or, when the search expanded every reachable
        pose without meeting the goal, the angle in use (success 0: nothing reaches it). None
        where the world is noisy, the belief holds several poses or a search of this episode
        hit its limits (the look-ahead decides from then on). A plan is kept while the robot is
        where it predicts and searched again otherwise."""
        if not self._deterministic or len(self.point) != 1 or self._route is False:
            return None
        point, heading = self.point[0], float(self.heading[0])
        route, k = self._route or (None, 0)
        if route is None or (route.found and (k >= len(route.actions) or not (
                np.allclose(route.points[k], point, rtol=0, atol=1e-9)
                and math.isclose(route.headings[k], heading, abs_tol=1e-9)))):
            route = shortest_plan(self.simulate, point, heading, self.plan.n_actions, self.last,
                                  self.steps_total - self.steps,
                                  self.search_nodes, self.plan.w1, self.plan.w2)
            k = 0
        self._route = (route, k + 1) if route.found or route.exhausted else False
        if route.found:
            return route.actions[k], 1.0
        if route.exhausted:  # every successor pose is in the same reachable set: keep going
            return (0 if self.last is None else self.last), 0.0
        return None

    def act(self, observation, info):
        del info  # the robot's own observation only
        self._condition(self._clock(observation))
        searched = self._searched()
        if searched is None:
            steps_left = min(self.steps_total - self.steps, self.reach)
            best = lookahead(self.simulate, self.plan, *self._draw(self.particles), self.depth,
                             steps_left, self.last, self.reach if self.rollouts else 0)
        else:  # the one exact pose: the search's answer is exact
            best, success = searched
        if self.predicted_success is None:
            self.predicted_success = success if searched is not None else self._followed()
        self._predict(best)
        self.steps += 1
        self.last = best
        return best
