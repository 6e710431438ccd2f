"""The hyperparameters of the JAX learners: the keys each reads (Stable-Baselines3's names and
defaults, so a hyperparameter file entry of SB3's PPO or DQN trains its JAX twin), checked
before anything is built.

`baselines.rl.train_config` checks every number's range; here a key the learner does not use
is a `ConfigError` (one line naming it), as is a value it cannot honour: a ``lin_`` schedule of
anything but ``learning_rate``, a relabelling strategy other than ``future``. No JAX import:
configurations are checked before any learner is compiled.
"""

from __future__ import annotations

import copy
import re
from collections.abc import Mapping

from bounce_gym.errors import ConfigError

#: jax_ppo: SB3 PPO's defaults of the hyperparameters it reads.
PPO_DEFAULTS = {"learning_rate": 3e-4, "n_steps": 2048, "batch_size": 64, "n_epochs": 10,
                "gamma": 0.99, "gae_lambda": 0.95, "clip_range": 0.2, "ent_coef": 0.0,
                "vf_coef": 0.5, "max_grad_norm": 0.5, "policy_kwargs": {}}
#: jax_dqn: SB3 DQN's defaults of the hyperparameters it reads (``replay_buffer_class``:
#: None, or ``HerReplayBuffer`` for hindsight relabelling).
DQN_DEFAULTS = {"learning_rate": 1e-4, "buffer_size": 1_000_000, "learning_starts": 100,
                "batch_size": 32, "tau": 1.0, "gamma": 0.99, "train_freq": 4,
                "gradient_steps": 1, "target_update_interval": 10000,
                "exploration_fraction": 0.1, "exploration_initial_eps": 1.0,
                "exploration_final_eps": 0.05, "max_grad_norm": 10.0, "policy_kwargs": {},
                "replay_buffer_class": None, "replay_buffer_kwargs": {}}
DEFAULTS = {"jax_ppo": PPO_DEFAULTS, "jax_dqn": DQN_DEFAULTS}
#: SB3's default activation of each learner's networks.
ACTIVATION = {"jax_ppo": "tanh", "jax_dqn": "relu"}
#: SB3's default hidden layers of each learner's networks.
NET_ARCH = {"jax_ppo": [64, 64], "jax_dqn": [64, 64]}
#: ``policy_kwargs`` keys the JAX networks read.
POLICY_KEYS = ("net_arch", "activation_fn")
#: The relabelling of ``HerReplayBuffer`` the JAX DQN implements.
HER_DEFAULTS = {"n_sampled_goal": 4, "goal_selection_strategy": "future"}
_LINEAR = re.compile(r"lin_(.+)")


def hyperparameters(algo: str, given: Mapping) -> dict:
    """The hyperparameters of JAX learner ``algo``: SB3's defaults (`DEFAULTS`) overridden by
    ``given`` (already range-checked by `baselines.rl.train_config`); a `ConfigError` naming
    the first key it does not read or cannot honour."""
    defaults = DEFAULTS[algo]
    field = "config.hyperparams"
    for key, value in given.items():
        if key not in defaults:
            raise ConfigError(f"{field}.{key}: not a hyperparameter of {algo}; it reads "
                              f"{sorted(defaults)}")
        if isinstance(value, str) and key != "replay_buffer_class" and (
                key != "learning_rate" or not _LINEAR.fullmatch(value)):
            raise ConfigError(f"{field}.{key}: {algo} takes a number here (a lin_ schedule only "
                              f"for learning_rate), got {value!r}")
        if isinstance(value, bool) or (isinstance(defaults[key], (int, float))
                                       and not isinstance(value, (int, float, str))):
            raise ConfigError(f"{field}.{key}: expected a number, got {value!r}")
    out = {**copy.deepcopy(defaults), **copy.deepcopy(dict(given))}
    _check_policy_kwargs(algo, out["policy_kwargs"])
    if algo == "jax_dqn":
        out["replay_buffer_kwargs"] = _her(out)
    return out


def _check_policy_kwargs(algo: str, policy_kwargs: Mapping) -> None:
    unknown = sorted(set(policy_kwargs) - set(POLICY_KEYS))
    if unknown:
        raise ConfigError(f"config.hyperparams.policy_kwargs.{unknown[0]}: not read by {algo}; "
                          f"it reads {list(POLICY_KEYS)}")
    arch = policy_kwargs.get("net_arch")
    if isinstance(arch, dict) and (algo != "jax_ppo" or set(arch) - {"pi", "vf"}):
        raise ConfigError(f"config.hyperparams.policy_kwargs.net_arch: {algo} takes "
                          + ("a list of layer sizes, or {pi: [...], vf: [...]}"
                             if algo == "jax_ppo" else "a list of layer sizes"))


def _her(settings: Mapping) -> dict:
    """The relabelling settings of a jax_dqn (``{}``: none)."""
    name = settings["replay_buffer_class"]
    kwargs = settings["replay_buffer_kwargs"] or {}
    if name is None:
        return {}
    if name != "HerReplayBuffer":
        raise ConfigError(f"config.hyperparams.replay_buffer_class: jax_dqn relabels with "
                          f"HerReplayBuffer (or none), got {name!r}")
    out = {**HER_DEFAULTS, **kwargs}
    if out["goal_selection_strategy"] != "future":
        raise ConfigError("config.hyperparams.replay_buffer_kwargs.goal_selection_strategy: "
                          "jax_dqn relabels with future goals only, got "
                          f"{out['goal_selection_strategy']!r}")
    out.pop("copy_info_dict", None)  # nothing is copied: the goals are in the observation
    return out


def net_arch(algo: str, settings: Mapping) -> dict[str, list[int]]:
    """The hidden layers of each network: ``pi`` and ``vf`` (jax_ppo) or ``q`` (jax_dqn)."""
    arch = settings["policy_kwargs"].get("net_arch", NET_ARCH[algo])
    if algo == "jax_dqn":
        return {"q": list(arch)}
    if isinstance(arch, dict):
        return {"pi": list(arch.get("pi", [])), "vf": list(arch.get("vf", []))}
    return {"pi": list(arch), "vf": list(arch)}


def activation(algo: str, settings: Mapping) -> str:
    """The activation name of the learner's networks (`ACTIVATION` by default)."""
    return settings["policy_kwargs"].get("activation_fn", ACTIVATION[algo])


def learning_rate(settings: Mapping) -> tuple[float, bool]:
    """``(rate, linear)``: the initial learning rate, and whether it decays linearly to 0 over
    the run (``lin_<x>``)."""
    value = settings["learning_rate"]
    if isinstance(value, str):
        return float(_LINEAR.fullmatch(value).group(1)), True
    return float(value), False
