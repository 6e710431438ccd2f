"""Model files are data: a planted pickle in a model's JSON, its weights or a checkpoint's resume
state never runs — even beside a manifest that lists the file — and a zip bomb or a broken file
is one line naming the file. Resuming unpickles only a resume state this user's runs signed, or
a checkpoint the user trusts (``bounce-gym trust``)."""

import base64
import io
import json
import pickle
import tracemalloc
import zipfile
from pathlib import Path

import gymnasium as gym
import pytest
import torch
import yaml

pytest.importorskip("stable_baselines3")

import bounce_gym  # noqa: E402, F401
from baselines.rl.model_files import (  # noqa: E402
    MANIFEST,
    METADATA_ENTRY,
    RESUME_ENTRY,
    SIGNATURE_ENTRY,
    read_model,
    save_model,
)
from baselines.rl.policies import SB3Policy  # noqa: E402
from baselines.rl.train import train  # noqa: E402
from bounce_gym.errors import ConfigError  # noqa: E402
from bounce_gym.trust import HOME_VARIABLE, digest, trusted_digests  # noqa: E402
from bounce_gym_experiments.cli import main  # noqa: E402

NAV = {"world": "square", "backend": "cell", "angles": [90, 135]}
CONFIG = {"name": "nav", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
          "algo": "ppo", "total_timesteps": 64, "n_envs": 1,
          "hyperparams": {"n_steps": 32, "batch_size": 32, "n_epochs": 1,
                          "learning_rate": "lin_0.001",
                          "policy_kwargs": {"activation_fn": "relu", "net_arch": [16]}}}


class Payload:
    """Unpickled, it creates the file ``marker``: proof that the pickle ran."""

    def __init__(self, marker: Path) -> None:
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    """A model trained and saved by this package (with its checkpoint at 64 steps)."""
    models = tmp_path_factory.mktemp("trained")
    (path,) = train({**CONFIG, "models": str(models)}, progress=False)
    return path


@pytest.fixture(scope="module")
def env():
    return gym.make("bounce_gym/BounceNavigation-v0", **NAV)


def _entries(path: Path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as archive:
        return {name: archive.read(name) for name in archive.namelist()}


def _write(path: Path, entries: dict[str, bytes], listed: bool = True) -> Path:
    """A zip of ``entries`` at ``path``, listed with its sha256 in its folder's manifest (as an
    attacker shipping a folder would list it)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, content in entries.items():
            archive.writestr(name, content)
    if listed:
        (path.parent / MANIFEST).write_text(json.dumps({path.name: [digest(path.read_bytes())]}))
    return path


def _pickled(marker: Path) -> str:
    return base64.b64encode(pickle.dumps(Payload(marker))).decode()


def _planted_data(source: Path, marker: Path, extra: str | None = None) -> dict[str, bytes]:
    """The entries of ``source`` with every pickled value of SB3's ``data`` replaced by the
    payload (and, with ``extra``, one more pickled key of that name)."""
    entries = _entries(source)
    data = json.loads(entries["data"])
    for value in data.values():
        if isinstance(value, dict) and ":serialized:" in value:
            value[":serialized:"] = _pickled(marker)
    if extra:
        data[extra] = {":type:": "<class 'x'>", ":serialized:": _pickled(marker)}
    entries["data"] = json.dumps(data).encode()
    return entries


def _weights(model) -> dict:
    return {k: v.clone() for k, v in model.policy.state_dict().items()}


def _same(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)


def test_a_listed_model_with_planted_pickles_loads_its_weights_and_runs_nothing(
        tmp_path, trained, env):
    marker = tmp_path / "payload-ran"
    planted = _write(tmp_path / "evil" / "ppo_seed0.zip", _planted_data(trained, marker))
    model = read_model(planted).load(env.observation_space, env.action_space)
    reference = read_model(trained).load(env.observation_space, env.action_space)
    assert _same(_weights(model), _weights(reference))
    # the replaced objects are rebuilt from the configuration the file carries
    assert model.lr_schedule(1.0) == pytest.approx(0.001) and model.lr_schedule(0.5) == \
        pytest.approx(0.0005)
    assert isinstance(model.policy.mlp_extractor.policy_net[1], torch.nn.ReLU)
    assert model.num_timesteps == 64  # a counter, kept from the file's JSON
    policy = SB3Policy(planted, env)
    policy.start_options(env, 10_000)
    observation, info = env.reset(seed=10_000)
    policy.reset(env)
    assert policy.act(observation, info) in (0, 1)
    assert not marker.exists()


def test_a_pickled_key_the_package_cannot_rebuild_is_refused(tmp_path, trained, env):
    marker = tmp_path / "payload-ran"
    planted = _write(tmp_path / "evil" / "ppo_seed0.zip",
                     _planted_data(trained, marker, extra="env"))
    with pytest.raises(ConfigError, match=r"ppo_seed0.zip: its 'data' holds a pickled entry "
                                          r"'env', which a ppo model does not save"):
        read_model(planted).load(env.observation_space, env.action_space)
    assert not marker.exists()


def _evaluate_config(tmp_path: Path, models: Path) -> Path:
    config = {"output": str(tmp_path / "runs"), "models": str(models),
              "experiments": [{"name": "nav", "env": "bounce_gym/BounceNavigation-v0",
                               "env_kwargs": NAV, "seeds": [10_000], "max_steps": 5,
                               "horizon_reason": "a quick test", "policies": ["rl"]}]}
    path = tmp_path / "eval.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    return path


def test_bounce_gym_evaluate_runs_nothing_from_a_planted_model(tmp_path, trained):
    marker = tmp_path / "payload-ran"
    _write(tmp_path / "models" / "nav" / "ppo_seed0.zip", _planted_data(trained, marker))
    config = _evaluate_config(tmp_path, tmp_path / "models")
    assert main(["evaluate", str(config), "--workers", "1", "--no-progress"]) == 0
    summary = next((tmp_path / "runs").glob("*/summary.csv")).read_text()
    assert "nav,rl ppo,1,1," in summary and "nav,rl ppo (greedy),1,1," in summary
    assert not marker.exists()


@pytest.mark.parametrize("entry", ["policy.pth", "policy.optimizer.pth",
                                   "pytorch_variables.pth"])
def test_weights_with_a_malicious_global_are_refused_without_running(tmp_path, trained, env,
                                                                     entry):
    marker = tmp_path / "payload-ran"
    entries = _entries(trained)
    buffer = io.BytesIO()
    torch.save({"weight": Payload(marker)}, buffer)  # torch.save pickles the payload
    entries[entry] = buffer.getvalue()
    planted = _write(tmp_path / "evil" / "ppo_seed0.zip", entries)
    refusal = r"UnpicklingError: Unsupported global: GLOBAL io.open was not an allowed global"
    with pytest.raises(ConfigError, match=rf"ppo_seed0.zip: .*{refusal} by default\)$"):
        read_model(planted).load(env.observation_space, env.action_space)
    assert not marker.exists()


def _bomb(path: Path, entries: dict[str, bytes], name: str, megabytes: int) -> Path:
    """``entries`` with ``name`` a deflated run of zeros of ``megabytes`` (about a thousandth
    of that on disk), written in pieces."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for entry, content in entries.items():
            if entry != name:
                archive.writestr(entry, content)
        with archive.open(name, "w", force_zip64=True) as fh:
            for _ in range(megabytes):
                fh.write(bytes(1 << 20))
    return path


@pytest.mark.parametrize(("entry", "message"), [
    ("data", r"its entry 'data' holds 67108864 bytes, more than the 16777216"),
    (METADATA_ENTRY, r"its entry 'bounce_gym.json' holds 67108864 bytes, more than the"),
    ("policy.pth", r"its entry 'policy.pth' holds 67108864 bytes, more than the \d+ the "
                   r"weights of its model may"),
])
def test_a_zip_bomb_is_one_line_and_nothing_of_it_is_inflated(tmp_path, trained, env, entry,
                                                             message):
    path = _bomb(tmp_path / "ppo_seed0.zip", _entries(trained), entry, 64)
    assert path.stat().st_size < 1 << 20
    tracemalloc.start()
    try:
        with pytest.raises(ConfigError, match=message) as error:
            read_model(path).load(env.observation_space, env.action_space)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert "\n" not in str(error.value)
    assert peak < 16 << 20


def _without(name: str):
    return lambda entries: {k: v for k, v in entries.items() if k != name}


def _data(change):
    def apply(entries):
        data = json.loads(entries["data"])
        change(data)
        return {**entries, "data": json.dumps(data).encode()}
    return apply


def _config(change):
    def apply(entries):
        metadata = json.loads(entries[METADATA_ENTRY])
        change(metadata["config"])
        return {**entries, METADATA_ENTRY: json.dumps(metadata).encode()}
    return apply


@pytest.mark.parametrize(("change", "message"), [
    (_without("policy.pth"), r"its weights do not fit the ppo model its configuration "
                             r"describes \(ValueError"),
    (_without("data"), r"not a readable Stable-Baselines3 model file \(it has no 'data' entry"),
    (lambda e: {**e, "data": b"{" * 100_000}, r"its entry 'data': lists and mappings nest 100000 deep"),
    (lambda e: {**e, "data": b"[1]"}, r"its entry 'data' is not a JSON object"),
    (lambda e: {**e, "policy.pth": b"not torch"}, r"its weights do not fit the ppo model"),
    (lambda e: {**e, "extra.pth": e["policy.pth"]}, r"holds weights 'extra.pth', which a ppo "
                                                    r"model does not have"),
    (_without(METADATA_ENTRY), r"carries no training configuration in its bounce_gym.json"),
    (_config(lambda c: c.update(algo="dqn")), r"its name says ppo, but its configuration says "
                                              r"algo 'dqn'"),
    (_config(lambda c: c["hyperparams"].update(env="x")), r"the training configuration it "
     r"carries is not valid \(config.hyperparams.env: not a hyperparameter of PPO\)"),
    (_config(lambda c: c["hyperparams"]["policy_kwargs"].update(net_arch=[8])),
     r"its weights do not fit the ppo model .*size mismatch"),
    (_data(lambda d: d.update(num_timesteps="many", tensorboard_log="/tmp/x")), None),
])
def test_a_broken_model_file_is_one_line_naming_it(tmp_path, trained, env, change, message):
    path = _write(tmp_path / "m" / "ppo_seed0.zip", change(_entries(trained)), listed=False)
    if message is None:  # a counter or setting of the wrong kind is the template's instead
        model = read_model(path).load(env.observation_space, env.action_space)
        assert (model.num_timesteps, model.tensorboard_log) == (0, None)
        return
    with pytest.raises(ConfigError, match=rf"model {path}: {message}") as error:
        read_model(path).load(env.observation_space, env.action_space)
    assert "\n" not in str(error.value)


def test_a_file_that_is_no_zip_is_one_line(tmp_path, env):
    for content in (b"", b"PK\x03\x04 truncated", b"just text"):
        path = tmp_path / "ppo_seed0.zip"
        path.write_bytes(content)
        with pytest.raises(ConfigError, match=rf"model {path}: not a readable Stable-Baselines3 "
                                              r"model file \(BadZipFile"):
            read_model(path)


def _checkpoint(model: Path) -> Path:
    return model.parent / "checkpoints" / f"{model.stem}_64_steps.zip"


def _resume_config(tmp_path: Path, models: Path) -> Path:
    path = tmp_path / "train.yaml"
    path.write_text(yaml.safe_dump({**CONFIG, "models": str(models), "total_timesteps": 96}),
                    encoding="utf-8")
    return path


def test_a_planted_resume_state_is_refused_and_never_runs(tmp_path, trained, capsys):
    marker = tmp_path / "payload-ran"
    models = tmp_path / "models"
    checkpoint = _checkpoint(models / "nav" / "ppo_seed0.zip")
    entries = _entries(_checkpoint(trained))
    entries[RESUME_ENTRY] = pickle.dumps(Payload(marker))
    for signature in (None, "0" * 64, entries[SIGNATURE_ENTRY].decode()):
        planted = {**entries, SIGNATURE_ENTRY: signature} if signature else \
            {k: v for k, v in entries.items() if k != SIGNATURE_ENTRY}
        _write(checkpoint, planted)  # listed in the manifest beside it
        assert main(["train", str(_resume_config(tmp_path, models)), "--resume",
                     "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: checkpoint {checkpoint}: its resume state was not written "
                              "by this user's runs") and err.count("\n") == 1
        assert f"run: bounce-gym trust {checkpoint}" in err
        assert not marker.exists()


def test_a_checkpoint_signed_under_another_key_resumes_once_trusted(tmp_path, monkeypatch,
                                                                    capsys):
    models = tmp_path / "models"
    config = _resume_config(tmp_path, models)
    with monkeypatch.context() as other_user:  # a colleague's runs sign with their own key
        other_user.setenv(HOME_VARIABLE, str(tmp_path / "colleague"))
        train({**CONFIG, "models": str(models)}, progress=False)
    checkpoint = _checkpoint(models / "nav" / "ppo_seed0.zip")
    assert main(["train", str(config), "--resume", "--no-progress"]) == 2
    assert "its resume state was not written by this user's runs" in capsys.readouterr().err
    manifest = (models / "nav" / MANIFEST).read_bytes()
    assert main(["trust", str(checkpoint)]) == 0
    assert digest(checkpoint.read_bytes()) in trusted_digests()
    # trust is the user's, not the folder's
    assert (models / "nav" / MANIFEST).read_bytes() == manifest
    capsys.readouterr()
    assert main(["train", str(config), "--resume", "--no-progress"]) == 0
    assert f"resumed from {checkpoint}" in capsys.readouterr().out
    assert read_model(models / "nav" / "ppo_seed0.zip").load(
        *_spaces()).num_timesteps == 96


def _spaces() -> tuple:
    env = gym.make("bounce_gym/BounceNavigation-v0", **NAV)
    return env.observation_space, env.action_space


def test_a_resume_state_signed_for_another_checkpoint_still_is_this_users(tmp_path, trained):
    """The signature vouches for the pickle, wherever it travels: a signed state moved into
    another zip is this user's own, and unpickles."""
    entries = _entries(_checkpoint(trained))
    moved = _write(tmp_path / "x" / "ppo_seed3_64_steps.zip",
                   {name: entries[name] for name in
                    ("data", "policy.pth", RESUME_ENTRY, SIGNATURE_ENTRY)}, listed=False)
    assert read_model(moved).resume_state()["episodes"] >= 0


def test_saving_signs_the_resume_state(tmp_path, trained, monkeypatch):
    model = read_model(trained).load(*_spaces())
    path = tmp_path / "ppo_seed0_64_steps.zip"
    save_model(model, path, resume={"episodes": 1})
    assert read_model(path).resume_state() == {"episodes": 1}
    monkeypatch.setenv(HOME_VARIABLE, str(tmp_path / "elsewhere"))  # another key
    with pytest.raises(ConfigError, match="not written by this user's runs"):
        read_model(path).resume_state()

