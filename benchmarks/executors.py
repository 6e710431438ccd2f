"""Evaluation sweeps on the three executors (issue #17): the wall time of the same evaluation
with one worker (in one process), the local pool of two workers and Ray (a local instance of
two CPUs), and the sha256 of each run's ``episodes.csv`` and ``results.json``, which must be
the same for all three.

Run with ``python -m benchmarks.executors`` (``--config``: the evaluations, default
``configs/eval_multirobot.yaml`` and ``configs/benchmark.yaml``; ``--seeds N``: every experiment
on its first N seeds; ``--quick``: the multi-robot study on 2 seeds). Prints rows; asserts
nothing. Each run is the whole command, ``python evaluate.py <config> --no-progress`` with the
executor's flags, in a fresh process timed from outside (imports, preparing the experiments,
Ray's start, the episodes and the files: what a user waits for), once per executor, one after
another. The runs execute a copy of the checkout taken before the first (`snapshot`): its files
may change while the benchmark runs (minutes on a loaded machine), and a run reading the checkout
itself would then execute other code, or record another git state in its ``results.json``
(``provenance``), than the runs before it. The machine's load average before and after is
printed too: on a shared machine the pool's and Ray's gain is what the cores left over allow.
Ray's row is skipped, with a line saying so, when ray is not installed (``pip install
bounce-gym[distributed]``).
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

from bounce_gym_experiments.run_folders import finished_runs

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ("configs/eval_multirobot.yaml", "configs/benchmark.yaml")
#: executor: its flags
EXECUTORS = {"1 worker": ["--workers", "1"], "local pool (2)": ["--workers", "2"],
             "ray (local, 2 CPUs)": ["--executor", "ray", "--workers", "2"]}
FILES = ("episodes.csv", "results.json")


def _config(source: Path, folder: Path, seeds: int | None) -> Path:
    """``source`` writing into ``folder/runs``, its model folders and map files read where
    ``source`` names them, on the first ``seeds`` seeds of every experiment (all if ``None``)."""
    from bounce_gym_experiments.config import load_config

    config = load_config(source)  # map files resolved against the source's folder
    config["output"] = str(folder / "runs")
    config["models"] = str(Path(config.get("models", "models")).resolve())
    if seeds is not None:
        for exp in config["experiments"]:
            exp["seeds"] = {"start": 10_000, "count": seeds}
    path = folder / "config.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    return path


def snapshot(checkout: Path, into: Path) -> Path:
    """A copy in ``into`` of the files of the git checkout ``checkout`` — tracked ones as they
    are now, uncommitted changes included, and untracked ones that are not ignored — for runs
    that must all execute the same code and record the same provenance, whatever happens to the
    checkout meanwhile; ``checkout`` itself when it is not a git checkout (nothing there records
    a git state)."""
    try:
        listed = subprocess.run(["git", "-C", str(checkout), "ls-files", "-z", "--cached",
                                 "--others", "--exclude-standard"], capture_output=True,
                                check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return checkout
    for name in filter(None, listed.decode().split("\0")):
        if (checkout / name).is_file():  # not a tracked file deleted from the work tree
            (into / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(checkout / name, into / name)
    return into


def run_one(config: Path, flags: list[str], folder: Path, code: Path) -> dict:
    """One timed run of ``code``'s ``evaluate.py``: seconds and the checksums of its files."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, str(code / "evaluate.py"), str(config),
                           "--no-progress", *flags], capture_output=True, text=True,
                          env={**os.environ, "RAY_USAGE_STATS_ENABLED": "0"})
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"evaluate.py {config} {' '.join(flags)} failed: "
                           f"{done.stderr.strip().splitlines()[-1:]}")
    (run,) = finished_runs(folder / "runs")
    out = {"seconds": seconds, **{f: hashlib.sha256((run / f).read_bytes()).hexdigest()
                                  for f in FILES}}
    shutil.rmtree(run)  # the next executor writes the same run folder afresh
    return out


def bench(source: Path, seeds: int | None) -> dict[str, dict]:
    """Every executor on one evaluation, all running one `snapshot` of the checkout (ray left
    out when it is not installed)."""
    rows = {}
    with tempfile.TemporaryDirectory(prefix="bench-executors-") as tmp:
        folder = Path(tmp)
        config = _config(source, folder, seeds)
        code = snapshot(ROOT, folder / "source")
        for name, flags in EXECUTORS.items():
            if "ray" in flags and importlib.util.find_spec("ray") is None:
                continue
            rows[name] = run_one(config, flags, folder, code)
    return rows


def main(argv: list[str] | None = None) -> dict[str, dict[str, dict]]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", nargs="+", help=f"evaluations (default: {CONFIGS})")
    parser.add_argument("--seeds", type=int, help="the first N seeds of every experiment")
    parser.add_argument("--quick", action="store_true",
                        help="the multi-robot study on 2 seeds")
    args = parser.parse_args(argv)
    configs = args.config or ([CONFIGS[0]] if args.quick else list(CONFIGS))
    seeds = 2 if args.quick and args.seeds is None else args.seeds
    print("executors: wall time of `python evaluate.py <config>` per executor (issue #17), "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} before")
    out = {}
    for config in configs:
        source = Path(config) if Path(config).is_absolute() else ROOT / config
        rows = bench(source, seeds)
        out[config] = rows
        label = config + ("" if seeds is None else f" ({seeds} seeds per experiment)")
        print(f"\n{label}")
        print(f"{'executor':<22} {'wall s':>8} {'x 1 worker':>11}  sha256 of episodes.csv, "
              "results.json")
        base = rows["1 worker"]["seconds"]
        for name, row in rows.items():
            print(f"{name:<22} {row['seconds']:>8.1f} {base / row['seconds']:>10.2f}x  "
                  f"{row['episodes.csv']}, {row['results.json']}", flush=True)
        if len(rows) < len(EXECUTORS):
            print("ray (local, 2 CPUs): skipped (ray is not installed; pip install "
                  "bounce-gym[distributed])")
        same = len({(r["episodes.csv"], r["results.json"]) for r in rows.values()}) == 1
        print("identical files for every executor" if same else "FILES DIFFER between executors")
    print(f"\nload average {os.getloadavg()[0]:.1f} after")
    return out


if __name__ == "__main__":
    main()
