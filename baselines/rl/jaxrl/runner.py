"""The host loop of one seed of a JAX learner (``algo: jax_ppo | jax_dqn``): the learner built
on ``bounce_gym.jax.make(env, **env_kwargs)``, its state from ``jax.random.PRNGKey(seed)``
(same configuration and seed: the same weights, bit for bit, on the same machine and JAX), then
chunks of iterations (`CHUNK_STEPS` env steps or fewer, one compiled function); after each the
host appends the episodes that ended in it to the monitor file (`baselines.rl.monitor`, in the
order a VecMonitor writes them: by step, then env; ``t`` is the time the chunk ended) and saves
a checkpoint once a multiple of ``checkpoint_every`` steps is passed. At the end: a last
checkpoint, and the model file (`baselines.rl.jaxrl.weights`).

Checkpoints hold weights only, so a JAX run is not resumed (``resume: true`` is refused by
`baselines.rl.train_config`): its state — optimiser moments, random key, the envs mid-episode
and, for jax_dqn, the replay buffer of up to ``buffer_size`` transitions — lives on the device.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import jax
import numpy as np

from baselines.rl.jaxrl import compile_cache
from baselines.rl.jaxrl.settings import hyperparameters
from baselines.rl.jaxrl.weights import WeightsArchive
from baselines.rl.model_files import save_model
from baselines.rl.monitor import open_monitor_file
from baselines.rl.train_env import MONITOR_KEYS
from bounce_gym.errors import ConfigError
from bounce_gym.provenance import provenance

#: The most env steps of one chunk (iterations are whole; at least one per chunk).
CHUNK_STEPS = 16384
#: The learner and jitted chunk of the configuration trained last in this process, by the
#: configuration less its seeds (`shared_learner`).
_SHARED: dict[str, tuple] = {}


def jax_env(config: dict):
    """``(env, params)`` of the configuration's env in JAX; a `ConfigError` for one without."""
    from bounce_gym.jax import make

    try:
        return make(config["env"], **config["env_kwargs"])
    except ConfigError as exc:
        raise ConfigError(f"config.env: {exc}") from None


def learner(config: dict):
    """The learner of a validated configuration (its checks done: nothing compiled yet; what
    it compiles is kept in the persistent compilation cache, `compile_cache`)."""
    from baselines.rl.jaxrl.dqn import DQN
    from baselines.rl.jaxrl.ppo import PPO

    compile_cache.enable()

    env, params = jax_env(config)
    info = jax.eval_shape(env.step, jax.random.PRNGKey(0), env.reset(
        jax.random.PRNGKey(0), params)[1], 0, params)[4]
    keys = tuple(k for k in MONITOR_KEYS if k in info)
    kind = {"jax_ppo": PPO, "jax_dqn": DQN}[config["algo"]]
    return kind(env, params, hyperparameters(config["algo"], config["hyperparams"]),
                config["n_envs"], config["total_timesteps"], keys)


def shared_learner(config: dict) -> tuple:
    """``(learner, chunk)`` of a validated configuration: its check before training
    (`baselines.rl.train.prepare`) and the seeds of a sweep trained one after another in this
    process share them, so that the learner is built and the chunk traced and compiled once,
    not once per seed (a seed's state is its own: the same weights either way; the chunk is
    compiled at its first call). Only the last configuration's are kept."""
    key = json.dumps({k: v for k, v in config.items() if k != "seeds"}, sort_keys=True)
    if key not in _SHARED:
        _SHARED.clear()
        agent = learner(config)
        _SHARED[key] = agent, agent.chunk(chunk_length(agent, config))
    return _SHARED[key]


def chunk_length(agent, config: dict) -> int:
    """Iterations per chunk: at most `CHUNK_STEPS` env steps (one iteration at least) and at
    most ``checkpoint_every`` rounded up to whole iterations, so that a checkpoint is saved at
    the end of the first chunk at or past each multiple of it."""
    every = config["checkpoint_every"]
    length = max(1, CHUNK_STEPS // agent.steps_per_iteration)
    if every:
        length = min(length, -(-every // agent.steps_per_iteration))
    return min(agent.iterations, length)


def write_rows(writer, records: dict, keys: tuple[str, ...], seconds: float) -> int:
    """Append a row per episode that ended in the chunk's ``records`` ((iterations, steps,
    n_envs) arrays); returns how many."""
    records = {k: np.asarray(v).reshape((-1, np.shape(v)[-1])) for k, v in records.items()}
    steps, envs = np.nonzero(records["done"])
    for t, e in zip(steps, envs, strict=True):
        writer.write_row({"r": round(float(records["r"][t, e]), 6),
                          "l": int(records["l"][t, e]), "t": round(seconds, 6),
                          **{k: records[k][t, e].item() for k in keys}})
    return len(steps)


def train_run(run, log, progress: bool = False) -> Path:
    """Train the seed of ``run`` (a `baselines.rl.train.RunFiles`); returns the model path.
    With ``progress``, ``log`` also gets a line after each chunk: the steps done and the
    seconds since the start (compiling included)."""
    config = run.config
    agent, chunk = shared_learner(config)
    state = agent.init(jax.random.PRNGKey(run.seed))
    every = config["checkpoint_every"]
    due = every

    made = provenance()

    def metadata() -> dict:
        return {"config": config, "jax": {"num_timesteps": agent.steps(state)},
                "trained_with": made}

    def save_checkpoint() -> None:
        run.check_links()
        save_model(WeightsArchive(agent.weights(state)), run.checkpoint(agent.steps(state)),
                   metadata(), overwrite=False)

    log(f"{run.stem}: training {config['total_timesteps']} steps ({config['algo']})")
    start = time.time()
    writer = open_monitor_file(run.monitor, start, config["env"], agent.monitor_keys)
    try:
        while int(state.iteration) < agent.iterations:
            state, records = chunk(state)
            write_rows(writer, records, agent.monitor_keys, time.time() - start)
            if progress:
                log(f"{run.stem}: {agent.steps(state)} of {config['total_timesteps']} steps, "
                    f"{time.time() - start:.0f} s")
            if every and agent.steps(state) >= due:
                save_checkpoint()
                due = (agent.steps(state) // every + 1) * every
    finally:
        writer.close()
    if agent.steps(state) not in run.checkpoints():
        save_checkpoint()
    save_model(WeightsArchive(agent.weights(state)), run.model, metadata())
    return run.model
