"""Evaluate analytic planners, simple baselines and trained RL agents side by side.

    python evaluate.py                    # the built-in default configuration
    python evaluate.py configs/eval.yaml  # a configuration file (see configs/)

Prints a table (means per experiment and policy) and writes ``episodes.csv``, ``results.json``
and plots into ``<output>/<name>-<timestamp>/``. The configuration format is documented in
`experiments.evaluation`.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import yaml

from bounce_gym.errors import ConfigError
from experiments.evaluation import DEFAULT_CONFIG, run, summarise, validate_config
from experiments.report import format_table, write_plots, write_results


def load_config(path: str | None) -> dict:
    if path is None:
        return DEFAULT_CONFIG
    file = Path(path)
    if not file.is_file():
        raise ConfigError(f"config: file {path!r} does not exist")
    try:
        return yaml.safe_load(file.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise ConfigError(f"config: {path} is not valid YAML: {exc}") from None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", help="YAML configuration (default: built-in)")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    args = parser.parse_args(argv)
    try:
        config = validate_config(load_config(args.config))
        rows, plots = run(config, progress=not args.no_progress)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    summary = summarise(rows)
    print(format_table(summary))
    folder = Path(config["output"]) / f"{config['name']}-{time.strftime('%Y%m%d-%H%M%S')}"
    write_results(folder, [r.row() for r in rows], summary, config)
    written = write_plots(folder, plots, summary)
    print(f"\nwrote {folder}/episodes.csv, results.json and {len(written)} plots")
    return 0


if __name__ == "__main__":
    sys.exit(main())
