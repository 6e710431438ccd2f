"""Several robots in a PettingZoo parallel env with no task (``bounce_gym/MultiBounce-v0``), and
what every multi-robot family shares.

Per episode: ``robots`` (m) and ``robot_contacts`` (robots that ended a step blocked by another
robot, summed over steps: a head-on pair counts twice). The first-seed plot data hold the task's
regions (if any) and the backend.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.errors import ConfigError
from bounce_gym_experiments.families.base import Episode, Family


class TeamEpisode(Episode):
    """Counts robot contacts and steps."""

    def __init__(self, env) -> None:
        self.inner = env.unwrapped
        self.contacts = 0
        self.steps = 0

    def step(self, info):
        # info names each robot's contact partner, not whether the robot is blocked now
        state = self.inner.robot_state
        self.contacts += int(np.sum(state.blocked & (state.contact_robot >= 0)))
        self.steps += 1
        return False

    def metrics(self, info):
        return {"robots": self.inner.options.n_robots, "robot_contacts": self.contacts}


class MultiRobot(Family):
    name = "multirobot"
    parallel = True
    table = "multi-robot bouncing"
    columns = ("experiment", "policy", "robots", "episodes", "seeds", "robot_contacts", "ticks")
    labels = frozenset({"robots"})
    takes_planner_kwargs = True
    #: the planner's class in `baselines.multirobot.policies`
    planner_class = ""

    def planner(self, env, experiment, setup):
        if not self.planner_class:
            raise ConfigError(f"policies: no multi-robot planner for task {self.task!r}")
        from baselines.multirobot import policies

        try:
            return getattr(policies, self.planner_class).for_env(env,
                                                                 **experiment["planner_kwargs"])
        except TypeError as exc:
            raise ConfigError(f"planner_kwargs: {exc}") from None

    def episode(self, env, policy, setup):
        return TeamEpisode(env)

    def collect(self, data, env, policy, setup):
        inner = env.unwrapped
        data["backend"] = inner.options.backend
        data["regions"] = inner.task.render_layers().get("regions")


FAMILY = MultiRobot()
