"""Evaluate analytic planners, simple baselines and trained RL agents side by side.

    python evaluate.py                    # the default configuration (configs/eval_default.yaml)
    python evaluate.py configs/eval.yaml  # a configuration file (see configs/)

The same as ``bounce-gym evaluate`` (`bounce_gym_experiments.cli`).
"""

from __future__ import annotations

import argparse
import sys

from bounce_gym_experiments.cli import Parser, add_version_flag, dispatch, evaluate_parser


def main(argv: list[str] | None = None) -> int:
    parser = evaluate_parser(add_version_flag(Parser(description=__doc__.splitlines()[0])))
    return dispatch(parser.parse_args(argv, argparse.Namespace(command="evaluate")))


if __name__ == "__main__":
    sys.exit(main())
