"""The hyperparameters of the multi-robot learners (``algo: ippo | mappo``): their names,
defaults and ranges, declared once in `Settings` and checked before anything is built (no torch
import here). Every mistake is a one-line `ConfigError` naming the key
(``config.hyperparams.<key>``).

The budget, ``total_timesteps``, counts **agent-steps** (every robot's step is one, as the
shared SB3 PPO of a multi-robot env counts them: a step of B teams of m robots is B·m); an
iteration collects ``n_steps`` steps of the ``n_envs`` teams (B) and learns from them for
``n_epochs`` passes, each split into ``n_minibatches`` mini-batches of team-steps (every robot
of a team-step in the same mini-batch).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, Literal

from pydantic import Field

from baselines.config_model import ConfigModel
from bounce_gym.errors import ConfigError

#: Most hidden layers of a network, and units per layer.
MAX_LAYERS = 16
MAX_WIDTH = 4096
#: The activations of the hidden layers (torch.nn's Tanh and ReLU).
ACTIVATIONS = ("tanh", "relu")
#: The model-file variant of each sharing choice (``<algo>-<variant>_seed<N>.zip``), when the
#: configuration names none.
SHARING_VARIANTS = {True: "shared", False: "separate"}

_Width = Annotated[int, Field(ge=1, le=MAX_WIDTH)]


class Settings(ConfigModel):
    """The hyperparameters of ``ippo`` and ``mappo`` (``hyperparams`` of a training
    configuration); each key's default is its value when the configuration and the
    hyperparameter file leave it out."""

    share: bool = Field(default=True, description="One actor and one critic for every robot "
                                                  "(parameter sharing); false: a pair per "
                                                  "robot.")
    learning_rate: float = Field(default=3e-4, gt=0, le=1, description="Adam's step size.")
    n_steps: int = Field(default=128, ge=1, le=10**5, description="Steps of every team per "
                                                                  "rollout.")
    n_epochs: int = Field(default=5, ge=1, le=100, description="Passes over each rollout.")
    n_minibatches: int = Field(default=4, ge=1, le=1024,
                               description="Mini-batches per pass (of team-steps).")
    gamma: float = Field(default=0.99, gt=0, le=1, description="Discount per step.")
    gae_lambda: float = Field(default=0.95, ge=0, le=1, description="GAE's λ.")
    clip_range: float = Field(default=0.2, gt=0, le=10, description="PPO's clip of the "
                                                                     "probability ratio.")
    ent_coef: float = Field(default=0.01, ge=0, le=100, description="Weight of the entropy "
                                                                    "bonus.")
    vf_coef: float = Field(default=0.5, ge=0, le=100, description="Weight of the value loss.")
    max_grad_norm: float = Field(default=0.5, gt=0, le=1e6,
                                 description="Clip of the gradient's norm, per robot's "
                                             "networks (all of them when shared).")
    actor_layers: list[_Width] = Field(default_factory=lambda: [64, 64], max_length=MAX_LAYERS,
                                       description="The actor's hidden layer sizes.")
    critic_layers: list[_Width] = Field(default_factory=lambda: [64, 64],
                                        max_length=MAX_LAYERS,
                                        description="The critic's hidden layer sizes.")
    activation: Literal[ACTIVATIONS] = Field(  # type: ignore[valid-type]
        default="tanh", description="The hidden layers' activation.")


def settings(hyperparams: Mapping, n_envs: int) -> Settings:
    """The checked hyperparameters of a configuration with ``n_envs`` teams: a `ConfigError`
    naming the first key that is unknown, of the wrong type or out of range."""
    out = Settings.check(hyperparams, "config.hyperparams")
    team_steps = out.n_steps * n_envs
    if out.n_minibatches > team_steps:
        raise ConfigError(f"config.hyperparams.n_minibatches: {out.n_minibatches} mini-batches "
                          f"of a rollout of n_steps x n_envs = {team_steps} team-steps would "
                          "leave some empty")
    return out


def default_variant(hyperparams: Mapping) -> str:
    """The model files' variant when the configuration names none: ``shared`` or
    ``separate``."""
    return SHARING_VARIANTS[bool(hyperparams.get("share", Settings.model_fields["share"].default))]
