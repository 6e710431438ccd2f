"""The ``bounce-gym`` command: evaluate planners, baselines and trained agents; train agents.

    bounce-gym evaluate [config.yaml] [--no-progress]
    bounce-gym train config.yaml [--timesteps N] [--resume] [--no-progress]
    bounce-gym trust models/<name>/<algo>_seed<N>.zip ...

``evaluate`` prints tables (per experiment and policy, every cell with its 95% interval and
count) and writes ``episodes.csv``, ``summary.csv``, ``results.json``, plots and, for a
configuration with ``leaderboard: true``, ``leaderboard.md`` and ``leaderboard.csv`` into
``<output>/<name>-<timestamp>/``; without a configuration it runs
the default one (``eval_default.yaml``; format: `experiments.config`). ``train`` saves the model
as ``models/<name>/<algo>_seed<seed>.zip``, where ``evaluate`` finds it (format:
`baselines.rl.train`), listed in ``models/<name>/manifest.json``; ``evaluate`` loads only listed
model files, and ``trust`` lists one obtained elsewhere (`baselines.rl.model_files`). A mistake
in a configuration, an env argument or a model file is one line ``error: ...`` on stderr and
exit status 2, reported before any long work starts.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from bounce_gym.errors import BounceGymError


def evaluate(config_path: str | None, progress: bool = True) -> int:
    """Run an evaluation configuration, print the tables and write the run folder."""
    from bounce_gym.files import check_writable
    from experiments.config import load_config, validate_config
    from experiments.leaderboard import write_leaderboard
    from experiments.provenance import provenance
    from experiments.report import (
        families_of,
        format_table,
        notes_of,
        summarise,
        table_rows,
        write_plots,
        write_results,
    )
    from experiments.runner import run

    config = validate_config(load_config(config_path))
    check_writable("config.output", Path(config["output"]))
    rows, plots = run(config, progress=progress)
    families, notes, made = families_of(plots), notes_of(plots), provenance()
    summary, per_seed = table_rows(summarise(rows, families), rows)
    print(format_table(summary, families))
    for note in notes:
        print(f"note: {note}")
    folder = Path(config["output"]) / f"{config['name']}-{time.strftime('%Y%m%d-%H%M%S')}"
    write_results(folder, [r.row() for r in rows], summary, config, per_seed, notes, made)
    written = write_plots(folder, plots, summary, per_seed)
    if config["leaderboard"]:
        written += write_leaderboard(folder, config, summary, families, notes, made)
    print(f"\nwrote {folder}/episodes.csv, summary.csv, results.json and {len(written)} other "
          "files" + (" (leaderboard.md, leaderboard.csv, plots)" if config["leaderboard"]
                     else " (plots)"))
    return 0


def train(config_path: str, timesteps: int | None = None, resume: bool = False,
          progress: bool = True) -> int:
    """Train (or resume) the agent of a training configuration and report where it is saved."""
    from baselines.rl.train import train as train_agent
    from experiments.config import load_config

    config = load_config(config_path)
    if isinstance(config, dict) and timesteps is not None:
        config["total_timesteps"] = timesteps
    if isinstance(config, dict) and resume:
        config["resume"] = True
    print(f"saved {train_agent(config, progress=progress)}")
    return 0


def trust(paths: list[str]) -> int:
    """List model files in their folders' manifests, so that ``evaluate`` loads them."""
    from baselines.rl.model_files import trust as trust_file

    for path in paths:
        print(f"trusted {path} (sha256 {trust_file(Path(path))})")
    return 0


def evaluate_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("config", nargs="?", help="YAML configuration (default: eval_default.yaml)")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    return parser


def train_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("config", help="YAML training configuration")
    parser.add_argument("--timesteps", type=int, help="override total_timesteps")
    parser.add_argument("--resume", action="store_true", help="continue from the saved model")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    return parser


def trust_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("models", nargs="+", help="model files (<algo>_seed<N>.zip) to trust")
    return parser


def dispatch(args: argparse.Namespace) -> int:
    """Run the parsed command; an input error of this package (`BounceGymError`: a bad
    configuration, env argument or model file) becomes ``error: ...`` on stderr and status 2."""
    try:
        if args.command == "evaluate":
            return evaluate(args.config, progress=not args.no_progress)
        if args.command == "trust":
            return trust(args.models)
        return train(args.config, args.timesteps, args.resume, progress=not args.no_progress)
    except BounceGymError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="bounce-gym", description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    evaluate_parser(commands.add_parser("evaluate", help="evaluate policies side by side"))
    train_parser(commands.add_parser("train", help="train a Stable-Baselines3 agent"))
    trust_parser(commands.add_parser("trust", help="let evaluate load these model files"))
    return dispatch(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
