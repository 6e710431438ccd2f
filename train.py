"""Train agents on a bounce_gym environment from a YAML configuration (any learner of
``bounce-gym train``: Stable-Baselines3, JAX or multi-robot).

    python train.py configs/train_navigation.yaml

The same as ``bounce-gym train`` (`bounce_gym_experiments.cli`).
"""

from __future__ import annotations

import argparse
import sys

from bounce_gym_experiments.cli import Parser, add_version_flag, dispatch, train_parser


def main(argv: list[str] | None = None) -> int:
    parser = train_parser(add_version_flag(Parser(description=__doc__.splitlines()[0])))
    return dispatch(parser.parse_args(argv, argparse.Namespace(command="train")))


if __name__ == "__main__":
    sys.exit(main())
