"""Functional JAX versions of the single-robot bouncing envs (``pip install 'bounce-gym[jax]'``).

``env, params = bounce_gym.jax.make(env_id, **options)`` gives the env of a Gymnasium id in the
gymnax convention (`bounce_gym.jax.environment`): ``env.reset(key, params)``,
``env.step(key, state, action, params)`` with automatic reset, jit-, vmap- and scan-compatible.
The NumPy envs are the reference; see docs/jax.md.
"""

from __future__ import annotations

try:
    import jax  # noqa: F401
except ModuleNotFoundError:  # pragma: no cover - the extra is missing
    from bounce_gym.errors import ConfigError

    raise ConfigError("bounce_gym.jax needs JAX: pip install 'bounce-gym[jax]'") from None

from bounce_gym.jax.environment import Environment
from bounce_gym.jax.make import make, pose_options

__all__ = ["Environment", "make", "pose_options"]
