"""PPO with the clipped surrogate objective (Schulman et al. 2017, Eq. 7 and 9), written in the
style of PureJaxRL (Lu et al. 2022): the ``n_envs`` envs vmapped, a rollout of ``n_steps`` a
``lax.scan``, generalized advantage estimation (Schulman et al. 2016, Eq. 16), ``n_epochs``
passes over shuffled mini-batches, all one jitted iteration.

It follows Stable-Baselines3's PPO where the two could differ: separate policy and value MLPs
(orthogonal initialisation, gains √2, 0.01 for the action head, 1 for the value head), the
advantages normalised per mini-batch, an unclipped value loss weighted by ``vf_coef``, the
entropy bonus ``ent_coef``, the gradient clipped to ``max_grad_norm`` (global norm), Adam with
ε = 1e-5, a ``lin_`` learning rate decayed once per rollout, and a truncated episode's reward
increased by γ·V(its last observation) (the episode is cut, not ended). Discrete actions only.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax

from baselines.rl.jaxrl import episodes
from baselines.rl.jaxrl.chunks import chunk_function
from baselines.rl.jaxrl.networks import (
    apply_mlp,
    flatten_observation,
    init_mlp,
    layer_names,
    observation_size,
)
from baselines.rl.jaxrl.settings import activation, learning_rate, net_arch
from bounce_gym.errors import ConfigError


class PPOState(NamedTuple):
    params: dict
    opt_state: tuple
    env_state: object
    obs: object
    running: episodes.Running
    key: jax.Array
    iteration: jax.Array


class Transition(NamedTuple):
    x: jax.Array
    action: jax.Array
    log_prob: jax.Array
    reward: jax.Array
    done: jax.Array
    cut: jax.Array  # truncated, not terminated: the reward gets γ·V(final)
    final_x: jax.Array


def actor_critic_sizes(n_inputs: int, n_actions: int, arch: dict[str, list[int]]) -> dict:
    """The layer sizes of the policy (``pi``) and value (``vf``) MLPs."""
    return {"pi": [n_inputs, *arch["pi"], n_actions], "vf": [n_inputs, *arch["vf"], 1]}


def policy_logits(params: dict, x: jax.Array, act: str) -> jax.Array:
    return apply_mlp(params["pi"], x, act)


class PPO:
    """The learner of one validated configuration on the JAX env ``env`` with ``env_params``;
    ``settings`` are its hyperparameters (`baselines.rl.jaxrl.settings.hyperparameters`)."""

    algo = "jax_ppo"

    def __init__(self, env, env_params, settings: dict, n_envs: int, total_timesteps: int,
                 monitor_keys: tuple[str, ...]) -> None:
        self.env, self.env_params, self.settings = env, env_params, settings
        self.n_envs = n_envs
        self.n_steps = settings["n_steps"]
        self.steps_per_iteration = self.n_steps * n_envs
        if self.steps_per_iteration % settings["batch_size"]:
            raise ConfigError(f"config.hyperparams.batch_size: jax_ppo splits each rollout of "
                              f"n_steps x n_envs = {self.steps_per_iteration} transitions into "
                              f"whole mini-batches; {settings['batch_size']} does not divide it")
        space = env.action_space(env_params)
        if not hasattr(space, "n"):
            raise ConfigError(f"config.env: jax_ppo needs discrete actions, the env's are {space}")
        self.n_actions = int(space.n)
        self.activation = activation(self.algo, settings)
        self.sizes = actor_critic_sizes(observation_size(env.observation_space(env_params)),
                                   self.n_actions, net_arch(self.algo, settings))
        self.iterations = -(-total_timesteps // self.steps_per_iteration)
        self.monitor_keys = monitor_keys
        self.rate, self.linear = learning_rate(settings)
        self.optimiser = optax.chain(optax.clip_by_global_norm(settings["max_grad_norm"]),
                                     optax.scale_by_adam(eps=1e-5))
        self._step = jax.vmap(env.step, in_axes=(0, 0, 0, None))
        self._reset = jax.vmap(env.reset, in_axes=(0, None))

    # -- state ------------------------------------------------------------------------------
    def init(self, key: jax.Array) -> PPOState:
        key, k_pi, k_vf, k_env = jax.random.split(key, 4)
        params = {"pi": init_mlp(k_pi, self.sizes["pi"], 0.01),
                  "vf": init_mlp(k_vf, self.sizes["vf"], 1.0)}
        obs, env_state = self._reset(jax.random.split(k_env, self.n_envs), self.env_params)
        return PPOState(params, self.optimiser.init(params), env_state, obs,
                        episodes.start(self.n_envs), key, jnp.int32(0))

    def steps(self, state: PPOState) -> int:
        return int(state.iteration) * self.steps_per_iteration

    def weights(self, state: PPOState) -> dict[str, np.ndarray]:
        return {**layer_names("pi", state.params["pi"]), **layer_names("vf", state.params["vf"])}

    def chunk(self, length: int):
        """The jitted ``state -> (state, records)`` of ``length`` iterations (`chunks`)."""
        return chunk_function(self._iterate, self.iterations, length)

    # -- one iteration ----------------------------------------------------------------------
    def _value(self, params, x):
        return apply_mlp(params["vf"], x, self.activation)[..., 0]

    def _rollout_step(self, carry, _):
        params, env_state, obs, running, key = carry
        key, k_act, k_step = jax.random.split(key, 3)
        x = flatten_observation(obs)
        logits = policy_logits(params, x, self.activation)
        action = jax.random.categorical(k_act, logits)
        log_prob = jnp.take_along_axis(jax.nn.log_softmax(logits), action[:, None], 1)[:, 0]
        obs, env_state, reward, done, info = self._step(
            jax.random.split(k_step, self.n_envs), env_state, action, self.env_params)
        running, record = episodes.track(running, reward, done, info, self.monitor_keys)
        cut = info["truncated"] & ~info["terminated"]
        transition = Transition(x, action, log_prob, reward, done, cut,
                                flatten_observation(info["final_observation"]))
        return (params, env_state, obs, running, key), (transition, record)

    def _advantages(self, params, batch: Transition, last_value: jax.Array):
        """Advantages and returns of a rollout, its values computed in one batch after it (a
        truncated episode's reward raised by γ·V of its last observation)."""
        gamma, lam = self.settings["gamma"], self.settings["gae_lambda"]
        values = self._value(params, batch.x)
        rewards = batch.reward + gamma * jnp.where(batch.cut, self._value(params, batch.final_x),
                                                   0.0)

        def back(carry, t):
            gae, next_value = carry
            reward, value, done = t
            live = 1.0 - done.astype(jnp.float32)
            delta = reward + gamma * next_value * live - value
            gae = delta + gamma * lam * live * gae
            return (gae, value), gae

        _, advantages = jax.lax.scan(back, (jnp.zeros_like(last_value), last_value),
                                     (rewards, values, batch.done), reverse=True)
        return advantages, advantages + values

    def _loss(self, params, batch: tuple, advantages, returns):
        s = self.settings
        x, action, old_log_prob = batch
        logits = policy_logits(params, x, self.activation)
        log_probs = jax.nn.log_softmax(logits)
        log_prob = jnp.take_along_axis(log_probs, action[:, None], 1)[:, 0]
        adv = (advantages - advantages.mean()) / (advantages.std(ddof=1) + 1e-8)
        ratio = jnp.exp(log_prob - old_log_prob)
        clipped = jnp.clip(ratio, 1.0 - s["clip_range"], 1.0 + s["clip_range"])
        policy_loss = -jnp.minimum(adv * ratio, adv * clipped).mean()
        value_loss = ((returns - self._value(params, x)) ** 2).mean()
        entropy = -(jnp.exp(log_probs) * log_probs).sum(-1).mean()
        return policy_loss - s["ent_coef"] * entropy + s["vf_coef"] * value_loss

    def _iterate(self, state: PPOState):
        s = self.settings
        carry = (state.params, state.env_state, state.obs, state.running, state.key)
        carry, (batch, records) = jax.lax.scan(self._rollout_step, carry, None, self.n_steps)
        params, env_state, obs, running, key = carry
        advantages, returns = self._advantages(
            params, batch, self._value(params, flatten_observation(obs)))
        total = self.steps_per_iteration
        flat = jax.tree.map(lambda a: a.reshape((total, *a.shape[2:])),
                            ((batch.x, batch.action, batch.log_prob), advantages, returns))
        n_batches = total // s["batch_size"]
        progress = state.iteration.astype(jnp.float32) / self.iterations
        rate = self.rate * (1.0 - progress) if self.linear else self.rate
        grad = jax.grad(self._loss)

        def minibatch(carry, part):
            params, opt_state = carry
            updates, opt_state = self.optimiser.update(grad(params, *part), opt_state, params)
            params = jax.tree.map(lambda p, u: p - rate * u, params, updates)
            return (params, opt_state), None

        def epoch(carry, k):
            order = jax.random.permutation(k, total)
            parts = jax.tree.map(
                lambda a: a[order].reshape((n_batches, s["batch_size"], *a.shape[1:])), flat)
            return jax.lax.scan(minibatch, carry, parts)[0], None

        key, k_epochs = jax.random.split(key)
        (params, opt_state), _ = jax.lax.scan(epoch, (params, state.opt_state),
                                              jax.random.split(k_epochs, s["n_epochs"]))
        return PPOState(params, opt_state, env_state, obs, running, key,
                        state.iteration + 1), records
