"""The host loop of one seed of a multi-robot learner (``algo: ippo | mappo``): the learner
(`baselines.rl.marl.ppo.Learner`) iterates until ``total_timesteps`` agent-steps are learned
from (whole iterations, the last one completed), appending after each iteration a monitor row
per robot and finished episode (`baselines.rl.monitor`; ``t`` is the time the iteration ended)
and saving a checkpoint once a multiple of ``checkpoint_every`` agent-steps is passed; at the
end a last checkpoint and the model file, weights only (`baselines.rl.jaxrl.weights`'s format:
an ``.npz`` read without pickle, and the metadata), atomically and listed in the folder's
manifest (`baselines.rl.model_files.save_model`).

Checkpoints hold the weights, not the optimiser's moments, the generator or the teams
mid-episode, so a run is not resumed (``resume: true`` is refused by
`baselines.rl.train_config`).
"""

from __future__ import annotations

import time
from pathlib import Path

import torch

from baselines.rl.jaxrl.weights import WeightsArchive
from baselines.rl.marl.ppo import Learner
from baselines.rl.marl.rollout import team_monitor_keys
from baselines.rl.model_files import save_model
from baselines.rl.monitor import open_monitor_file
from bounce_gym.provenance import provenance


def train_team_run(run, log) -> Path:
    """Train the seed of ``run`` (a `baselines.rl.train.RunFiles`) with ``torch_threads``
    threads; returns the model path."""
    config = run.config
    threads = torch.get_num_threads()
    torch.set_num_threads(config["torch_threads"])
    try:
        agent = Learner(config, run.seed, team_monitor_keys(config))
        every = config["checkpoint_every"]
        due = every
        made = provenance()

        def save(path: Path, overwrite: bool) -> None:
            metadata = {"config": config, "marl": {"num_timesteps": agent.steps},
                        "trained_with": made}
            save_model(WeightsArchive(agent.weights()), path, metadata, overwrite=overwrite)

        def save_checkpoint() -> None:
            run.check_links()
            save(run.checkpoint(agent.steps), overwrite=False)

        log(f"{run.stem}: training {config['total_timesteps']} agent-steps ({config['algo']}, "
            f"{'shared' if agent.settings.share else 'separate'} networks)")
        start = time.time()
        writer = open_monitor_file(run.monitor, start, config["env"],
                                   agent.collector.monitor_keys)
        try:
            while agent.iteration < agent.iterations:
                rows = agent.iterate()
                seconds = round(time.time() - start, 6)
                for row in rows:
                    writer.write_row({**row, "t": seconds})
                if every and agent.steps >= due:
                    save_checkpoint()
                    due = (agent.steps // every + 1) * every
        finally:
            writer.close()
        if agent.steps not in run.checkpoints():
            save_checkpoint()
        save(run.model, overwrite=True)
    finally:
        torch.set_num_threads(threads)
    return run.model
