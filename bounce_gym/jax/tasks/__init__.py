"""The tasks of the cell-backend JAX env, one module each (`bounce_gym.jax.make` builds them
from a configured NumPy task); users reach them through `bounce_gym.jax.make`."""

#: the package itself exports nothing: `bounce_gym.jax` is the interface
__all__: list[str] = []
