"""The observation wrappers a model was trained behind, written into its file and rebuilt at
evaluation.

Training may stack frames (``VecFrameStack``) and normalise observations (``VecNormalize``;
`baselines.rl.train_env`); the policy only ever saw the wrapped observations. `describe_wrappers` records
what the evaluation needs — the stack size and the normalisation statistics, as JSON numbers
(float64, exact) — in the model file's metadata (`baselines.rl.model_files.METADATA_ENTRY`,
JSON, never a pickle). `ObservationPipeline` rebuilds the same SB3 wrappers,
with the statistics frozen, around the observations of one evaluation episode, so the model acts
on exactly what it would have seen in training.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecFrameStack, VecNormalize
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvWrapper

from bounce_gym.errors import ConfigError

_NORMALIZE_NUMBERS = ("clip_obs", "clip_reward", "gamma", "epsilon")


def describe_wrappers(env) -> dict:
    """The wrappers of a training VecEnv as JSON: ``{"n_stack": n, "normalize": None | {...}}``."""
    out: dict[str, Any] = {"n_stack": 1, "normalize": None}
    layer = env
    while isinstance(layer, VecEnvWrapper):
        if isinstance(layer, VecFrameStack):
            out["n_stack"] = int(layer.stacked_obs.n_stack)
        elif isinstance(layer, VecNormalize):
            out["normalize"] = {
                "norm_obs": bool(layer.norm_obs), "norm_reward": bool(layer.norm_reward),
                **{key: float(getattr(layer, key)) for key in _NORMALIZE_NUMBERS},
                "obs_rms": _stats(layer.obs_rms) if layer.norm_obs else None,
                "ret_rms": _stats(layer.ret_rms)}
        layer = layer.venv
    return out


def _stats(rms) -> dict:
    return {"mean": np.asarray(rms.mean, dtype=np.float64).tolist(),
            "var": np.asarray(rms.var, dtype=np.float64).tolist(), "count": float(rms.count)}


class Feed(VecEnv):
    """A one-env VecEnv that hands the wrappers above it the observation it was last given; with
    none, an env that only has these spaces (`baselines.rl.model_load` builds models on it)."""

    def __init__(self, observation_space, action_space) -> None:
        super().__init__(1, observation_space, action_space)
        self.observation = None

    def reset(self):
        return self._batch()

    def step_async(self, actions) -> None:
        pass

    def step_wait(self):
        return self._batch(), np.zeros(1, np.float32), np.zeros(1, bool), [{}]

    def _batch(self):
        """The observation as a batch of one (a dict of batches for a ``Dict`` space)."""
        if isinstance(self.observation, Mapping):
            return {key: np.asarray(value)[None] for key, value in self.observation.items()}
        return np.asarray(self.observation)[None]

    def close(self) -> None:
        pass

    def get_attr(self, attr_name, indices=None):
        return [None]

    def set_attr(self, attr_name, value, indices=None) -> None:
        pass

    def env_method(self, method_name, *method_args, indices=None, **method_kwargs):
        return [None]

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False]


class ObservationPipeline:
    """The wrappers described by ``wrappers`` (`describe_wrappers`), frozen, over single observations of
    ``observation_space``: `first` at the start of an episode, `next` after every step; both
    return the batch of one observation the model acts on. ``path`` names the model file in
    errors."""

    def __init__(self, wrappers: Mapping, observation_space, action_space, path: Path) -> None:
        self.feed = Feed(observation_space, action_space)
        n_stack, normalize = _checked(wrappers, observation_space.shape, path)
        venv = self.feed
        if normalize is not None and normalize["norm_obs"]:
            venv = VecNormalize(venv, training=False, norm_obs=True, norm_reward=False,
                                clip_obs=normalize["clip_obs"], epsilon=normalize["epsilon"])
            venv.obs_rms.mean = np.asarray(normalize["obs_rms"]["mean"], dtype=np.float64)
            venv.obs_rms.var = np.asarray(normalize["obs_rms"]["var"], dtype=np.float64)
            venv.obs_rms.count = normalize["obs_rms"]["count"]
        if n_stack > 1:
            venv = VecFrameStack(venv, n_stack)
        self.venv = venv
        self.observation_space = venv.observation_space
        self._action = np.zeros((1, *(action_space.shape or ())), dtype=action_space.dtype)

    def first(self, observation) -> np.ndarray | dict:
        self.feed.observation = observation
        return self.venv.reset()

    def next(self, observation) -> np.ndarray | dict:
        self.feed.observation = observation
        return self.venv.step(self._action)[0]


def _checked(wrappers: Mapping, shape: tuple, path: Path) -> tuple[int, dict | None]:
    """``(n_stack, normalize)`` of a model file's wrappers, checked against the env's
    observation ``shape``."""
    where = f"model {path}: wrappers"
    if not isinstance(wrappers, Mapping):
        raise ConfigError(f"{where}: expected a mapping, got {wrappers!r}")
    n_stack = wrappers.get("n_stack", 1)
    if isinstance(n_stack, bool) or not isinstance(n_stack, int) or n_stack < 1:
        raise ConfigError(f"{where}.n_stack: expected an integer >= 1, got {n_stack!r}")
    normalize = wrappers.get("normalize")
    if normalize is None or not normalize.get("norm_obs"):
        return n_stack, None
    try:
        rms = normalize["obs_rms"]
        mean, var = np.asarray(rms["mean"], dtype=np.float64), np.asarray(rms["var"],
                                                                           dtype=np.float64)
        numbers = [float(normalize[key]) for key in ("clip_obs", "epsilon")] + [
            float(rms["count"])]
    except (KeyError, TypeError, ValueError) as exc:
        raise ConfigError(f"{where}.normalize: incomplete or not numbers ({exc})") from None
    if mean.shape != shape or var.shape != shape or not (
            np.all(np.isfinite(mean)) and np.all(var >= 0) and all(np.isfinite(numbers))):
        raise ConfigError(f"{where}.normalize.obs_rms: expected finite mean and var >= 0 of "
                          f"shape {shape}, got shapes {mean.shape} and {var.shape}")
    return n_stack, normalize
