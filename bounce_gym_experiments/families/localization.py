"""Localization with a contact sensor and a clock: the angle-switching planner
(`baselines.localization.AngleSwitchPolicy`) against the filter's remaining candidates.

Per episode: ``success`` (localized), ``candidates`` (left at the end), ``correct`` (the claim is
the true decision state), ``wrong_claim`` (it is not among the claim) and the score,
``steps_to_correct``: the bumps (env steps) until the filter made a correct claim, an episode
without one — no claim within the horizon, or a wrong one — counted at the horizon
(right-censored; ``correct`` says how many were not). Success alone is no score on the
benchmark's map: the planner, the trained agents and random bouncing all localize in every
episode, and they differ in how soon. With the task's
``filter_factory: belief`` the planner is `baselines.localization.BeliefLocalizationPolicy`,
with ``filter_factory: particles`` `baselines.localization.ParticleLocalizationPolicy`.
"""

from __future__ import annotations

from bounce_gym_experiments.families.base import Episode, SingleRobotFamily


class LocalizationEpisode(Episode):
    """Counts the steps until a correct claim (module docstring)."""

    def __init__(self, horizon: int, read) -> None:
        self.read = read
        self.horizon = horizon
        self.steps = 0
        self.correct_at: int | None = None

    def step(self, info):
        self.steps += 1
        if self.correct_at is None and info.get("localized") and info.get("correct"):
            self.correct_at = self.steps
        return False

    def metrics(self, info):
        steps = self.horizon if self.correct_at is None else self.correct_at
        return {**self.read(info), "steps_to_correct": steps}


class Localization(SingleRobotFamily):
    name = task = "localization"
    columns = (*SingleRobotFamily.columns, "steps_to_correct", "success", "candidates",
               "correct", "wrong_claim")
    score = "steps_to_correct"
    higher_is_better = False

    def make_planner(self, env):
        from baselines.localization import (
            AngleSwitchPolicy,
            BeliefLocalizationPolicy,
            ParticleLocalizationPolicy,
        )
        from bounce_gym.envs.tasks.localization import BELIEF, PARTICLES

        if env.unwrapped.task.filter_factory == BELIEF:
            return BeliefLocalizationPolicy.for_env(env)
        if env.unwrapped.task.filter_factory == PARTICLES:
            return ParticleLocalizationPolicy.for_env(env)
        return AngleSwitchPolicy.for_env(env)

    def prepare(self, env, experiment):
        """The horizon, where `LocalizationEpisode` caps the steps to a correct claim."""
        return int(experiment["max_steps"])

    def episode(self, env, policy, setup):
        return LocalizationEpisode(setup, self.metrics)

    def metrics(self, info):
        return {"success": bool(info.get("localized", False)),
                "candidates": int(info.get("candidates", -1)),
                "correct": bool(info.get("correct", False)),
                "wrong_claim": bool(info.get("wrong_claim", False))}


FAMILY = Localization()
