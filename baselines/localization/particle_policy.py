"""Choosing bounce angles to localize on a particle belief, from contact and clock only."""

from __future__ import annotations

import numpy as np

from baselines.policy import Policy, episode_rng
from bounce_gym.dynamics.particles import DEFAULT_PARTICLES, ParticleBelief
from bounce_gym.errors import ConfigError

#: expected information (bits) below which an angle counts as telling nothing
NO_GAIN = 1e-3


class ParticleLocalizationPolicy(Policy):
    """Information gathering on a particle belief (`bounce_gym.dynamics.particles`): at every
    bump, the angle of Φ whose next bump leaves the smallest expected entropy of the belief over
    decision states (`ParticleBelief.expected_entropy`; ties: the first angle). When no angle
    is expected to tell anything at the next bump (a gain below `NO_GAIN` bits: the robot runs
    a limit cycle whose clocks every candidate shares, and a myopic rule would keep it there)
    it picks a uniformly random angle, which takes it out of the cycle.

    The policy keeps its own particles, moved by the env's dynamics (its configuration: world,
    backend, noise, radius, step length — not its state), and feeds them what the robot senses:
    the clock of its observation (ticks / ``max_clock``) after the reset's drive (the prior) and
    at every bump, with the angle it commanded itself. ``act`` ignores ``info`` (it may be
    None). The claim is the task's (filter "particles"). Its random stream restarts at every
    episode from ``seed`` (None: the episode's seed), so an episode does not depend on the ones
    before it.
    """

    name = "particles (expected entropy)"

    def __init__(self, particles: int = DEFAULT_PARTICLES, seed: int | None = None) -> None:
        self.particles, self.seed = int(particles), seed
        self.rng = np.random.default_rng(seed)

    @classmethod
    def for_env(cls, env, seed: int | None = None) -> ParticleLocalizationPolicy:
        """As many particles as the env's localization task uses (`LocalizationTask.particles`)."""
        return cls(env.unwrapped.task.particles, seed)

    def start_options(self, env, seed: int) -> None:
        self.rng = episode_rng(self.seed, seed)
        return None

    def reset(self, env) -> None:
        base = env.unwrapped
        options = base.options
        if options.action_type != "discrete" or options.step_mode != "bounce":
            raise ConfigError("ParticleLocalizationPolicy needs discrete actions and "
                              "step_mode='bounce'")
        self.angles = np.asarray(options.angles[0], dtype=np.float64)
        self.max_clock = int(options.max_clock)
        self._clock_index = 1 if base.core.observes_contact else 0
        self.belief = ParticleBelief(base.cell_model(), options.robot_dynamics, self.particles,
                                     max_clock=self.max_clock)
        self.last_action: int | None = None

    def _clock(self, observation) -> int:
        value = float(np.asarray(observation).reshape(-1)[self._clock_index])
        return int(round(value * self.max_clock))

    def act(self, observation, info=None) -> int:
        del info  # the robot's own observation only
        clock = self._clock(observation)
        if self.last_action is None:
            self.belief.reset(self.rng, clock)
        else:
            self.belief.update(float(self.angles[self.last_action]), clock)
        expected = self.belief.expected_entropy(self.angles)
        if expected.min() < self.belief.entropy - NO_GAIN:
            self.last_action = int(np.argmin(expected))
        else:  # no angle tells anything at the next bump (a limit cycle): leave it at random
            self.last_action = int(self.rng.integers(len(self.angles)))
        return self.last_action
