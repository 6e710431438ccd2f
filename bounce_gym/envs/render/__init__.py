"""Drawing the environments: the pygame renderer, what the envs draw, and GIF recording."""

from bounce_gym.envs.render.gif import record_episode, save_gif

__all__ = ["record_episode", "save_gif"]
