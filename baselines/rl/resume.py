"""Checkpoints that a run can be resumed from exactly.

A checkpoint is taken where an iteration of the algorithm begins (SB3's ``on_rollout_start``:
after the previous update, before the next env step), so that nothing is half done. Its file
(`baselines.rl.model_files.save_model`) holds SB3's model — weights, optimiser state, step
count and the counters SB3 saves — and the state SB3 does not save (`capture`):

* the random streams: Python's, NumPy's global one, torch's, and those of the model's spaces;
* the algorithm's running state: the last observations and episode starts, the recurrent
  state (RecurrentPPO), the exploration rate and call count and the replay buffer (DQN), the
  episode-info buffers;
* the whole training VecEnv (`baselines.rl.train_env`): every env's state and random generator
  mid-episode, the monitor's running sums and episode count, VecNormalize's statistics and
  running returns, the frame stack.

`restore` puts all of it back into a model loaded from the checkpoint and a freshly built env,
so a resumed run continues the same episodes where they stopped (no env is re-seeded; none
replays its task sequence) and takes the same steps as a run that was never interrupted.

All of it is one pickle (the envs caught mid-episode are arbitrary object graphs), stored in the
checkpoint with a signature under the user's key and unpickled only when that signature checks
or the user trusts the checkpoint's digest (`baselines.rl.model_files.ModelFile.resume_state`):
`restore` and `restore_env` are given only state that was vouched for so.
"""

from __future__ import annotations

import pickle
import random
from pathlib import Path

import numpy as np

from baselines.rl.model_files import CHECKPOINT_NAME, run_name

#: Attributes of an SB3 algorithm that change while it learns (those it has).
RUNNING_ATTRIBUTES = ("num_timesteps", "_episode_num", "_n_updates", "_n_calls",
                      "exploration_rate", "_current_progress_remaining", "_last_obs",
                      "_last_original_obs", "_last_episode_starts", "_last_lstm_states",
                      "ep_info_buffer", "ep_success_buffer", "replay_buffer")
#: Attributes of a VecEnv wrapper that are structure, not state (kept from the fresh env).
_STRUCTURE = ("venv", "results_writer", "class_attributes")


def capture(model) -> dict:
    """Everything `restore` needs besides what ``model.save`` writes (module docstring)."""
    import torch

    return {
        "rng": {"python": random.getstate(), "numpy": np.random.get_state(),
                "torch": torch.get_rng_state(),
                "spaces": [space.np_random.bit_generator.state
                           for space in (model.observation_space, model.action_space)]},
        "model": {name: getattr(model, name) for name in RUNNING_ATTRIBUTES
                  if hasattr(model, name)},
        "env": capture_env(model.get_env()),
        "episodes": episodes(model.get_env()),
    }


def restore(model, state: dict) -> None:
    """Put a `capture` back into ``model`` (loaded from the checkpoint with the freshly built
    training env, whose layers must be those captured); ``state`` is a resume state vouched
    for by `baselines.rl.model_files.ModelFile.resume_state`, never one read otherwise."""
    import torch

    restore_env(model.get_env(), state["env"])
    for name, value in state["model"].items():
        setattr(model, name, value)
    rng = state["rng"]
    random.setstate(rng["python"])
    np.random.set_state(rng["numpy"])
    torch.set_rng_state(rng["torch"])
    for space, saved in zip((model.observation_space, model.action_space), rng["spaces"],
                            strict=True):
        space.np_random.bit_generator.state = saved


def _layers(venv) -> list:
    from stable_baselines3.common.vec_env.base_vec_env import VecEnvWrapper

    layers = [venv]
    while isinstance(layers[-1], VecEnvWrapper):
        layers.append(layers[-1].venv)
    return layers


def episodes(venv) -> int:
    """How many episodes the VecEnv's monitor has seen end."""
    from stable_baselines3.common.vec_env import VecMonitor

    return next(layer for layer in _layers(venv) if isinstance(layer, VecMonitor)).episode_count


def _copies(base) -> bool:
    """Whether the envs are SB3 copies (``sync``/``subproc``), each a `SnapshotEnv`."""
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    return isinstance(base, DummyVecEnv | SubprocVecEnv)


def capture_env(venv) -> dict:
    """The state of every layer of a training VecEnv, as bytes."""
    *wrappers, base = _layers(venv)
    state = {"wrappers": [(type(layer).__name__,
                           {k: v for k, v in vars(layer).items() if k not in _STRUCTURE})
                          for layer in wrappers]}
    if _copies(base):
        state["copies"] = base.env_method("snapshot")
    else:
        state["base"] = dict(vars(base))
    return {"kinds": [type(layer).__name__ for layer in (*wrappers, base)],
            "state": pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL)}


def restore_env(venv, captured: dict) -> None:
    """Put a `capture_env` back into a VecEnv built with the same layers. ``captured`` comes
    from a vouched-for resume state (`restore`), so its inner pickle is vouched for too."""
    *wrappers, base = _layers(venv)
    kinds = [type(layer).__name__ for layer in (*wrappers, base)]
    if kinds != captured["kinds"]:
        raise ValueError(f"the env's layers {kinds} are not the captured {captured['kinds']}")
    state = pickle.loads(captured["state"])  # noqa: S301  (part of a vouched-for resume state)
    for layer, (_, saved) in zip(wrappers, state["wrappers"], strict=True):
        vars(layer).update(saved)
    if _copies(base):
        for i, data in enumerate(state["copies"]):
            base.env_method("restore", data, indices=[i])
        base._reset_seeds()  # the model's load seeded the next reset; there is none to come
    else:
        vars(base).update(state["base"])


def checkpoints(folder: Path, run: str, seed: int) -> dict[int, Path]:
    """The checkpoints of run ``<run>_seed<seed>`` in ``folder``, by step count."""
    if not folder.is_dir():
        return {}
    out = {}
    for path in folder.iterdir():
        match = CHECKPOINT_NAME.fullmatch(path.name)
        if match and run_name(match.group("algo"), match.group("variant")) == run \
                and int(match.group("seed")) == seed:
            out[int(match.group("steps"))] = path
    return dict(sorted(out.items()))


def checkpoint_callback(every: int, save):
    """An SB3 callback calling ``save(model)`` at the start of every iteration at which the
    model's step count has reached the next multiple of ``every`` (``every`` 0: never)."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Checkpoints(BaseCallback):
        def _on_training_start(self) -> None:
            self.due = (self.model.num_timesteps // every + 1) * every if every else None

        def _on_rollout_start(self) -> None:
            if self.due is not None and self.model.num_timesteps >= self.due:
                save(self.model)
                self.due = (self.model.num_timesteps // every + 1) * every

        def _on_step(self) -> bool:
            return True

    return Checkpoints()
