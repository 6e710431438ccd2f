"""Whether the world lets a robot with continuous bounce angles reach a goal at all, asked of
the simulator and not of any planner.

`world_reachable` drives the robot from its start pose to its first contact as a bounce-mode
reset does (the task does not count that drive's path), then plays ``walks`` independent random
walks of at most ``bumps`` bumps each in the noise-free world: at every bump every walk draws
its angle uniformly from the continuous range (the float32 action the env would be given,
`baselines.navigation.motion`), all walks are simulated together
(`bounce_gym.dynamics.bump_sampler.simulate_bumps`), and every straight drive is tested
against the goal region by the task's own test (`BumpOutcomes.goal_hits`). The pair is
*world-reachable* when some walk's drive passes through the goal.

On pymunk's dynamic physics the walks read the tabulated bump map
(`bounce_gym.dynamics.bump_table`), and a walk's hit is replayed in the simulator itself before
it counts: the answer is the world's, the table only finds candidate sequences fast.

The check is one-sided. A hit is a proof: the walk's angles, replayed in the env, reach the
goal. A miss is not: the walks are a sample of the sequences of angles, and a goal that only a
narrow set of them reaches (a long corridor to be crossed at a steep angle, say) may be missed.
Its budget is ``walks`` × ``bumps`` simulated bumps (by default 1,000 × 200: the 200 steps of
``BounceNavigation-v0``); on the kinematic backend about 1 s for a pair the walks miss, less
for one they hit (the walks stop at the first hit).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from baselines.navigation.motion import executed_angle
from baselines.navigation.shots import GoalRegion
from bounce_gym.dynamics.bump_sampler import default_max_ticks
from bounce_gym.dynamics.noise import Exact

#: the default number of random walks
WALKS = 1_000


@dataclass(frozen=True)
class Reachability:
    """What `world_reachable` found: ``reached`` (some walk passed through the goal), after how
    many bumps the first did (−1: none), and the budget it spent."""

    reached: bool
    first_bump: int
    walks: int
    bumps: int


def noise_free(dynamics: dict) -> dict:
    """``dynamics`` (`BounceDynamics` arguments) with the rotation noise taken out."""
    return {**dynamics, "noise": Exact()}


def world_reachable(motion, start: tuple[np.ndarray, float], goal: GoalRegion,
                    angle_range: tuple[float, float], bumps: int, seed: int,
                    walks: int = WALKS, max_ticks: int | None = None,
                    phi: np.ndarray | None = None) -> Reachability:
    """Random walks with continuous angles (with ``phi``: uniform among these discrete angles,
    radians) from ``start`` (position (2,), heading) in the noise-free world of ``motion`` (`bounce_gym.dynamics.bump_table.bump_motion` of
    `noise_free` dynamics): does any pass through ``goal`` within ``bumps`` bumps (module
    docstring)? ``seed`` seeds the angles drawn. Where ``motion`` reads the tabulated map (a
    model of the simulator), a walk's hit counts only once its angles, replayed in the
    simulator itself, reach the goal too (`replay_reaches`)."""
    rng = np.random.default_rng(seed)
    if max_ticks is None:
        max_ticks = default_max_ticks(motion.dynamics)
    position, heading = np.asarray(start[0], dtype=np.float64).reshape(1, 2), float(start[1])
    state, point, head, _ = motion.reset_drives(position, np.array([heading]), rng, max_ticks)
    if state[0] < 0:
        return Reachability(False, -1, walks, bumps)
    point, head = np.repeat(point, walks, axis=0), np.repeat(head, walks)
    walk = np.arange(walks)  # the walk of every robot still driving
    history = np.zeros((walks, bumps))  # the angles every walk drew
    for bump in range(1, bumps + 1):
        if phi is None:
            angle = executed_angle(rng.uniform(-1.0, 1.0, len(point)).astype(np.float32),
                                   angle_range)
        else:
            angle = np.asarray(phi, dtype=np.float64)[rng.integers(len(phi), size=len(point))]
        history[walk, bump - 1] = angle
        out = motion.bumps(angle, np.arange(len(angle)), point, head, rng, max_ticks)
        hits = out.goal_hits(goal.point, goal.heading, goal.radius, goal.tolerance)
        alive = out.next_state >= 0
        for k in np.flatnonzero(hits):
            if motion.table is None or replay_reaches(motion, start, goal,
                                                      history[walk[k], :bump], max_ticks):
                return Reachability(True, bump, walks, bumps)
            alive[k] = False  # the table's hit the simulator does not confirm: dropped
        point, head, walk = out.end[alive], out.heading[alive], walk[alive]
        if len(point) == 0:
            break
    return Reachability(False, -1, walks, bumps)


def replay_reaches(motion, start: tuple[np.ndarray, float], goal: GoalRegion,
                   angles: np.ndarray, max_ticks: int) -> bool:
    """Whether one robot of the simulator itself (not the table), started at ``start`` and
    bouncing by ``angles`` in turn, drives through ``goal``."""
    from bounce_gym.dynamics.bump_table import bump_motion

    world = bump_motion(motion.model, motion.dynamics, tabulated=False)
    rng = np.random.default_rng(0)  # noise-free: nothing is drawn
    position = np.asarray(start[0], dtype=np.float64).reshape(1, 2)
    state, point, head, _ = world.reset_drives(position, np.array([float(start[1])]), rng,
                                               max_ticks)
    for angle in angles:
        if state[0] < 0:
            return False
        out = world.bumps(np.array([angle]), np.zeros(1, dtype=np.int64), point, head, rng,
                          max_ticks)
        if out.goal_hits(goal.point, goal.heading, goal.radius, goal.tolerance).any():
            return True
        state, point, head = out.next_state, out.end, out.heading
    return False
