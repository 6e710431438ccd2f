"""``bounce-gym train``: several seeds in one command, what it prints and writes, and the
evaluation scoring every seed's model."""

import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import train  # noqa: E402
from bounce_gym_experiments.runner import run  # noqa: E402

NAV = {"world": "square", "backend": "cell", "angles": [90, 135]}


def test_the_seeds_flag_trains_each_seed_and_the_evaluation_scores_them(tmp_path, capsys,
                                                                        monkeypatch):
    monkeypatch.chdir(tmp_path)
    config = {"name": "nav", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
              "algo": "ppo", "total_timesteps": 10_000, "seed": 0, "n_envs": 2,
              "hyperparams": {"n_steps": 64, "batch_size": 64, "n_epochs": 1}}
    Path("t.yaml").write_text(yaml.safe_dump(config), encoding="utf-8")
    assert train.main(["t.yaml", "--seeds", "3", "7", "--timesteps", "512",
                       "--no-progress"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[:2] == ["ppo_seed3: training 512 steps", "ppo_seed7: training 512 steps"]
    assert "saved models/nav/ppo_seed3.zip" in out and "saved models/nav/ppo_seed7.zip" in out
    assert out[-2].startswith("ppo: 2 seeds, at ")
    folder = tmp_path / "models" / "nav"
    assert sorted(p.name for p in folder.glob("*.monitor.csv")) == [
        "ppo_seed3.monitor.csv", "ppo_seed7.monitor.csv"]
    assert (folder / "learning_curves.png").is_file()
    rows, _ = run({"models": str(tmp_path / "models"), "experiments": [
        {"name": "nav", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
         "seeds": [10_000], "max_steps": 10, "horizon_reason": "a short smoke run",
         "policies": ["rl"]}]}, progress=False)
    assert sorted(r.policy for r in rows) == ["rl ppo_seed3", "rl ppo_seed3 (greedy)",
                                              "rl ppo_seed7", "rl ppo_seed7 (greedy)"]
