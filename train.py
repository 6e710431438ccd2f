"""Train a Stable-Baselines3 agent on a bounce_gym environment from a YAML configuration.

    python train.py configs/train_navigation.yaml

The model is saved as ``models/<name>/<algo>_seed<seed>.zip``, where ``evaluate.py`` finds it for
the experiment of the same name (or those with ``rl_models: <name>``). With a multi-robot
PettingZoo id (``python train.py configs/train_multirobot_coverage.yaml``) all robots train one
shared PPO policy. The configuration format is documented in `baselines.rl.train`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import yaml

from bounce_gym.errors import ConfigError


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", help="YAML training configuration")
    parser.add_argument("--timesteps", type=int, help="override total_timesteps")
    parser.add_argument("--resume", action="store_true", help="continue from the saved model")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    from baselines.rl.train import train

    try:
        path = Path(args.config)
        if not path.is_file():
            raise ConfigError(f"config: file {args.config!r} does not exist")
        config = yaml.safe_load(path.read_text(encoding="utf-8"))
        if isinstance(config, dict) and args.timesteps is not None:
            config["total_timesteps"] = args.timesteps
        if isinstance(config, dict) and args.resume:
            config["resume"] = True
        out = train(config, progress=not args.no_progress)
    except (ConfigError, yaml.YAMLError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"saved {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
