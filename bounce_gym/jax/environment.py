"""`Environment`: the functional env protocol of gymnax (Lange 2022), which PureJaxRL-style
training loops expect.

An env is a pure function of a key, a state and parameters:

* ``reset(key, params) -> (obs, state)``;
* ``step(key, state, action, params) -> (obs, state, reward, done, info)``, resetting
  automatically: where ``done`` the returned ``obs`` and ``state`` are the next episode's first,
  and ``info["final_observation"]`` is the observation the step itself ended in;
* ``action_space(params)``, ``observation_space(params)``, ``default_params``.

``done`` is ``terminated | truncated``; ``info["terminated"]`` and ``info["truncated"]`` tell them
apart (a learner that bootstraps through truncation needs the difference). Everything is
jit-, vmap- and scan-compatible: no Python control flow on traced values.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def where_tree(condition: jax.Array, on_true, on_false):
    """``jnp.where(condition, a, b)`` leaf by leaf of two pytrees of the same structure."""
    return jax.tree.map(lambda a, b: jnp.where(condition, a, b), on_true, on_false)


class Environment:
    """Base class: subclasses define `reset_env`, `step_env`, the spaces and `default_params`."""

    #: the Gymnasium id this env reproduces
    env_id: str = ""
    #: whether `step_env` draws nothing from its key (then `step` hands the whole key to the
    #: reset instead of splitting it: a split costs as much as a cell env's step)
    deterministic_step: bool = False

    @property
    def default_params(self):
        raise NotImplementedError

    def reset(self, key: jax.Array, params=None):
        """A new episode: ``(obs, state)``."""
        return self.reset_env(key, self.default_params if params is None else params)

    def step(self, key: jax.Array, state, action, params=None):
        """One step with automatic reset (module docstring)."""
        params = self.default_params if params is None else params
        key_step, key_reset = ((key, key) if self.deterministic_step
                               else tuple(jax.random.split(key)))
        obs, next_state, reward, done, info = self.step_env(key_step, state, action, params)
        fresh_obs, fresh_state = self.reset_env(key_reset, params)
        info = {**info, "final_observation": obs}
        return (where_tree(done, fresh_obs, obs), where_tree(done, fresh_state, next_state),
                reward, done, info)

    def reset_env(self, key: jax.Array, params):
        raise NotImplementedError

    def step_env(self, key: jax.Array, state, action, params):
        raise NotImplementedError

    def action_space(self, params=None):
        raise NotImplementedError

    def observation_space(self, params=None):
        raise NotImplementedError

    @property
    def num_actions(self) -> int:
        return self.action_space().n
