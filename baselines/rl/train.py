"""Reinforcement-learning baselines: Stable-Baselines3 agents trained on the bounce_gym envs.

A training configuration (YAML, see ``configs/train_*.yaml``; read by `bounce_gym.documents`,
checked by `baselines.rl.train_config`, whose docstring gives every number's range)::

    name: navigation-lab             # the evaluation experiment the models are for
    env: bounce_gym/BounceNavigation-v0
    role: patrollers                 # only for bounce_gym/Patrol-v0: the side that learns,
                                     # patrollers | adversary (`baselines.rl.patrol`)
    env_kwargs: {backend: cell, angles: [45, 90, 135]}
    algo: ppo                        # ppo | dqn | recurrentppo (sb3-contrib; memory for a robot
                                     # that senses only contact and time) | jax_ppo | jax_dqn
                                     # (trained in JAX, `baselines.rl.jaxrl`) | ippo | mappo
                                     # (several robots, `baselines.rl.marl`)
    variant: stack4                  # optional: files ppo-stack4_seed<N>.zip (several variants
                                     # of one algorithm side by side in models/<name>/)
    hyperparams_file: hyperparams/ppo.yaml  # optional, rl-zoo style, keyed by env id; relative
                                     # to this file's folder
    total_timesteps: 200000          # per seed (default: the file's n_timesteps), 1..10**10
    seeds: [0, 1, 2, 3, 4]           # or seed: 0; env i of seed s is seeded with s + i < 9000
    n_envs: 8                        # parallel episodes (default 4; DQN and multi-robot 1),
                                     # 1..1024
    n_stack: 1                       # frame stacking (VecFrameStack) when > 1, 1..100
    normalize: false                 # VecNormalize: true, or {norm_obs, norm_reward, clip_obs,
                                     # clip_reward}
    vec_env: native                  # native | sync | subproc (see below)
    hyperparams: {learning_rate: 0.0003}   # over the file's; lin_<x>: linear decay from x;
                                     # ranges: train_config.HYPERPARAM_RANGES (gamma in (0, 1])
    checkpoint_every: 50000          # env steps between checkpoints (0: only the final one)
    tensorboard: false               # logs in models/<name>/tensorboard (pip install
                                     # bounce-gym[tensorboard])
    models: models
    torch_threads: 1                 # torch intra-op threads while training (default 1), at
                                     # most 4 x the machine's cores
    executor: {kind: local, workers: 2}  # where the seeds run at once (`bounce-gym train`,
                                     # bounce_gym_experiments.training; default: a process per core)

**What a run writes** into ``<models>/<name>/`` for each seed: the model
``<run>_seed<seed>.zip`` (``<run>`` = ``<algo>[-<variant>]``), where the evaluation finds it;
checkpoints ``checkpoints/<run>_seed<seed>_<steps>_steps.zip`` (every ``checkpoint_every`` steps,
at the start of an iteration, and at the end), never overwritten; the per-episode monitor file
``<run>_seed<seed>.monitor.csv`` (`baselines.rl.monitor`), from which ``bounce-gym train`` and
``bounce-gym curves`` draw the learning curves (`baselines.rl.curves`). A symbolic link at the
monitor file's name, or at ``checkpoints`` (``tensorboard``), is a `ConfigError` before any
training: nothing is written through one. Model files are written atomically and recorded with
their sha256 in the folder's ``manifest.json``, against damage (`baselines.rl.model_files`);
each carries its configuration and the wrappers the evaluation must rebuild (frame stack,
VecNormalize statistics; `baselines.rl.wrappers`), and is loaded as data, nothing in it
unpickled (`baselines.rl.model_load`).

**Resuming** (``resume: true``, ``--resume``) continues every seed from its newest checkpoint —
weights, optimiser, step count, random streams and the envs mid-episode (`baselines.rl.resume`)
— up to ``total_timesteps``, with the monitor file cut back to the checkpoint: the result is the
run that was never interrupted. The state besides the weights is a pickle, signed with the
user's key (`bounce_gym.trust`) when the checkpoint is saved; a checkpoint whose signature does
not check (one copied from another user or machine) is resumed only once trusted with
``bounce-gym trust FILE`` (``docs/model_files.md``). A seed without a checkpoint starts afresh;
a configuration that differs from the checkpoint's (other than budget, checkpoint interval and
logging) or no checkpoint for any seed is a `ConfigError`. Without ``resume`` a seed with
checkpoints is a `ConfigError` too: nothing is overwritten. Same configuration and seed, same
weights, bit for bit (torch on the CPU).

**JAX learners.** ``algo: jax_ppo`` and ``algo: jax_dqn`` (`baselines.rl.jaxrl`) train on the
functional env ``bounce_gym.jax.make(env, **env_kwargs)`` (a `ConfigError` where it has none)
with the hyperparameter keys of SB3's PPO and DQN (a key they do not read is a `ConfigError`);
they write the same model, checkpoint and monitor files, weights only (an ``.npz``). They take
no ``vec_env``, ``n_stack``, ``normalize`` or ``tensorboard``, and cannot resume: their
checkpoints hold the weights, not the optimiser, key, envs and replay buffer that live on the
device, so ``resume: true`` is a `ConfigError` (`baselines.rl.jaxrl.runner`).

**Batched episodes.** ``vec_env: native`` (the default for ids with a Gymnasium
``vector_entry_point``: free, navigation, coverage) steps the ``n_envs`` episodes as one batch
(`baselines.rl.train_env`); it runs the same episodes as ``sync`` (SB3's DummyVecEnv of
``gym.make`` copies, the default for the other ids), only faster. ``subproc`` runs the copies in
SB3's SubprocVecEnv. Options the batch cannot run (``step_mode: tick``, the pymunk backend,
noise) raise `ConfigError` with ``native``: choose ``sync`` for them.

**Several robots.** With a PettingZoo id (``bounce_gym/MultiBounceCoverage-v0``, …) and
``algo: ppo`` the robots share one policy (parameter sharing): the parallel env becomes one SB3
VecEnv with a slot per robot (`baselines.rl.parallel_vec_env.ParallelToVecEnv`), so ``n_envs``
must stay 1 and there is no frame stack or VecNormalize; ``env_kwargs`` may set ``max_cycles``
(the episode length; see ``configs/train_multirobot_coverage.yaml``). The
evaluation runs the saved model as one policy for every robot
(`baselines.rl.policies.SharedSB3Policy`); ``rl_models: <name>`` lets several evaluation
experiments (e.g. m = 2..5) use it.

**Multi-robot learners.** ``algo: ippo`` and ``algo: mappo`` (`baselines.rl.marl`, torch)
train the robots of a bouncing-robot PettingZoo id on ``n_envs`` teams of the batched team env
(`bounce_gym.envs.team_vector_env.TeamVectorEnv`): IPPO's critics see each robot's own
observation, MAPPO's the global state; ``hyperparams.share`` (default true) gives every robot
the same actor and critic, false a pair each (`baselines.rl.marl.settings` lists the keys and
ranges). ``total_timesteps`` counts agent-steps; the files are named
``<algo>-shared_seed<N>.zip`` or ``<algo>-separate_seed<N>.zip`` unless ``variant`` says
otherwise, weights only (an ``.npz``), with the same checkpoint and monitor files (a row per
robot and episode). No ``tensorboard``, no ``resume``. The evaluation plays them with
`baselines.rl.marl.policy.TeamPolicy`, every robot from its own observation.

**The patrol game.** ``bounce_gym/Patrol-v0`` has two sides, so its configurations say which one
learns (``role``) and the other is played inside the env (`baselines.rl.patrol`): the patrollers
train like the robots above (one shared policy, a slot each), the adversary like a single-robot
env (``n_envs`` copies); their hyperparameter entries are keyed ``<env id>:<role>``. The
evaluation loads them with `baselines.rl.policies.patrol_policy`.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.rl.model_files import JAX_ALGOS, MARL_ALGOS, read_model, run_name, save_model
from baselines.rl.monitor import SUFFIX
from baselines.rl.patrol import training_callbacks
from baselines.rl.train_config import (
    algo_class,
    algo_kwargs,
    check_hyperparams,
    policy_name,
    validate_train_config,
)
from baselines.rl.train_env import attach_monitor_file, make_train_env
from bounce_gym.errors import ConfigError
from bounce_gym.extras import require
from bounce_gym.files import check_writable, refuse_links

__all__ = ["RunFiles", "finished", "make_train_env", "prepare", "train", "train_seed",
           "validate_train_config"]

#: Keys a resumed run may change: the budget, checkpointing, logging, and which seeds run.
RESUMABLE_CHANGES = ("total_timesteps", "checkpoint_every", "tensorboard", "resume", "seeds",
                     "torch_threads", "models", "hyperparams_file")


class RunFiles:
    """The files of one seed's run of a validated configuration."""

    def __init__(self, config: Mapping, seed: int) -> None:
        self.config = {**config, "seeds": [seed]}
        self.seed = seed
        self.run = run_name(config["algo"], config["variant"])
        self.stem = f"{self.run}_seed{seed}"
        self.folder = Path(config["models"]) / config["name"]
        self.model = self.folder / f"{self.stem}.zip"
        self.monitor = self.folder / f"{self.stem}{SUFFIX}"
        self.checkpoint_folder = self.folder / "checkpoints"

    def checkpoint(self, steps: int) -> Path:
        return self.checkpoint_folder / f"{self.stem}_{steps}_steps.zip"

    def check_links(self) -> None:
        """A `ConfigError` if a symbolic link stands where the run writes in place or into a
        folder of its own: the monitor file, ``checkpoints/``, ``tensorboard/`` (whole files
        are renamed over their names and need no check; `bounce_gym.files`)."""
        refuse_links("config.models", self.folder, self.monitor)
        refuse_links("config.models", self.folder, self.checkpoint_folder)
        if self.config["tensorboard"]:
            refuse_links("config.models", self.folder, self.folder / "tensorboard")

    def checkpoints(self) -> dict[int, Path]:
        """This run's checkpoints by step count."""
        from baselines.rl.resume import checkpoints

        return checkpoints(self.checkpoint_folder, self.run, self.seed)


def train(config: Mapping, progress: bool = True, callbacks: Sequence = (),
          folder: Path | None = None, log: Callable[[str], None] | None = None) -> list[Path]:
    """Train (or resume) an agent for every seed of ``config`` and save each where the
    evaluation finds it; returns the model paths. ``callbacks`` are SB3 callbacks added to
    every run; ``folder`` is where a relative ``hyperparams_file`` is read from; ``log`` gets
    one line per seed saying what happens to it."""
    config = prepare(config, folder)
    return [train_seed(config, seed, progress, callbacks, log) for seed in config["seeds"]]


def prepare(config: Mapping, folder: Path | None = None) -> dict:
    """The validated configuration (`validate_train_config`), checked for everything that can
    be checked before any training: the models folder, the checkpoints there, the
    hyperparameters and the action space. Its seeds may then train in any order or at once
    (`train_seed`; a sweep over processes, `bounce_gym_experiments.training`)."""
    config = validate_train_config(config, folder)  # the quick checks first, before torch
    runs = [RunFiles(config, seed) for seed in config["seeds"]]
    check_writable("config.models", runs[0].folder)
    for run in runs:
        run.check_links()
    _check_checkpoints(config, runs)
    if config["tensorboard"]:
        require("config.tensorboard: true", "tensorboard")
    if config["algo"] in JAX_ALGOS:
        require(f"config.algo: {config['algo']}", "jax", "optax")
        from baselines.rl.jaxrl.runner import shared_learner

        shared_learner(config)  # the JAX env exists, the actions are discrete, the sizes fit
        return config
    if config["algo"] in MARL_ALGOS:
        require(f"config.algo: {config['algo']}", "torch")
        from baselines.rl.marl.ppo import Learner

        Learner(config, config["seeds"][0], ())  # the teams are batched, the networks fit
        return config
    require(f"config.algo: {config['algo']}", "stable_baselines3", "sb3_contrib", "torch", "rich",
            "tqdm")
    check_hyperparams(algo_class(config["algo"]), config["hyperparams"])
    _check_action_space(config)
    return config


def train_seed(config: Mapping, seed: int, progress: bool = True, callbacks: Sequence = (),
               log: Callable[[str], None] | None = None) -> Path:
    """Train (or, with ``resume``, continue from its newest checkpoint) the run of one seed of
    a configuration `prepare` returned; returns the model path. torch uses
    ``torch_threads`` threads meanwhile. A JAX learner trains in `baselines.rl.jaxrl.runner`
    (``progress``: a ``log`` line per chunk instead of SB3's progress bar), a multi-robot
    learner in `baselines.rl.marl.runner` (neither can resume)."""
    if config["algo"] in JAX_ALGOS:
        from baselines.rl.jaxrl.runner import train_run

        return train_run(RunFiles(config, seed), log or (lambda line: None), progress)
    if config["algo"] in MARL_ALGOS:
        from baselines.rl.marl.runner import train_team_run

        return train_team_run(RunFiles(config, seed), log or (lambda line: None))
    import torch

    threads = torch.get_num_threads()
    # small MLPs on tiny batches: more intra-op threads only contend with the env processes
    torch.set_num_threads(config["torch_threads"])
    try:
        return _train_run(RunFiles(config, seed), progress, list(callbacks),
                          log or (lambda line: None))
    finally:
        torch.set_num_threads(threads)


def finished(config: Mapping, seed: int) -> bool:
    """Whether the seed's model of a configuration `prepare` returned is saved already: a
    readable model file (unchanged since saved, `baselines.rl.model_files.read_model`), trained
    with this configuration (`RESUMABLE_CHANGES` aside) for exactly its ``total_timesteps``. A
    sweep started again skips such seeds."""
    run = RunFiles(config, seed)
    if not run.model.is_file():
        return False
    try:
        saved = read_model(run.model).metadata.get("config", {})
    except ConfigError:
        return False
    return saved.get("total_timesteps") == config["total_timesteps"] and \
        _comparable(saved) == _comparable(run.config)


def _check_checkpoints(config: Mapping, runs: list[RunFiles]) -> None:
    """Resume only from checkpoints of this configuration, and never start afresh over one."""
    found = {run.stem: run.checkpoints() for run in runs}
    folder = runs[0].checkpoint_folder
    if config["resume"] and not any(found.values()):
        raise ConfigError(f"config.resume: nothing to resume: {folder} holds no checkpoint of "
                          f"{', '.join(found)}; train without --resume first")
    if not config["resume"] and any(found.values()):
        stem, steps = next((stem, max(c)) for stem, c in found.items() if c)
        raise ConfigError(f"config.resume: {folder} already holds checkpoints of {stem} (the "
                          f"newest at {steps} steps); pass --resume to continue them, or delete "
                          "them to start again (a checkpoint is never overwritten)")
    for run in runs:
        if found[run.stem]:
            path = found[run.stem][max(found[run.stem])]
            _check_same_config(read_model(path).metadata.get("config", {}), run.config, path)


def _check_action_space(config: Mapping) -> None:
    """DQN needs discrete actions (a multi-robot env trains PPO only)."""
    import gymnasium as gym

    from baselines.rl.train_env import make_config_env

    if config["algo"] != "dqn":
        return
    space = make_config_env(config).action_space
    if not isinstance(space, gym.spaces.Discrete):
        raise ConfigError(f"config.algo: dqn needs discrete actions, but the env's are {space} "
                          "(set env_kwargs.action_type: discrete, or use ppo or recurrentppo)")


def _comparable(config: Mapping) -> dict:
    return json.loads(json.dumps({k: v for k, v in config.items()
                                  if k not in RESUMABLE_CHANGES}))


def _check_same_config(saved: Mapping, config: Mapping, path: Path) -> None:
    theirs, ours = _comparable(saved), _comparable(config)
    changed = sorted(k for k in {*theirs, *ours} if theirs.get(k) != ours.get(k))
    if changed:
        key = changed[0]
        raise ConfigError(f"config.{key}: the checkpoint {path} was trained with "
                          f"{theirs.get(key)!r}, this configuration says {ours.get(key)!r}; "
                          "resume with the configuration it was trained with")


def _train_run(run: RunFiles, progress: bool, extra_callbacks: list, log) -> Path:
    from baselines.rl.resume import capture, checkpoint_callback
    from baselines.rl.wrappers import describe_wrappers
    from bounce_gym.provenance import provenance

    config = run.config
    own_callbacks = training_callbacks(config)
    env = make_train_env(config, run.seed)
    try:
        found = run.checkpoints() if config["resume"] else {}
        model = _resumed(run, env, found, log) if found else _fresh(run, env, log)

        made = provenance()  # once per run: the git calls are not repeated per checkpoint

        def metadata() -> dict:
            return {"config": config, "wrappers": describe_wrappers(env), "trained_with": made}

        def save_checkpoint(model) -> None:
            run.check_links()  # also a link made since the run started
            save_model(model, run.checkpoint(model.num_timesteps), metadata(),
                       resume=capture(model), overwrite=False)

        if model.num_timesteps < config["total_timesteps"]:
            model.learn(config["total_timesteps"] - model.num_timesteps,
                        callback=[checkpoint_callback(config["checkpoint_every"],
                                                      save_checkpoint), *own_callbacks,
                                  *extra_callbacks],
                        progress_bar=progress, reset_num_timesteps=not found)
        if model.num_timesteps not in run.checkpoints():
            save_checkpoint(model)
        save_model(model, run.model, metadata())
    finally:
        env.close()
    return run.model


def _log_dir(run: RunFiles) -> str | None:
    return str(run.folder / "tensorboard") if run.config["tensorboard"] else None


def _fresh(run: RunFiles, env, log):
    """A new model of the run's algorithm on ``env``, its monitor file started."""
    config = run.config
    kwargs = algo_kwargs(config["hyperparams"])
    try:
        model = algo_class(config["algo"])(
            policy_name(config["algo"], env.observation_space), env, seed=run.seed, device="cpu", verbose=0,
            tensorboard_log=_log_dir(run), **kwargs)
    except (AssertionError, TypeError, ValueError) as exc:  # SB3's checks of the values
        raise ConfigError(f"config.hyperparams: {exc}") from None
    attach_monitor_file(env, run.monitor, config["env"])
    log(f"{run.stem}: training {config['total_timesteps']} steps")
    return model


def _resumed(run: RunFiles, env, found: dict[int, Path], log):
    """The model of the newest checkpoint in ``found``, with everything restored into it and
    into ``env``, its monitor file cut back to the checkpoint. The resume state is unpickled
    only once vouched for (`baselines.rl.model_files.ModelFile.resume_state`), before the
    weights are loaded."""
    from baselines.rl.resume import restore

    steps, path = max(found.items())
    checkpoint = read_model(path)
    state = checkpoint.resume_state()
    model = checkpoint.load(env.observation_space, env.action_space, env=env,
                            tensorboard_log=_log_dir(run))
    restore(model, state)
    attach_monitor_file(env, run.monitor, run.config["env"], keep_rows=state["episodes"])
    total = run.config["total_timesteps"]
    log(f"{run.stem}: resumed from {path} ({steps} of {total} steps)" if steps < total
        else f"{run.stem}: already trained for {steps} steps ({path})")
    return model
