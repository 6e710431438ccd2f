"""The JAX learners end to end (``algo: jax_ppo | jax_dqn``, `baselines.rl.jaxrl`): a short run
of each through `baselines.rl.train` writes the model, its checkpoints, the monitor file and the
manifest; the model plays in the evaluation beside SB3's (sampled by default, greedy twin); the
same configuration and seed give the same weights bit for bit; the configuration checks."""
import io
import platform
import zipfile

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("jax")
pytest.importorskip("optax")

import jax  # noqa: E402

import bounce_gym  # noqa: E402,F401
from baselines.rl.curves import learning_curves  # noqa: E402
from baselines.rl.jaxrl.policy import JaxPolicy  # noqa: E402
from baselines.rl.model_files import MANIFEST, WEIGHTS_ENTRY, read_model  # noqa: E402
from baselines.rl.monitor import read_monitor  # noqa: E402
from baselines.rl.train import prepare, train  # noqa: E402
from bounce_gym.errors import ConfigError  # noqa: E402

ENV = "bounce_gym/BounceNavigation-v1"
#: short runs: a few thousand steps each, small networks (compiling dominates here)
CONFIGS = {
    "jax_ppo": {"n_envs": 4, "total_timesteps": 4096, "checkpoint_every": 2048,
                "hyperparams": {"n_steps": 64, "batch_size": 128, "n_epochs": 2,
                                "gamma": 0.9, "ent_coef": 0.01,
                                "policy_kwargs": {"net_arch": [32, 32]}}},
    "jax_dqn": {"hyperparams_file": "configs/hyperparams/dqn.yaml", "total_timesteps": 3000,
                "hyperparams": {"learning_starts": 500, "buffer_size": 8000, "batch_size": 64,
                                "gradient_steps": 1, "exploration_final_eps": 0.3,
                                "policy_kwargs": {"net_arch": [32, 32]}}},
}


def _config(algo: str, folder) -> dict:
    return {"name": "nav", "env": ENV, "algo": algo, "seeds": [0], "models": str(folder),
            **CONFIGS[algo]}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("models")
    return folder, {algo: train(_config(algo, folder), progress=False)[0] for algo in CONFIGS}


def _weights(path) -> dict[str, np.ndarray]:
    with zipfile.ZipFile(path) as archive, \
            np.load(io.BytesIO(archive.read(WEIGHTS_ENTRY)), allow_pickle=False) as npz:
        return {name: npz[name] for name in npz.files}


@pytest.mark.parametrize("algo", list(CONFIGS))
def test_a_run_writes_model_checkpoints_monitor_and_manifest(runs, algo):
    folder, paths = runs
    path = paths[algo]
    assert path == folder / "nav" / f"{algo}_seed0.zip"
    trained = read_model(path)
    assert trained.algo == algo and trained.metadata["config"]["algo"] == algo
    steps = trained.metadata["jax"]["num_timesteps"]
    made = trained.trained_with()  # the machine and libraries of this run
    assert made == trained.metadata["trained_with"]
    assert made["packages"]["jax"] == jax.__version__ and made["machine"] == platform.machine()
    assert steps >= CONFIGS[algo]["total_timesteps"]
    manifest = (folder / "nav" / MANIFEST).read_text()
    assert path.name in manifest
    checkpoints = sorted(p.name for p in (folder / "nav" / "checkpoints").glob(f"{algo}_*.zip"))
    assert f"{algo}_seed0_{steps}_steps.zip" in checkpoints
    monitor = read_monitor(folder / "nav" / f"{algo}_seed0.monitor.csv")
    assert len(monitor["r"]) > 20 and set(np.unique(monitor["is_success"])) <= {0.0, 1.0}
    assert np.all((monitor["l"] >= 1) & (monitor["l"] <= 42))
    # the sparse reward: the return of an episode is 1 exactly when it succeeded
    np.testing.assert_array_equal(monitor["r"], monitor["is_success"])
    assert monitor["steps"][-1] <= steps
    (curve,) = [run for run in learning_curves(folder / "nav") if run.name == algo]
    assert list(curve.seeds) == [0] and "success" in curve.metrics


@pytest.mark.parametrize("algo", list(CONFIGS))
def test_the_model_plays_sampled_by_default_and_greedy_as_its_twin(runs, algo):
    _, paths = runs
    env = gym.make(ENV)

    def episode(policy, seed):
        policy.start_options(env, seed)
        obs, _ = env.reset(seed=seed)
        policy.reset(env)
        actions, done = [], False
        while not done:
            actions.append(policy.act(obs, None))  # the observation only, never info
            obs, _, terminated, truncated, _ = env.step(actions[-1])
            done = terminated or truncated
        return actions

    sampled = JaxPolicy(paths[algo], env)
    greedy = JaxPolicy(paths[algo], env, deterministic=True)
    assert sampled.name == f"rl {algo}_seed0" and greedy.name == f"rl {algo}_seed0 (greedy)"
    seeds = range(10_000, 10_010)
    first = [episode(sampled, s) for s in seeds]
    assert [episode(JaxPolicy(paths[algo], env), s) for s in seeds] == first
    assert [episode(greedy, s) for s in seeds] != first


def test_the_evaluation_finds_jax_models_beside_sb3_ones(runs):
    from bounce_gym_experiments.runner import run

    folder, _ = runs
    config = {"models": str(folder), "experiments": [
        {"name": "nav-eval", "env": ENV, "seeds": {"start": 10_000, "count": 5},
         "policies": ["rl"], "rl_models": "nav"}]}
    rows, _ = run(config, progress=False)
    # v1's achieved_goal is the cell pose: every row says the pose is observed
    assert {r.policy for r in rows} == {f"rl {a}_seed0 (pose observed){g}" for a in CONFIGS
                                        for g in ("", " (greedy)")}


@pytest.mark.parametrize("algo", list(CONFIGS))
def test_same_configuration_and_seed_give_the_same_weights(runs, tmp_path, algo):
    _, paths = runs
    (again,) = train(_config(algo, tmp_path), progress=False)
    first, second = _weights(paths[algo]), _weights(again)
    assert first.keys() == second.keys()
    assert all(np.array_equal(first[k], second[k]) for k in first)


@pytest.mark.parametrize("change, field", [
    ({"resume": True}, "config.resume"),
    ({"vec_env": "sync"}, "config.vec_env"),
    ({"normalize": True}, "config.normalize"),
    ({"n_stack": 4}, "config.n_stack"),
    ({"hyperparams": {"buffer_size": 1000}}, "config.hyperparams.buffer_size"),
    ({"hyperparams": {"clip_range": "lin_0.2"}}, "config.hyperparams.clip_range"),
    ({"hyperparams": {"policy_kwargs": {"ortho_init": False}}},
     "config.hyperparams.policy_kwargs.ortho_init"),
    ({"hyperparams": {"n_steps": 64, "batch_size": 100}}, "config.hyperparams.batch_size"),
    ({"env": "bounce_gym/BounceNavigation-v0", "env_kwargs": {"backend": "pymunk"}},
     "config.env"),
])
def test_configuration_checks(tmp_path, change, field):
    config = {**_config("jax_ppo", tmp_path), "n_envs": 4, **change}
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")) as raised:
        prepare(config)
    assert "\n" not in str(raised.value)


@pytest.mark.parametrize("change, field", [
    ({"hyperparams": {"n_steps": 64}}, "config.hyperparams.n_steps"),
    ({"hyperparams": {"replay_buffer_class": "HerReplayBuffer",
                      "replay_buffer_kwargs": {"goal_selection_strategy": "final"}}},
     "config.hyperparams.replay_buffer_kwargs.goal_selection_strategy"),
    ({"env": "bounce_gym/BounceNavigation-v0", "env_kwargs": {"backend": "cell"},
      "hyperparams": {"replay_buffer_class": "HerReplayBuffer"}},
     "config.hyperparams.replay_buffer_class"),
])
def test_dqn_configuration_checks(tmp_path, change, field):
    config = {**_config("jax_dqn", tmp_path), **change}
    config.pop("hyperparams_file")
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        prepare(config)


def test_the_example_trains_and_scores_on_held_out_seeds():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).parents[3] / "examples" / "jax_ppo_navigation.py"
    spec = importlib.util.spec_from_file_location("jax_ppo_navigation", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    out = example.train_and_score(steps=2048, episodes=5)
    assert out["episodes"] == 5 and 0.0 <= out["success"] <= 1.0
    low, high = out["interval"]
    assert low <= out["success"] <= high


def test_a_jax_model_without_jax_installed_is_one_line_naming_the_extra(monkeypatch):
    import importlib.util

    from bounce_gym_experiments.families import base

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *args: None if name == "jax" else real(name, *args))
    with pytest.raises(ConfigError, match=r"pip install 'bounce-gym\[jax\]'") as raised:
        base._jax_policy()
    assert "\n" not in str(raised.value)


def _weights_file(tmp_path, npz: bytes):
    """A ModelFile holding ``npz`` as its weights (the rest of the file is not read here)."""
    from baselines.rl.model_files import ModelFile

    data = io.BytesIO()
    with zipfile.ZipFile(data, "w") as archive:
        archive.writestr(WEIGHTS_ENTRY, npz)
    return ModelFile(tmp_path / "jax_ppo_seed0.zip", "jax_ppo", data.getvalue(),
                     {WEIGHTS_ENTRY: len(npz)}, {}, {})


@pytest.mark.parametrize("save", [np.savez, np.savez_compressed])
@pytest.mark.parametrize("order", ["C", "F"])
def test_weights_are_read_as_numpy_writes_them(tmp_path, save, order):
    from baselines.rl.jaxrl.weights import read_weights

    arrays = {"pi.0.w": np.arange(12, dtype=np.float32).reshape(3, 4),
              "pi.0.b": np.array([1.5, -2.0, 0.0, 3.25], np.float32)}
    npz = io.BytesIO()
    save(npz, **{k: np.asarray(v, order=order) for k, v in arrays.items()})
    read = read_weights(_weights_file(tmp_path, npz.getvalue()),
                        {k: v.shape for k, v in arrays.items()})
    assert read.keys() == arrays.keys()
    assert all(np.array_equal(read[k], arrays[k]) and read[k].dtype == np.float32
               for k in arrays)


def test_weights_are_sized_by_the_network_before_they_are_inflated(tmp_path):
    """An ``.npz`` member is checked against the network's array, by its declared size and its
    ``.npy`` header, before its data is read; 64 MiB of zeros after a right header are refused
    without being inflated (the whole check takes under 1 MiB)."""
    import tracemalloc

    from baselines.rl.jaxrl.weights import read_weights

    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f4", "fortran_order": False,
                                                  "shape": (3, 4)})
    npz = io.BytesIO()
    with zipfile.ZipFile(npz, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("pi.0.w.npy", header.getvalue() + bytes(64 << 20))
    trained = _weights_file(tmp_path, npz.getvalue())
    tracemalloc.start()
    try:
        with pytest.raises(ConfigError, match=r"its weights 'pi.0.w' take 67108992 bytes "
                                              r"uncompressed, more than a float32\[3, 4\] array"):
            read_weights(trained, {"pi.0.w": (3, 4)})
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1 << 20
    with pytest.raises(ConfigError, match=r"its network needs 4294967296 bytes of weights, "
                                          r"more than the 1073741824"):
        read_weights(trained, {"pi.0.w": (1 << 15, 1 << 15)})
