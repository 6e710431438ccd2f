"""DQN (Mnih et al. 2015) on the vmapped JAX envs, with hindsight relabelling on a
goal-conditioned env (`baselines.rl.jaxrl.replay`).

It follows Stable-Baselines3's DQN step for step where it can: an iteration is ``train_freq``
steps of every env, then ``gradient_steps`` updates (−1: one per transition collected) once
more than ``learning_starts`` transitions were collected; actions are uniformly random before
``learning_starts``, then ε-greedy with ε decaying linearly from ``exploration_initial_eps`` to
``exploration_final_eps`` over the first ``exploration_fraction`` of the run; the target
network is moved towards the online one (Polyak, ``tau``; 1 copies it) every
``target_update_interval // n_envs`` vector steps; the loss is the Huber loss of the TD error
against r + γ·(1 − terminated)·max_a Q_target(s', a) (a truncated episode bootstraps), the
gradient clipped to ``max_grad_norm``, Adam. Two differences: ε-greedy draws explore per env
(SB3 draws once for the whole batch), and the Q-network is initialised orthogonally like the
PPO networks (SB3 keeps torch's default).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax

from baselines.rl.jaxrl import episodes, replay
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


class DQNState(NamedTuple):
    params: tuple
    target: tuple
    opt_state: tuple
    buffer: replay.Buffer
    env_state: object
    obs: object
    running: episodes.Running
    key: jax.Array
    iteration: jax.Array
    timesteps: jax.Array


def q_network_sizes(n_inputs: int, n_actions: int, arch: dict[str, list[int]]) -> dict:
    """The layer sizes of the Q-network (``q``)."""
    return {"q": [n_inputs, *arch["q"], n_actions]}


class DQN:
    """The learner of one validated configuration on the JAX env ``env`` with ``env_params``;
    ``settings`` are its hyperparameters (`baselines.rl.jaxrl.settings.hyperparameters`)."""

    algo = "jax_dqn"

    def __init__(self, env, env_params, settings: dict, n_envs: int, total_timesteps: int,
                 monitor_keys: tuple[str, ...]) -> None:
        self.env, self.env_params, self.settings = env, env_params, settings
        self.n_envs = n_envs
        self.total = total_timesteps
        space = env.action_space(env_params)
        if not hasattr(space, "n"):
            raise ConfigError(f"config.env: jax_dqn needs discrete actions, the env's are {space}")
        self.n_actions = int(space.n)
        observation_space = env.observation_space(env_params)
        self.goals = hasattr(observation_space, "spaces")
        her = settings["replay_buffer_kwargs"]
        if her and not self.goals:
            raise ConfigError("config.hyperparams.replay_buffer_class: hindsight relabelling "
                              "needs a goal-conditioned env (a Dict observation with goals)")
        self.her_ratio = 1.0 - 1.0 / (her["n_sampled_goal"] + 1) if her else 0.0
        self.horizon = int(env_params.max_steps_in_episode)
        self.capacity = settings["buffer_size"] // n_envs
        if self.capacity < self.horizon:
            raise ConfigError(f"config.hyperparams.buffer_size: jax_dqn keeps buffer_size // "
                              f"n_envs = {self.capacity} transitions per env, fewer than one "
                              f"episode of {self.horizon} steps")
        self.activation = activation(self.algo, settings)
        self.sizes = q_network_sizes(observation_size(observation_space), self.n_actions,
                                   net_arch(self.algo, settings))
        self.steps_per_iteration = settings["train_freq"] * n_envs
        self.iterations = -(-total_timesteps // self.steps_per_iteration)
        self.gradient_steps = (settings["gradient_steps"] if settings["gradient_steps"] >= 0
                               else self.steps_per_iteration)
        self.target_every = max(settings["target_update_interval"] // n_envs, 1)
        self.monitor_keys = monitor_keys
        self.rate, self.linear = learning_rate(settings)
        self.optimiser = optax.chain(optax.clip_by_global_norm(settings["max_grad_norm"]),
                                     optax.scale_by_adam())
        self._step = jax.vmap(env.step, in_axes=(0, 0, 0, None))
        self._reset = jax.vmap(env.reset, in_axes=(0, None))

    # -- state ------------------------------------------------------------------------------
    def init(self, key: jax.Array) -> DQNState:
        key, k_q, k_env = jax.random.split(key, 3)
        params = init_mlp(k_q, self.sizes["q"], 1.0)
        obs, env_state = self._reset(jax.random.split(k_env, self.n_envs), self.env_params)
        example = self._transition(obs, obs, jnp.zeros((self.n_envs,), jnp.int32),
                                   jnp.zeros((self.n_envs,), jnp.float32),
                                   jnp.zeros((self.n_envs,), bool))
        return DQNState(params, params, self.optimiser.init(params),
                        replay.create(example, self.capacity), env_state, obs,
                        episodes.start(self.n_envs), key, jnp.int32(0), jnp.int32(0))

    def steps(self, state: DQNState) -> int:
        return int(state.timesteps)

    def weights(self, state: DQNState) -> dict[str, np.ndarray]:
        return layer_names("q", state.params)

    def chunk(self, length: int):
        """The jitted ``state -> (state, records)`` of ``length`` iterations (`chunks`)."""
        return chunk_function(self._iterate, self.iterations, length)

    # -- collecting -------------------------------------------------------------------------
    def _transition(self, obs, next_obs, action, reward, terminated) -> dict:
        out = {"action": action, "reward": reward, "terminated": terminated}
        if not self.goals:
            return {**out, "observation": flatten_observation(obs),
                    "next_observation": flatten_observation(next_obs)}
        return {**out, "observation": obs["observation"],
                "achieved_goal": obs["achieved_goal"].astype(jnp.uint8),
                "desired_goal": obs["desired_goal"].astype(jnp.uint8),
                "next_observation": next_obs["observation"],
                "next_achieved_goal": next_obs["achieved_goal"].astype(jnp.uint8)}

    def _epsilon(self, timesteps):
        s = self.settings
        progress = timesteps.astype(jnp.float32) / self.total
        start, end = s["exploration_initial_eps"], s["exploration_final_eps"]
        if s["exploration_fraction"] == 0:
            return jnp.float32(end)
        return jnp.where(progress > s["exploration_fraction"], end,
                         start + progress * (end - start) / s["exploration_fraction"])

    def _collect(self, carry, _):
        params, target, buffer, env_state, obs, running, key, timesteps, calls = carry
        key, k_random, k_explore, k_step = jax.random.split(key, 4)
        greedy = jnp.argmax(apply_mlp(params, flatten_observation(obs), self.activation), -1)
        random = jax.random.randint(k_random, (self.n_envs,), 0, self.n_actions)
        explore = (jax.random.uniform(k_explore, (self.n_envs,)) < self._epsilon(timesteps)) | (
            timesteps < self.settings["learning_starts"])
        action = jnp.where(explore, random, greedy).astype(jnp.int32)
        next_obs, env_state, reward, done, info = self._step(
            jax.random.split(k_step, self.n_envs), env_state, action, self.env_params)
        running, record = episodes.track(running, reward, done, info, self.monitor_keys)
        buffer = replay.add(buffer, self._transition(obs, info["final_observation"], action,
                                                     reward, info["terminated"]),
                            done, self.horizon)
        calls = calls + 1
        tau = self.settings["tau"]
        target = jax.lax.cond(calls % self.target_every == 0,
                              lambda t: jax.tree.map(lambda p, q: tau * p + (1 - tau) * q,
                                                     params, t),
                              lambda t: t, target)
        return (params, target, buffer, env_state, next_obs, running, key,
                timesteps + self.n_envs, calls), record

    # -- learning ---------------------------------------------------------------------------
    def _batch(self, buffer: replay.Buffer, key: jax.Array):
        """``(x, action, reward, terminated, x_next)`` of a sampled mini-batch, relabelled."""
        k_sample, k_goal = jax.random.split(key)
        env, slot = replay.sample_transitions(buffer, k_sample, self.settings["batch_size"],
                                  self.her_ratio > 0)
        get = {k: v[env, slot] for k, v in buffer.data.items()}
        if not self.goals:
            return (get["observation"], get["action"], get["reward"], get["terminated"],
                    get["next_observation"])
        if self.her_ratio > 0:
            goal = replay.relabelled_goals(buffer, k_goal, env, slot, self.her_ratio)
        else:
            goal = get["desired_goal"].astype(jnp.float32)
        achieved = get["achieved_goal"].astype(jnp.float32)
        next_achieved = get["next_achieved_goal"].astype(jnp.float32)
        reward = self.env.task.compute_reward(next_achieved, goal, self.env_params.task)
        x = jnp.concatenate([get["observation"], achieved, goal], -1)
        x_next = jnp.concatenate([get["next_observation"], next_achieved, goal], -1)
        return x, get["action"], reward, get["terminated"], x_next

    def _loss(self, params, target, batch):
        x, action, reward, terminated, x_next = batch
        best_next = apply_mlp(target, x_next, self.activation).max(-1)
        goal = reward + self.settings["gamma"] * (1.0 - terminated.astype(jnp.float32)) * \
            jax.lax.stop_gradient(best_next)
        q = jnp.take_along_axis(apply_mlp(params, x, self.activation), action[:, None], 1)[:, 0]
        return optax.huber_loss(q, goal, delta=1.0).mean()

    def _learn(self, carry):
        params, target, opt_state, buffer, key, timesteps = carry
        progress = timesteps.astype(jnp.float32) / self.total
        rate = self.rate * jnp.maximum(1.0 - progress, 0.0) if self.linear else self.rate

        def update(inner, k):
            params, opt_state = inner
            grads = jax.grad(self._loss)(params, target, self._batch(buffer, k))
            updates, opt_state = self.optimiser.update(grads, opt_state, params)
            return (jax.tree.map(lambda p, u: p - rate * u, params, updates), opt_state), None

        key, k_updates = jax.random.split(key)
        (params, opt_state), _ = jax.lax.scan(
            update, (params, opt_state), jax.random.split(k_updates, self.gradient_steps))
        return params, target, opt_state, buffer, key, timesteps

    def _iterate(self, state: DQNState):
        calls = state.iteration * self.settings["train_freq"]
        carry = (state.params, state.target, state.buffer, state.env_state, state.obs,
                 state.running, state.key, state.timesteps, calls)
        carry, records = jax.lax.scan(self._collect, carry, None, self.settings["train_freq"])
        params, target, buffer, env_state, obs, running, key, timesteps, _ = carry
        learn = (timesteps > self.settings["learning_starts"]) & (self.gradient_steps > 0) & \
            replay.ready(buffer, self.her_ratio > 0)
        params, target, opt_state, buffer, key, timesteps = jax.lax.cond(
            learn, self._learn, lambda c: c,
            (params, target, state.opt_state, buffer, key, timesteps))
        return DQNState(params, target, opt_state, buffer, env_state, obs, running, key,
                        state.iteration + 1, timesteps), records
