"""A saved JAX learner (``jax_ppo_seed<N>.zip``, ``jax_dqn_seed<N>.zip``) as a policy of the
evaluation (`baselines.policy.Policy`), beside the SB3 models of the same folder
(`bounce_gym_experiments.families.base.Family.trained_policies`).

It acts from the NumPy env's observation alone (never ``info``), flattened as in training
(`baselines.rl.jaxrl.networks.flatten_observation`). As `baselines.rl.policies.SB3Policy`, its
action is **sampled** by default with the generator restarted from the episode's seed
(`baselines.rl.action_draws`): jax_ppo draws from its categorical distribution, jax_dqn acts
ε-greedily at its ``exploration_final_eps``; ``deterministic=True`` gives the greedy action, the
row named with `baselines.rl.policies.GREEDY_SUFFIX`.
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

import jax
import numpy as np

from baselines.policy import Policy, is_parallel_env
from baselines.rl.action_draws import categorical, episode_stream, epsilon_draw
from baselines.rl.jaxrl import compile_cache, dqn, ppo
from baselines.rl.jaxrl.networks import (
    apply_mlp,
    flatten_observation,
    layer_shapes,
    named_layers,
    observation_size,
)
from baselines.rl.jaxrl.settings import activation, hyperparameters, net_arch
from baselines.rl.jaxrl.weights import read_weights, saved_config
from baselines.rl.model_files import read_model
from baselines.rl.policies import GREEDY_SUFFIX
from bounce_gym.errors import ConfigError

_SIZES = {"jax_ppo": ppo.actor_critic_sizes, "jax_dqn": dqn.q_network_sizes}
_HEADS = {"jax_ppo": "pi", "jax_dqn": "q"}


@partial(jax.jit, static_argnames="act")
def _forward(layers, x, act):
    return apply_mlp(layers, flatten_observation(x), act)


class JaxPolicy(Policy):
    """A jax_ppo or jax_dqn model file as a policy for the Gymnasium env ``env``."""

    def __init__(self, path: Path, env, deterministic: bool = False) -> None:
        if is_parallel_env(env):
            raise ConfigError(f"model {path}: a JAX learner acts in a single-robot env only")
        trained = read_model(path)
        if trained.algo not in _SIZES:
            raise ConfigError(f"model {path}: not a JAX learner's model")
        compile_cache.enable()  # its forward pass, compiled once per machine
        config = saved_config(trained)
        settings = hyperparameters(trained.algo, config["hyperparams"])
        n_actions = getattr(env.action_space, "n", None)
        if n_actions is None:
            raise ConfigError(f"model {path}: a JAX learner needs discrete actions, the env's "
                              f"are {env.action_space}")
        sizes = _SIZES[trained.algo](observation_size(env.observation_space), int(n_actions),
                                     net_arch(trained.algo, settings))
        head = _HEADS[trained.algo]
        shapes = {name: shape for net, s in sizes.items()
                  for name, shape in layer_shapes(net, s).items()}
        arrays = read_weights(trained, shapes)
        self.layers = named_layers(head, arrays, len(sizes[head]) - 1)
        self.activation = activation(trained.algo, settings)
        self.algo = trained.algo
        self.epsilon = settings.get("exploration_final_eps", 0.0)
        self.n_actions = int(n_actions)
        self.deterministic = deterministic
        self.rng: np.random.Generator | None = None
        self.name = f"rl {path.stem}{GREEDY_SUFFIX if deterministic else ''}"

    def start_options(self, env, seed: int) -> None:
        self.rng = episode_stream(seed)
        return None

    def act(self, observation, info):
        scores = np.asarray(_forward(self.layers, observation, self.activation), np.float64)
        if self.deterministic:
            return int(np.argmax(scores))
        if self.rng is None:
            raise RuntimeError(f"{self.name}: start_options(env, seed) starts an episode of a "
                               "sampling policy (baselines.policy.Policy)")
        if self.algo == "jax_dqn":
            return int(epsilon_draw(np.argmax(scores), self.epsilon, self.n_actions, self.rng))
        probs = np.exp(scores - scores.max())
        return int(categorical((probs / probs.sum())[None], self.rng)[0])
