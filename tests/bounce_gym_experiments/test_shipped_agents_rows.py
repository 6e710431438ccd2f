"""The shipped agents as an evaluation finds them: ``models: baselines/agents`` outside a
checkout is the installed package's folder, a learner whose extra is missing is left out with one
warning, and a folder without models names what trains them."""

from __future__ import annotations

import shutil

from baselines.shipped_agents import SHIPPED_MODELS, models_folder, shipped_agents
from bounce_gym_experiments.config import load_config, validate_config
from bounce_gym_experiments.families import base
from bounce_gym_experiments.runner import prepare_experiment


def test_the_shipped_agents_folder_is_found_from_anywhere(tmp_path, monkeypatch):
    assert models_folder(SHIPPED_MODELS) in (SHIPPED_MODELS, str(shipped_agents()))
    monkeypatch.chdir(tmp_path)  # no baselines/agents below: the package's own
    assert models_folder(SHIPPED_MODELS) == str(shipped_agents())
    assert validate_config(load_config())["models"] == str(shipped_agents())
    assert models_folder("mine") == "mine"  # any other folder as given
    (tmp_path / SHIPPED_MODELS).mkdir(parents=True)
    assert models_folder(SHIPPED_MODELS) == SHIPPED_MODELS  # a folder of that name wins


def test_jax_models_are_left_out_with_a_note_without_jax(tmp_path, monkeypatch):
    folder = tmp_path / "navigation-lab-v1"
    folder.mkdir()
    source = shipped_agents() / "navigation-lab-v1"
    for name in ("manifest.json", "dqn_seed0.zip", "jax_dqn_seed0.zip"):
        shutil.copy(source / name, folder / name)
    monkeypatch.setattr(base, "installed", lambda module: module not in base.JAX_MODULES)
    config = validate_config({"name": "t", "models": str(tmp_path), "experiments": [{
        "name": "v1", "env": "bounce_gym/BounceNavigation-v1", "greedy": False,
        "policies": ["rl"], "rl_models": ["navigation-lab-v1"],
        "seeds": {"start": 10_000, "count": 1}}]})
    prepared = prepare_experiment(config["experiments"][0], tmp_path, "config.experiments[0]")
    assert [who.policy.name for who in prepared.entrants] == ["rl dqn_seed0 (pose observed)"]
    assert prepared.warnings == [f"v1: playing the 1 JAX models of {folder} needs the 'jax' extra: "
                              "pip install 'bounce-gym[jax]'; they are left out"]


def test_a_folder_without_models_names_the_configurations_that_train_them(tmp_path):
    config = validate_config({"name": "t", "models": str(tmp_path), "experiments": [{
        "name": "nav", "env": "bounce_gym/BounceNavigation-v0", "policies": ["rl"],
        "rl_models": ["navigation-lab"], "seeds": {"start": 10_000, "count": 1}}]})
    prepared = prepare_experiment(config["experiments"][0], tmp_path, "config.experiments[0]")
    (note,) = prepared.warnings
    assert note.endswith("so no rl rows; train them with `bounce-gym train "
                         "configs/train_navigation.yaml` or `bounce-gym train "
                         "configs/train_navigation_dqn.yaml` or `bounce-gym train "
                         "configs/train_navigation_framestack.yaml` or `bounce-gym train "
                         "configs/train_navigation_recurrent.yaml`")
