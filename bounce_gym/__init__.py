"""bounce_gym: Gymnasium and PettingZoo environments for minimal bouncing robots.

A bouncing robot senses only contact and time. It drives straight until it bumps, rotates by a
bounce angle and drives on. `bounce_gym.worlds` holds the geometry, `bounce_gym.dynamics` the
motion of one or many robots, `bounce_gym.envs` the Gymnasium and PettingZoo environments, which
are registered on import (``gym.make("bounce_gym/Bounce-v0")``).
"""

from bounce_gym.envs.registration import register_envs
from bounce_gym.errors import BounceGymError, ConfigError

__version__ = "0.1.0"

__all__ = ["BounceGymError", "ConfigError", "__version__", "register_envs"]

register_envs()
