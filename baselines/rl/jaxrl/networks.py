"""MLPs as plain parameter pytrees: a tuple of ``(w, b)`` layers, orthogonal initialisation
(Saxe et al. 2014) with Stable-Baselines3's gains, and the flat observation they read.

A ``Dict`` observation (the goal-conditioned envs) is flattened by concatenating its entries in
the fixed order `OBSERVATION_KEYS`, so the JAX learners and the evaluation (which gets the NumPy
env's observation) feed the network the same vector.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.errors import ConfigError

#: The entries of a goal-conditioned observation, in the order they are concatenated.
OBSERVATION_KEYS = ("observation", "achieved_goal", "desired_goal")
#: Activation names of ``policy_kwargs.activation_fn`` and their JAX functions.
ACTIVATIONS = {"tanh": jnp.tanh, "relu": jax.nn.relu, "elu": jax.nn.elu,
               "leaky_relu": jax.nn.leaky_relu, "gelu": jax.nn.gelu}
#: Gain of the hidden layers' orthogonal initialisation (SB3's, for tanh and ReLU nets alike).
HIDDEN_GAIN = math.sqrt(2.0)


def init_mlp(key: jax.Array, sizes: list[int], head_gain: float) -> tuple:
    """Layers ``sizes[0] -> ... -> sizes[-1]``: weights orthogonal (gain `HIDDEN_GAIN`, the last
    layer ``head_gain``), biases zero."""
    keys = jax.random.split(key, len(sizes) - 1)
    layers = []
    for k, (n_in, n_out) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
        gain = head_gain if k == len(sizes) - 2 else HIDDEN_GAIN
        w = jax.nn.initializers.orthogonal(scale=gain)(keys[k], (n_in, n_out), jnp.float32)
        layers.append((w, jnp.zeros((n_out,), jnp.float32)))
    return tuple(layers)


def apply_mlp(layers: tuple, x: jax.Array, activation: str) -> jax.Array:
    """The MLP's output for ``x`` (leading dimensions broadcast): the activation after every
    layer but the last."""
    act = ACTIVATIONS[activation]
    for w, b in layers[:-1]:
        x = act(x @ w + b)
    w, b = layers[-1]
    return x @ w + b


def flatten_observation(observation) -> jax.Array:
    """One float32 vector per observation (leading dimensions kept): a ``Dict`` observation's
    entries concatenated in `OBSERVATION_KEYS` order."""
    if isinstance(observation, dict):
        return jnp.concatenate([jnp.asarray(observation[k], jnp.float32)
                                for k in OBSERVATION_KEYS], axis=-1)
    return jnp.asarray(observation, jnp.float32)


def observation_size(space) -> int:
    """The length of the flat observation of a Gymnasium (or `bounce_gym.jax.spaces`) space; a
    `ConfigError` for a space the learners do not read."""
    spaces = getattr(space, "spaces", None)
    if spaces is not None:
        if set(spaces) != set(OBSERVATION_KEYS):
            raise ConfigError(f"config.env: a Dict observation needs exactly the entries "
                              f"{list(OBSERVATION_KEYS)}, got {sorted(spaces)}")
        return sum(observation_size(spaces[k]) for k in OBSERVATION_KEYS)
    shape = getattr(space, "shape", None)
    if shape is None or len(shape) != 1:
        raise ConfigError(f"config.env: the JAX learners read flat vector observations, got "
                          f"{space}")
    return int(shape[0])


def layer_names(prefix: str, layers: tuple) -> dict[str, np.ndarray]:
    """The layers as named arrays (``<prefix>.<k>.w``, ``<prefix>.<k>.b``), for a weights file."""
    out = {}
    for k, (w, b) in enumerate(layers):
        out[f"{prefix}.{k}.w"] = np.asarray(w)
        out[f"{prefix}.{k}.b"] = np.asarray(b)
    return out


def layer_shapes(prefix: str, sizes: list[int]) -> dict[str, tuple[int, ...]]:
    """The names `layer_names` gives an MLP of these sizes, and each array's shape."""
    out = {}
    for k, (n_in, n_out) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
        out[f"{prefix}.{k}.w"] = (n_in, n_out)
        out[f"{prefix}.{k}.b"] = (n_out,)
    return out


def named_layers(prefix: str, arrays: dict[str, np.ndarray], depth: int) -> tuple:
    """The layers `layer_names` wrote under ``prefix`` (``depth`` of them), as JAX arrays."""
    return tuple((jnp.asarray(arrays[f"{prefix}.{k}.w"]), jnp.asarray(arrays[f"{prefix}.{k}.b"]))
                 for k in range(depth))
