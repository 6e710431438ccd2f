"""`GoalNavigationEnv`: ``bounce_gym/BounceNavigation-v1``, navigation as a goal-conditioned task.

The goal-conditioned convention of Gymnasium-Robotics (its ``GoalEnv``), which SB3's
``HerReplayBuffer`` relabels with (Andrychowicz et al., "Hindsight Experience Replay", NeurIPS
2017): a ``Dict`` observation of ``observation``, ``achieved_goal`` and ``desired_goal``, and a
vectorised ``compute_reward(achieved_goal, desired_goal, info)`` equal to the step's reward.
"""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces

from bounce_gym.envs.bounce_env import BounceEnv
from bounce_gym.errors import ConfigError

#: the horizon of ``BounceNavigation-v1`` in units of the longest optimal plan of the map
#: (`GoalNavigationEnv.horizon`)
HORIZON_FACTOR = 3.0


class GoalNavigationEnv(BounceEnv):
    """Reach a goal pose of the cell model; observations and goals as one-hot poses.

    ## Description

    The task of `bounce_gym.envs.tasks.goal_navigation.GoalNavigationTask`: the robot must end
    a drive against the wall in a goal pose of the env's cell model (a cell and a heading bin)
    that the model says it can reach — after ``info["optimal_bounces"]`` bounces at the
    fewest. It is v0's navigation with the changes that let a learner learn it
    (docs/learning.md): goals where a contact-sensing robot can know it has arrived, only
    joined start/goal pairs, a horizon a few times the longest optimal plan of the map
    (`horizon`), the sparse reward, and the goal-conditioned observation below.

    ## Action Space

    ``Discrete(len(angles))``: the index of the bounce angle in Φ, as in v0. Discrete actions
    only: the angles must be whole heading bins of the cell model, so that every bounce ends in
    a pose of the model.

    ## Observation Space

    ``Dict`` of three float32 ``Box`` es:

    * ``observation`` — what the v0 robot senses: ``clock`` (ticks since the last bump /
      max_clock), then the optional ``history`` and ``privileged`` pose;
    * ``achieved_goal`` — the robot's pose on the cell model after the step: a one-hot of its
      position cell (``n_positions`` entries) then a one-hot of its heading bin (``n_bins``);
      zeros where it is outside the model's free cells or its heading is not within tolerance
      of a bin. On the noise-free cell backend this pose follows from the start pose and the
      clock readings and angles since (what the roadmap planner tracks), so it tells the
      robot nothing it could not know; on noisy or continuous worlds it is the true cell, an
      oracle, and rows that use it there say so ("pose observed");
    * ``desired_goal`` — the goal pose, encoded the same way.

    ## Rewards

    ``goal_bonus`` (1) on the step that ends in the goal pose, else 0; `compute_reward` gives
    the same from ``achieved_goal`` and ``desired_goal``.

    ## Starting State

    A pose of the cell model (cell centre, bin heading) from which the goal can be reached;
    in bounce mode the robot then drives on to its first bump, where the first action turns it.

    ## Episode End

    Terminated on reaching the goal. Truncated after `horizon` steps: `HORIZON_FACTOR` (3)
    times the longest optimal plan of the env's own map (``task.longest_plan``, the fewest
    bounces of the hardest start/goal pair it draws), so every map gets the same slack — 42
    on the lab map (14 bounces). The id registers no ``max_episode_steps``; ``gym.make`` applies
    the horizon with `bounce_gym.envs.map_horizon.MapHorizon` and reports it as
    ``env.spec.max_episode_steps``; ``gym.make(..., max_episode_steps=n)`` sets another.

    ## Arguments

    Those of `BounceEnv` (the "Arguments" table), with ``task_kwargs`` for `GoalNavigationTask` (``draw``,
    ``heading_tolerance_deg``, ``start``, ``goal``, ``goal_bonus``, ``w1``, ``w2``); the task is
    always ``goal_navigation``.
    """

    tasks = ("goal_navigation",)
    option_defaults = {"task": "goal_navigation"}

    @property
    def observes_pose(self) -> bool:
        """True: ``achieved_goal`` is the robot's cell pose after every step."""
        return True

    def __init__(self, render_mode: str | None = None, **options: object) -> None:
        super().__init__(render_mode, **options)
        if self.options.action_type != "discrete":
            raise ConfigError("action_type: BounceNavigation-v1 takes discrete actions (an "
                              "index into the angles)")
        model = self.task.model
        self.n_positions, self.n_bins = model.n_positions, model.n_bins
        size = self.n_positions + self.n_bins
        self.observation_space = spaces.Dict({
            "observation": self.observation_space,
            "achieved_goal": spaces.Box(0.0, 1.0, (size,), dtype=np.float32),
            "desired_goal": spaces.Box(0.0, 1.0, (size,), dtype=np.float32),
        })
        #: the steps after which an episode is truncated: `HORIZON_FACTOR` times the longest
        #: optimal plan of the map, rounded up (one step where no start/goal pair is joined,
        #: which only ``draw="any"`` allows)
        self.horizon = max(1, math.ceil(HORIZON_FACTOR * self.task.longest_plan))

    def observation_labels(self, agent: str | None = None) -> dict[str, tuple[str, ...]]:
        """What each index of each key of the observation is."""
        pose = (("position cell, one-hot",) * self.n_positions
                + ("heading bin, one-hot",) * self.n_bins)
        return {"observation": self.core.obs_labels, "achieved_goal": pose,
                "desired_goal": pose}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        sensed, info = super().reset(seed=seed, options=options)
        return self._observe(sensed), info

    def step(self, action):
        sensed, reward, terminated, truncated, info = super().step(action)
        return self._observe(sensed), reward, terminated, truncated, info

    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray:
        """The step reward of every (achieved, desired) pair (leading dimensions broadcast):
        ``goal_bonus`` where they share a position cell and a heading bin, else 0."""
        achieved = np.asarray(achieved_goal, dtype=np.float32)
        desired = np.asarray(desired_goal, dtype=np.float32)
        n = self.n_positions
        cell = (achieved[..., :n] * desired[..., :n]).sum(axis=-1) > 0
        heading = (achieved[..., n:] * desired[..., n:]).sum(axis=-1) > 0
        return np.where(cell & heading, self.task.goal_bonus, 0.0)

    def _observe(self, sensed: np.ndarray) -> dict:
        task = self.task
        return {"observation": sensed, "achieved_goal": self._one_hot(task.achieved),
                "desired_goal": self._one_hot(task.goal_pose)}

    def _one_hot(self, z: int) -> np.ndarray:
        """A pose as a one-hot of its position cell followed by a one-hot of its bin (zeros
        for −1)."""
        out = np.zeros(self.n_positions + self.n_bins, dtype=np.float32)
        if z >= 0:
            position, heading = self.task.model.decode(z)
            out[position] = out[self.n_positions + heading] = 1.0
        return out
