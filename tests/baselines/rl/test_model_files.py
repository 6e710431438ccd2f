"""Model files: atomic saving with a manifest, refusing untrusted or broken files, and the
folder-name rule shared by train and evaluate."""

import base64
import io
import json
import pickle
import zipfile
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


@pytest.fixture(scope="module")
def env():
    return gym.make("bounce_gym/BounceNavigation-v0", **ENV_KWARGS)


@pytest.fixture(scope="module")
def ppo(env):
    from stable_baselines3 import PPO

    return PPO("MlpPolicy", env, n_steps=64, device="cpu")


def _load(path: Path, env):
    return load_model(path, env.observation_space, env.action_space)


def test_save_model_lists_the_file_and_leaves_no_temporary_file(tmp_path, ppo, env):
    path = tmp_path / "m" / "ppo_seed0.zip"
    save_model(ppo, path)
    save_model(ppo, path)  # saving again replaces the digest
    manifest = json.loads((tmp_path / "m" / MANIFEST).read_text())
    assert list(manifest) == ["ppo_seed0.zip"] and len(manifest["ppo_seed0.zip"]) == 1
    # the manifest's lock file stays (bounce_gym.files.locked), no temporary one does
    assert sorted(p.name for p in (tmp_path / "m").iterdir()) == [
        f".{MANIFEST}.lock", MANIFEST, "ppo_seed0.zip"]
    assert _load(path, env).observation_space == env.observation_space


def test_only_final_model_names_are_loaded(tmp_path, ppo):
    save_model(ppo, tmp_path / "ppo_seed3.zip")
    for name in ("ppo_seed0.partial.zip", ".ppo_seed0.zip.abc.tmp", "notes.zip"):
        (tmp_path / name).write_bytes(b"")
    assert [p.name for p in model_files(tmp_path)] == ["ppo_seed3.zip"]


def _planted(tmp_path: Path, source: Path, marker: Path) -> Path:
    """A copy of a real SB3 zip whose JSON part carries a pickle that creates ``marker`` when
    SB3 unpickles it."""

    class Payload:
        def __reduce__(self):
            return (open, (str(marker), "w"))

    with zipfile.ZipFile(source) as archive:
        parts = {name: archive.read(name) for name in archive.namelist()}
    data = json.loads(parts["data"])
    data["policy_class"][":serialized:"] = base64.b64encode(pickle.dumps(Payload())).decode()
    parts["data"] = json.dumps(data).encode()
    planted = tmp_path / "evil" / "ppo_seed0.zip"
    planted.parent.mkdir()
    with zipfile.ZipFile(planted, "w") as archive:
        for name, content in parts.items():
            archive.writestr(name, content)
    return planted


def test_a_planted_model_is_refused_and_nothing_in_it_runs(tmp_path, ppo, env):
    save_model(ppo, tmp_path / "good" / "ppo_seed0.zip")
    marker = tmp_path / "payload-ran"
    planted = _planted(tmp_path, tmp_path / "good" / "ppo_seed0.zip", marker)
    with pytest.raises(ConfigError, match=r"ppo_seed0.zip: is not listed in .*manifest.json .*"
                                          r"bounce-gym trust"):
        _load(planted, env)
    assert not marker.exists()
    # swapping a listed file for another is refused as well
    (tmp_path / "good" / "ppo_seed0.zip").write_bytes(planted.read_bytes())
    with pytest.raises(ConfigError, match="has changed since it was listed"):
        _load(tmp_path / "good" / "ppo_seed0.zip", env)
    assert not marker.exists()
    # once trusted, it is loaded: the payload was real
    trust(planted)
    with pytest.raises(Exception):  # noqa: B017  (the payload breaks SB3's load)
        _load(planted, env)
    assert marker.exists()


def test_broken_or_mismatched_trusted_models_are_one_error_naming_the_file(tmp_path, ppo, env):
    folder = tmp_path / "m"
    save_model(ppo, folder / "ppo_seed0.zip")
    data = (folder / "ppo_seed0.zip").read_bytes()
    (folder / "ppo_seed1.zip").write_bytes(data[: len(data) // 2])
    trust(folder / "ppo_seed1.zip")
    with pytest.raises(ConfigError, match=r"ppo_seed1.zip: not a readable Stable-Baselines3"):
        _load(folder / "ppo_seed1.zip", env)
    (folder / "dqn_seed0.zip").write_bytes(data)
    trust(folder / "dqn_seed0.zip")
    with pytest.raises(ConfigError, match=r"dqn_seed0.zip: its name says dqn, but it holds a "
                                          r"ppo policy"):
        _load(folder / "dqn_seed0.zip", env)
    other = gym.make("bounce_gym/BounceNavigation-v0", **ENV_KWARGS, history=2)
    with pytest.raises(ConfigError, match=r"ppo_seed0.zip: trained for observations"):
        load_model(folder / "ppo_seed0.zip", other.observation_space, other.action_space)


def test_trust_refuses_missing_files_and_other_names(tmp_path):
    with pytest.raises(ConfigError, match="does not exist"):
        trust(tmp_path / "ppo_seed0.zip")
    (tmp_path / "x.zip").write_bytes(io.BytesIO(b"zip").getvalue())
    with pytest.raises(ConfigError, match="not named like a model"):
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


def test_metadata_and_resume_state_travel_in_the_trusted_zip(tmp_path, ppo, env):
    path = tmp_path / "m" / "checkpoints" / "ppo-x_seed0_64_steps.zip"
    save_model(ppo, path, {"wrappers": {"n_stack": 2}}, resume={"episodes": 3},
               overwrite=False)
    trusted = read_model(path)
    assert (trusted.algo, trusted.metadata) == ("ppo", {"wrappers": {"n_stack": 2}})
    assert trusted.resume_state() == {"episodes": 3}
    with pytest.raises(ConfigError, match="a checkpoint is never overwritten"):
        save_model(ppo, path, overwrite=False)
    plain = tmp_path / "m" / "ppo_seed0.zip"
    save_model(ppo, plain)
    assert read_model(plain).metadata == {}
    with pytest.raises(ConfigError, match="holds no resume state"):
        read_model(plain).resume_state()
    copy = tmp_path / "other" / path.name  # a checkpoint obtained elsewhere: trusted once listed
    copy.parent.mkdir()
    copy.write_bytes(path.read_bytes())
    with pytest.raises(ConfigError, match="is not listed in"):
        read_model(copy)
    trust(copy)
    assert read_model(copy).resume_state() == {"episodes": 3}


def _trust_many(folder: str, prefix: str, count: int) -> None:
    for i in range(count):
        path = Path(folder) / f"ppo-{prefix}_seed{i}.zip"
        path.write_bytes(f"{prefix}{i}".encode())
        trust(path)


def test_processes_listing_files_at_once_lose_no_entry(tmp_path):
    """The manifest is read, changed and rewritten under a lock: two processes adding 40
    entries each to one manifest at once leave all 80 listed."""
    import multiprocessing

    context = multiprocessing.get_context("fork")
    workers = [context.Process(target=_trust_many, args=(str(tmp_path), p, 40))
               for p in ("a", "b")]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(timeout=120)
        assert worker.exitcode == 0
    assert len(json.loads((tmp_path / MANIFEST).read_text())) == 80
