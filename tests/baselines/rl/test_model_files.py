"""Model files: atomic saving with a manifest, refusing changed or broken files, and the
folder-name rule shared by train and evaluate (what loading refuses to run:
test_model_safety.py)."""

import io
import json
from pathlib import Path

import gymnasium as gym
import pytest

import bounce_gym  # noqa: F401
from baselines.rl.model_files import (
    CHECKPOINT_NAME,
    MANIFEST,
    MODEL_NAME,
    check_folder_name,
    load_model,
    model_files,
    read_model,
    save_model,
    trust,
)
from bounce_gym.errors import ConfigError

ENV_KWARGS = {"world": "square", "backend": "cell", "angles": [90, 135]}
#: The training configuration of the `ppo` fixture, which a model file must carry to load.
CONFIG = {"name": "m", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": ENV_KWARGS,
          "algo": "ppo", "total_timesteps": 64, "seeds": [0], "n_envs": 1,
          "hyperparams": {"n_steps": 64}}


@pytest.fixture(scope="module")
def env():
    return gym.make("bounce_gym/BounceNavigation-v0", **ENV_KWARGS)


@pytest.fixture(scope="module")
def ppo(env):
    from stable_baselines3 import PPO

    return PPO("MlpPolicy", env, n_steps=64, device="cpu", seed=0)


def _save(model, path: Path, **kwargs) -> None:
    save_model(model, path, {"config": CONFIG}, **kwargs)


def _load(path: Path, env):
    return load_model(path, env.observation_space, env.action_space)


def test_save_model_lists_the_file_and_leaves_no_temporary_file(tmp_path, ppo, env):
    path = tmp_path / "m" / "ppo_seed0.zip"
    _save(ppo, path)
    _save(ppo, path)  # saving again replaces the digest
    manifest = json.loads((tmp_path / "m" / MANIFEST).read_text())
    assert list(manifest) == ["ppo_seed0.zip"] and len(manifest["ppo_seed0.zip"]) == 1
    # the manifest's lock file stays (bounce_gym.files.locked), no temporary one does
    assert sorted(p.name for p in (tmp_path / "m").iterdir()) == [
        f".{MANIFEST}.lock", MANIFEST, "ppo_seed0.zip"]
    assert _load(path, env).observation_space == env.observation_space
    path.write_bytes(path.read_bytes()[:-1] + b"!")  # damaged: no longer what was saved
    with pytest.raises(ConfigError, match=r"ppo_seed0.zip: has changed since it was saved .*"
                                          r"manifest.json lists\): the file is damaged"):
        _load(path, env)


def test_only_final_model_names_are_loaded(tmp_path, ppo):
    save_model(ppo, tmp_path / "ppo_seed3.zip")
    for name in ("ppo_seed0.partial.zip", ".ppo_seed0.zip.abc.tmp", "notes.zip"):
        (tmp_path / name).write_bytes(b"")
    assert [p.name for p in model_files(tmp_path)] == ["ppo_seed3.zip"]


def test_broken_or_mismatched_models_are_one_error_naming_the_file(tmp_path, ppo, env):
    folder = tmp_path / "m"
    _save(ppo, folder / "ppo_seed0.zip")
    data = (folder / "ppo_seed0.zip").read_bytes()
    (folder / "ppo_seed1.zip").write_bytes(data[: len(data) // 2])
    with pytest.raises(ConfigError, match=r"ppo_seed1.zip: not a readable Stable-Baselines3"):
        _load(folder / "ppo_seed1.zip", env)
    (folder / "dqn_seed0.zip").write_bytes(data)
    with pytest.raises(ConfigError, match=r"dqn_seed0.zip: its name says dqn, but it holds a "
                                          r"ppo policy"):
        _load(folder / "dqn_seed0.zip", env)
    other = gym.make("bounce_gym/BounceNavigation-v0", **ENV_KWARGS, history=2)
    with pytest.raises(ConfigError, match=r"ppo_seed0.zip: trained for observations "
                                          r"Box\(dtype=float32, shape=\[17\]\) and actions "
                                          r"Discrete\(dtype=int64, shape=\[\], n=2, start=0\), "
                                          r"but this env has Box"):
        load_model(folder / "ppo_seed0.zip", other.observation_space, other.action_space)


def test_trust_refuses_missing_files_and_other_names(tmp_path):
    with pytest.raises(ConfigError, match="does not exist"):
        trust(tmp_path / "ppo_seed0.zip")
    (tmp_path / "x.zip").write_bytes(io.BytesIO(b"zip").getvalue())
    with pytest.raises(ConfigError, match=r"x.zip: expected a name <ppo\|dqn\|recurrentppo\|jax_ppo\|jax_dqn\|ippo\|mappo>"):
        trust(tmp_path / "x.zip")


@pytest.mark.parametrize("name", ["", ".", "..", "../x", "a/b", "/abs", "..\\x"])
def test_model_folder_names_are_one_plain_component(name):
    with pytest.raises(ConfigError, match="config.name: expected the name of a folder"):
        check_folder_name("config.name", name)
    check_folder_name("config.name", "navigation-lab")


@pytest.mark.parametrize(("name", "kind"), [
    ("ppo_seed0.zip", "model"), ("ppo-stack4_seed10.zip", "model"),
    ("recurrentppo-a-b2_seed3.zip", "model"), ("dqn_seed0_640_steps.zip", "checkpoint"),
    ("ppo-stack4_seed0_2048_steps.zip", "checkpoint"), ("ppo-_seed0.zip", None),
    ("ppo-Stack_seed0.zip", None), ("a2c_seed0.zip", None), ("ppo_seed0_steps.zip", None),
])
def test_model_and_checkpoint_names(name, kind):
    assert bool(MODEL_NAME.fullmatch(name)) == (kind == "model")
    assert bool(CHECKPOINT_NAME.fullmatch(name)) == (kind == "checkpoint")


def test_metadata_and_resume_state_travel_in_the_zip(tmp_path, ppo, env):
    path = tmp_path / "m" / "checkpoints" / "ppo-x_seed0_64_steps.zip"
    save_model(ppo, path, {"wrappers": {"n_stack": 2}}, resume={"episodes": 3},
               overwrite=False)
    saved = read_model(path)
    assert (saved.algo, saved.metadata) == ("ppo", {"wrappers": {"n_stack": 2}})
    assert saved.resume_state() == {"episodes": 3}
    with pytest.raises(ConfigError, match="a checkpoint is never overwritten"):
        save_model(ppo, path, overwrite=False)
    plain = tmp_path / "m" / "ppo_seed0.zip"
    save_model(ppo, plain)
    assert read_model(plain).metadata == {}
    with pytest.raises(ConfigError, match="holds no resume state"):
        read_model(plain).resume_state()
    with pytest.raises(ConfigError, match=r"ppo_seed0.zip: carries no training configuration"):
        _load(plain, env)
    copy = tmp_path / "other" / path.name  # a copy elsewhere: unlisted, signed by this user
    copy.parent.mkdir()
    copy.write_bytes(path.read_bytes())
    assert read_model(copy).resume_state() == {"episodes": 3}


def _save_many(model, folder: str, prefix: str, count: int) -> None:
    for i in range(count):
        save_model(model, Path(folder) / f"ppo-{prefix}_seed{i}.zip")


def test_processes_listing_files_at_once_lose_no_entry(tmp_path, ppo):
    """The manifest is read, changed and rewritten under a lock: two processes saving 20
    models each into one folder at once leave all 40 listed."""
    import multiprocessing

    context = multiprocessing.get_context("fork")
    workers = [context.Process(target=_save_many, args=(ppo, str(tmp_path), p, 20))
               for p in ("a", "b")]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(timeout=120)
        assert worker.exitcode == 0
    assert len(json.loads((tmp_path / MANIFEST).read_text())) == 40
