"""The multi-robot learners end to end (``algo: ippo | mappo``, shared and separate networks,
`baselines.rl.marl`): a short run of each through `baselines.rl.train` writes the model, its
checkpoints, the monitor file and the manifest; the model plays the PettingZoo env from
observations alone (sampled by default, a greedy twin), in rows that say what it is; the same
configuration and seed give the same weights bit for bit; every bad hyperparameter and every
damaged weights file is one line; and MAPPO learns where learning is easy."""

from __future__ import annotations

import io
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("torch")

import pettingzoo  # noqa: E402

import bounce_gym  # noqa: E402,F401
from baselines.rl.marl.policy import TeamPolicy  # noqa: E402
from baselines.rl.marl.ppo import Learner  # noqa: E402
from baselines.rl.model_files import MANIFEST, WEIGHTS_ENTRY, read_model  # noqa: E402
from baselines.rl.monitor import read_monitor  # noqa: E402
from baselines.rl.train import prepare, train  # noqa: E402
from baselines.rl.train_config import validate_train_config  # noqa: E402
from bounce_gym.errors import ConfigError  # noqa: E402

ROOT = Path(__file__).parents[3]
ENV = "bounce_gym/MultiBounceMonitoring-v0"
HALVES = [[[0, 0], [7.5, 0], [7.5, 15], [0, 15]], [[7.5, 0], [15, 0], [15, 15], [7.5, 15]]]
#: configs/benchmark.yaml's multirobot-monitoring-15x15, plus agent_id (the evaluation's env)
MONITORING = {"world": "grid_15x15", "n_robots": 2, "backend": "cell", "step_mode": "tick",
              "angles": [45, 90, 135], "corner_rule": "no_squeeze",
              "robot_collisions": "ignore", "agent_id": True, "task_kwargs": {"regions": HALVES}}
#: every learner and sharing, as (algo, share)
VARIANTS = [("ippo", True), ("ippo", False), ("mappo", True), ("mappo", False)]
IDS = [f"{a}-{'shared' if s else 'separate'}" for a, s in VARIANTS]


def _config(algo: str, share: bool, folder, **change) -> dict:
    """A tiny run: 2 teams, episodes of 12 steps (truncations and autoresets within each
    rollout of 16 steps), 3 iterations, a checkpoint every 64 agent-steps."""
    return {"name": "team", "env": ENV, "algo": algo, "seeds": [0], "models": str(folder),
            "env_kwargs": {**MONITORING, "max_cycles": 12}, "n_envs": 2,
            "total_timesteps": 3 * 16 * 2 * 2, "checkpoint_every": 64,
            "hyperparams": {"share": share, "n_steps": 16, "n_epochs": 2, "n_minibatches": 2,
                            "actor_layers": [16], "critic_layers": [16]}, **change}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("models")
    return folder, {name: train(_config(a, s, folder), progress=False)[0]
                    for name, (a, s) in zip(IDS, VARIANTS, strict=True)}


def _weights(path) -> dict[str, np.ndarray]:
    with zipfile.ZipFile(path) as archive, \
            np.load(io.BytesIO(archive.read(WEIGHTS_ENTRY)), allow_pickle=False) as npz:
        return {name: npz[name] for name in npz.files}


@pytest.mark.parametrize("name", IDS)
def test_a_run_writes_model_checkpoints_monitor_and_manifest(runs, name):
    folder, paths = runs
    path = paths[name]
    assert path == folder / "team" / f"{name}_seed0.zip"
    trained = read_model(path)  # listed in the manifest, weights only
    assert trained.algo == name.partition("-")[0] and not trained.sb3_data
    assert trained.metadata["marl"]["num_timesteps"] == 192
    assert path.name in (folder / "team" / MANIFEST).read_text()
    assert sorted(p.name for p in (folder / "team" / "checkpoints").glob(f"{name}_*")) == [
        f"{name}_seed0_{n}_steps.zip" for n in (128, 192, 64)]  # sorted by name
    monitor = read_monitor(folder / "team" / f"{name}_seed0.monitor.csv")
    # 48 team-steps of 2 teams: 4 whole episodes of 12 steps each, a row per robot
    assert len(monitor["r"]) == 4 * 2 * 2 and set(monitor["l"]) == {12}
    names = _weights(path)
    critics = [k for k in names if k.startswith("critics.")]
    assert len({k.split(".")[1] for k in critics}) == (1 if "shared" in name else 2)


class Untouchable(dict):
    """Infos a policy must not read: any look inside fails."""

    def _refuse(self, *args, **kwargs):
        raise AssertionError("the policy read infos")

    __getitem__ = get = items = keys = values = __iter__ = __contains__ = __len__ = _refuse


def _episode(policy, seed: int, blind: bool, steps: int = 60) -> list[dict]:
    env = pettingzoo.make("parallel", ENV, **MONITORING)
    policy.start_options(env, seed)
    observations, infos = env.reset(seed=seed)
    played = []
    for _ in range(steps):
        actions = policy.act(observations, Untouchable() if blind else infos)
        played.append(actions)
        observations, _, _, _, infos = env.step(actions)
    return played


@pytest.mark.parametrize("name", IDS)
def test_the_model_plays_the_pettingzoo_env_from_observations_only(runs, name):
    _, paths = runs
    env = pettingzoo.make("parallel", ENV, **MONITORING)
    sampled, greedy = TeamPolicy(paths[name], env), TeamPolicy(paths[name], env, True)
    algo, _, sharing = name.partition("-")
    assert sampled.described == f"{algo} ({sharing}, id)"
    assert greedy.name == f"rl {algo} ({sharing}, id) (greedy)"
    first = _episode(sampled, 10_000, blind=True)
    assert _episode(sampled, 10_000, blind=False) == first  # infos change nothing
    assert _episode(TeamPolicy(paths[name], env), 10_000, blind=True) == first
    assert all(set(a) == set(env.possible_agents) for a in first)
    assert _episode(greedy, 10_000, blind=True) == _episode(greedy, 10_000, blind=False)
    assert len({tuple(a.values()) for a in first}) > 1  # sampled: not one action for ever


def test_the_evaluation_names_the_rows_by_learner_sharing_and_observation(runs):
    from bounce_gym_experiments.runner import run

    folder, _ = runs
    env_kwargs = {k: v for k, v in MONITORING.items() if k != "agent_id"}
    config = {"models": str(folder), "experiments": [
        {"name": "monitoring", "env": ENV, "env_kwargs": env_kwargs,
         "seeds": {"start": 10_000, "count": 1}, "max_steps": 20,
         "horizon_reason": "a short check", "policies": ["rl"],
         "rl_models": [{"folder": "team", "env_kwargs": {"agent_id": True}}]}]}
    rows, _ = run(config, progress=False)
    assert {r.policy for r in rows} == {
        f"rl {a} ({s}, id) seed0{g}" for a in ("ippo", "mappo") for s in ("shared", "separate")
        for g in ("", " (greedy)")}


@pytest.mark.parametrize(("algo", "share"), VARIANTS, ids=IDS)
def test_same_configuration_and_seed_give_the_same_weights(tmp_path, algo, share):
    def weights(seed: int) -> dict[str, np.ndarray]:
        config = validate_train_config(_config(algo, share, tmp_path, seeds=[seed]))
        learner = Learner(config, seed, ())
        for _ in range(2):
            learner.iterate()
        return learner.weights()

    first, again, other = weights(0), weights(0), weights(1)
    assert first.keys() == again.keys()
    assert all(np.array_equal(first[k], again[k]) for k in first)
    assert not all(np.array_equal(first[k], other[k]) for k in first)


@pytest.mark.parametrize(("change", "field"), [
    ({"hyperparams": {"share": "yes"}}, "config.hyperparams.share"),
    ({"hyperparams": {"gamma": 1.5}}, "config.hyperparams.gamma"),
    ({"hyperparams": {"n_minibatches": 0}}, "config.hyperparams.n_minibatches"),
    ({"hyperparams": {"n_steps": 4, "n_minibatches": 9}}, "config.hyperparams.n_minibatches"),
    ({"hyperparams": {"actor_layers": [0]}}, "config.hyperparams.actor_layers"),
    ({"hyperparams": {"activation": "sigmoid"}}, "config.hyperparams.activation"),
    ({"hyperparams": {"batch_size": 64}}, "config.hyperparams"),
    ({"hyperparams": {"learning_rate": "lin_0.001"}}, "config.hyperparams.learning_rate"),
    ({"hyperparams": {"ent_coef": float("nan")}}, "config.hyperparams.ent_coef"),
    ({"resume": True}, "config.resume"),
    ({"tensorboard": True}, "config.tensorboard"),
    ({"env": "bounce_gym/MultiDrifter-v0", "env_kwargs": {}}, "config.env"),
    ({"env": "bounce_gym/BounceCoverage-v0", "env_kwargs": {}}, "config.env"),
    ({"env_kwargs": {**MONITORING, "backend": "kinematic"}}, "config.env_kwargs"),
    ({"env_kwargs": {**MONITORING, "angles": [[45, 90], [90]]}}, "config.env_kwargs"),
])
def test_bad_configurations_are_one_line_naming_the_key(tmp_path, change, field):
    config = _config("mappo", True, tmp_path)
    config.update({k: v for k, v in change.items() if k != "hyperparams"})
    config["hyperparams"].update(change.get("hyperparams", {}))
    with pytest.raises(ConfigError) as raised:
        prepare(config)
    message = str(raised.value)
    assert message.startswith(field) and "\n" not in message, message


def _copied(path: Path, folder: Path, entries: dict[str, bytes | None]) -> Path:
    """The model at ``path`` copied into ``folder`` (no manifest there) with ``entries``
    replaced (None: left out)."""
    folder.mkdir(exist_ok=True)
    with zipfile.ZipFile(path) as archive:
        items = {name: archive.read(name) for name in archive.namelist()}
    items.update(entries)
    out = folder / path.name
    with zipfile.ZipFile(out, "w") as archive:
        for name, data in items.items():
            if data is not None:
                archive.writestr(name, data)
    return out


def _npz(**arrays) -> bytes:
    out = io.BytesIO()
    np.savez(out, **arrays)
    return out.getvalue()


@pytest.mark.parametrize("damage", ["pickle", "wrong shape", "float64", "missing",
                                    "not a zip", "truncated", "no weights"])
def test_damaged_or_hostile_weights_are_refused_in_one_line(runs, tmp_path, damage):
    import pickle

    _, paths = runs
    path = paths["mappo-shared"]
    weights = _weights(path)
    name = next(iter(weights))
    if damage == "pickle":
        bad = _copied(path, tmp_path / "m", {WEIGHTS_ENTRY: pickle.dumps(object)})
    elif damage == "wrong shape":
        bad = _copied(path, tmp_path / "m", {WEIGHTS_ENTRY: _npz(**{
            **weights, name: np.zeros((3, 3), np.float32)})})
    elif damage == "float64":
        bad = _copied(path, tmp_path / "m", {WEIGHTS_ENTRY: _npz(**{
            **weights, name: weights[name].astype(np.float64)})})
    elif damage == "missing":
        bad = _copied(path, tmp_path / "m", {WEIGHTS_ENTRY: _npz(**{
            k: v for k, v in weights.items() if k != name})})
    elif damage == "no weights":
        bad = _copied(path, tmp_path / "m", {WEIGHTS_ENTRY: None})
    else:
        bad = tmp_path / path.name
        data = path.read_bytes()
        bad.write_bytes(b"junk" * 100 if damage == "not a zip" else data[:len(data) // 2])
    env = pettingzoo.make("parallel", ENV, **MONITORING)
    with pytest.raises(ConfigError) as raised:
        TeamPolicy(bad, env)
    message = str(raised.value)
    assert message.startswith(f"model {bad}") and "\n" not in message, message


def test_a_model_changed_since_saved_is_refused_by_the_manifest(runs, tmp_path):
    folder, paths = runs
    path = paths["ippo-separate"]
    original = path.read_bytes()
    try:
        path.write_bytes(original[:-1] + bytes([original[-1] ^ 1]))
        with pytest.raises(ConfigError, match="has changed since it was saved"):
            TeamPolicy(path, pettingzoo.make("parallel", ENV, **MONITORING))
    finally:
        path.write_bytes(original)


def test_a_model_of_other_robots_is_refused_in_one_line(runs):
    _, paths = runs
    env = pettingzoo.make("parallel", ENV, **{**MONITORING, "agent_id": False})
    with pytest.raises(ConfigError, match="train with the same env_kwargs") as raised:
        TeamPolicy(paths["mappo-shared"], env)
    assert "\n" not in str(raised.value)


def test_train_py_runs_a_shipped_configuration_under_the_budget_cap(tmp_path):
    """The documented command, capped by BOUNCE_GYM_MAX_TIMESTEPS (one iteration), writes
    every seed's model into the configuration's folder."""
    shipped = ROOT / "configs" / "train_multirobot_monitoring_mappo.yaml"
    config = tmp_path / "mappo.yaml"
    config.write_text(shipped.read_text().replace("hyperparams_file: hyperparams/", (
        f"models: {tmp_path / 'models'}\nhyperparams_file: {shipped.parent}/hyperparams/")))
    env = {**os.environ, "BOUNCE_GYM_MAX_TIMESTEPS": "1000", "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "train.py", str(config), "--seeds", "0",
                           "--workers", "1", "--no-progress"],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    path = tmp_path / "models" / "multirobot-monitoring-marl" / "mappo-shared_seed0.zip"
    trained = read_model(path)
    assert trained.metadata["config"]["total_timesteps"] == 1000
    assert trained.metadata["marl"]["num_timesteps"] == 16 * 128 * 2  # one whole iteration


def test_mappo_learns_monitoring_with_the_pose_observed():
    """Where learning is easy — each robot observes its pose, its index and whether it is in its
    region — MAPPO's return rises well above its first iterations' within 40 iterations (about
    60 ± 5 of 100 against 48 ± 2, seeds 0, 1, 2 measured; 100 iterations reach 87 ± 2)."""
    config = validate_train_config({
        "name": "x", "env": ENV, "algo": "mappo", "seeds": [0], "n_envs": 16,
        "total_timesteps": 10**6,
        "env_kwargs": {**MONITORING, "max_cycles": 100, "privileged": True,
                       "task_kwargs": {"regions": HALVES, "observe_region": True}},
        "hyperparams": {"n_steps": 100, "learning_rate": 1e-3, "ent_coef": 0.0}})
    learner = Learner(config, 0, ())
    returns = [np.mean([row["r"] for row in learner.iterate()]) for _ in range(40)]
    assert np.mean(returns[-3:]) > np.mean(returns[:3]) + 10, returns
