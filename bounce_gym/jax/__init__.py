"""Functional JAX versions of the single-robot bouncing envs (``pip install 'bounce-gym[jax]'``).

``env, params = bounce_gym.jax.make(env_id, **options)`` gives the env of a Gymnasium id in the
gymnax convention (`bounce_gym.jax.environment`): ``env.reset(key, params)``,
``env.step(key, state, action, params)`` with automatic reset, jit-, vmap- and scan-compatible.
The NumPy envs are the reference; see docs/jax.md.
"""

from __future__ import annotations

from bounce_gym.extras import require

require("bounce_gym.jax", "jax", "optax")

from bounce_gym.jax.environment import Environment  # noqa: E402  (after the check)
from bounce_gym.jax.make import make, pose_options  # noqa: E402

__all__ = ["Environment", "make", "pose_options"]
