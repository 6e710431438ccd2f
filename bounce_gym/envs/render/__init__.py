"""Drawing the environments: the pygame renderer, what the envs draw, and GIF recording."""
