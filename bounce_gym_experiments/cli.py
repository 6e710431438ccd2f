"""The ``bounce-gym`` command: evaluate planners, baselines and trained agents; train agents.

    bounce-gym evaluate [config.yaml] [--executor local|ray] [--workers N] [--address ADDR]
                        [--no-progress]
    bounce-gym train config.yaml [--timesteps N] [--seeds S ...] [--resume]
                     [--executor local|ray] [--workers N] [--address ADDR] [--no-progress]
    bounce-gym tune config.yaml [--space FILE] [--trials N] [--metric return|success]
                    [--scheduler fifo|asha] [--workers N] [--address ADDR] ...
    bounce-gym curves models/<name> [--window EPISODES]
    bounce-gym trust models/<name>/checkpoints/<algo>_seed<N>_<steps>_steps.zip ...
    bounce-gym schema evaluation|training | --write
    bounce-gym tables [--write] [--from RUN_FOLDER [--into docs/results/benchmark]]
    bounce-gym envs

``evaluate`` prints who wins (`bounce_gym_experiments.leaderboard.who_wins_text`: per
experiment, the best planner, trained agent and random bouncing, in 100 columns) and writes
``episodes.csv``, ``summary.csv``, ``results.json``, ``tables.txt`` (per experiment and policy,
every cell with its 95% interval and count; ``--tables`` prints them too), unless the
configuration says ``plots: false`` the plots, and for a configuration with
``leaderboard: true`` ``leaderboard.md``, ``leaderboard.csv`` and ``verdicts.csv`` into
``<output>/<name>-<timestamp>/``, which appears only once all of them are written (they are
written into a hidden ``.<name>-<timestamp>.tmp-<random>`` beside it, `bounce_gym_experiments.run_folders`);
without a configuration it runs the default one (``eval_default.yaml``; format:
`bounce_gym_experiments.config`). ``train`` saves a model per seed as
``models/<name>/<algo>_seed<seed>.zip``, where ``evaluate`` finds it (format:
`baselines.rl.train`), recorded in ``models/<name>/manifest.json``, and then draws the folder's
learning curves, as ``curves`` does at any time (``learning_curves.png`` and ``.csv``,
`bounce_gym_experiments.plots.learning_curves`). Model files are data: ``evaluate`` loads any, unpickling
nothing in them, and refuses one the manifest records with other content. ``trust`` adds a
file's sha256 to the user's own trusted digests (``$BOUNCE_GYM_HOME``, `bounce_gym.trust`),
which only ``--resume`` needs, for a checkpoint this user's runs did not sign
(``docs/model_files.md``). A mistake in a configuration, an env argument, a flag or a model
file is one line ``error: ...`` on stderr and exit status 2, reported before any long work
starts — among them a name that becomes part of a path but is not one plain path component, or
a symbolic link planted where a command writes its own files (`bounce_gym.files`); a
configuration's (`bounce_gym.documents` reads every file, each command's module checks the
numbers) before anything heavy (torch, SB3, Ray) is imported. So is a command whose extra is
not installed (``evaluate`` and ``curves`` need ``experiments``, ``train`` also ``rl`` or
``jax``, ``tune`` also ``rl`` and ``distributed``; `bounce_gym.extras`): ``error: bounce-gym
evaluate needs the 'experiments' extra: pip install 'bounce-gym[experiments]'``. A fault of
the machine — a full disk, a folder that is not writable — is one ``error:`` line naming the
path too (`bounce_gym.errors.OutputError`; an `OSError` raised elsewhere, e.g. by a library's
own file, as ``error: <path>: <reason>``), status 2, and leaves no partial file under a name
the command writes.

``evaluate`` runs its units — one policy of one experiment on up to ten seeds
(`bounce_gym_experiments.sweep`) — on the configuration's ``executor`` or the one the flags choose
(`bounce_gym_experiments.executors`): by default a local process pool over the machine's cores
(``--workers 1``: one after another in this process), or Ray (``--executor ray``, on the
cluster at ``--address`` or a local instance). Finished units are kept in
``<output>/<name>-units/`` until the run folder is written, so that the same command started
again after an interruption runs only the rest and writes the same files; they are signed with
the user's key (`bounce_gym.trust`), and a unit file that is not is one ``warning:`` line and
its unit runs again. A unit that fails for good (after its retries) is one line
``error: unit ...`` on stderr each, once the other units are done; then no run folder is
written and the exit status is 1.

``train`` runs one unit per seed on the same executors (`bounce_gym_experiments.training`; locally no
more workers than seeds, so one seed trains in this process); with ``--resume`` it skips the
seeds whose model is saved and continues the others from their checkpoints. A seed that fails
for good is ``error: <run>_seed<N> failed after ...`` (status 1) once the others are saved.
``tune`` searches hyperparameters with Ray Tune (`bounce_gym_experiments.search`): trials are training runs
in ``models/<name>-tune/``, summarised in ``trials.csv`` and ``best_hyperparams.yaml``.

``schema`` prints the JSON Schema of the evaluation or the training configuration, generated
from their models (`bounce_gym_experiments.schema`); ``schema --write`` writes both into the
shipped ``configs/schema/``, where editors find them.

``tables`` checks the result tables of README.md and docs/ against the leaderboard files they
cite (exit 1 and one ``stale:`` line each where they differ); ``--write`` regenerates them,
after ``--from RUN_FOLDER`` copied a run's leaderboard files into ``--into``
(`bounce_gym_experiments.published`).

``envs`` lists every registered environment id with what it is, one line each (`bounce_gym.envs.registration.SUMMARY`).

``bounce-gym --version`` or ``-V`` (and ``train.py``'s, ``evaluate.py``'s) prints the installed
distribution's version, ``bounce-gym <version>``. Flags are never abbreviated: ``--worker 2`` is
an unknown flag, not ``--workers 2``, and the error names the flag meant and the positional that
took the word after it (``evaluate --worker 1`` reads 1 as the configuration). A configuration
must be an existing file or a name ending ``.yaml``/``.yml``. ``--help`` is plain text: the
docstrings' markup is left out.

The environment variable ``BOUNCE_GYM_MAX_TIMESTEPS=N`` caps every training run at N env steps
(SB3 still finishes the iteration it is in): a smoke test of a documented training command,
which then runs exactly as written.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.metadata
import os
import re
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import NoReturn

from baselines.rl.model_files import ALGO_FAMILIES
from bounce_gym.errors import BounceGymError
from bounce_gym.extras import from_import_error, require


def evaluate_command(config_path: str | None, progress: bool = True,
                     flags: Mapping[str, str] | None = None,
                     experiments: list[str] | None = None, show_tables: bool = False) -> int:
    """Run an evaluation configuration on its executor (``flags``: the executor flags given,
    `executor_from`), print who wins (and with ``show_tables`` every table) and write the run
    folder (the tables in ``tables.txt``); if units fail for good, say which and return 1,
    keeping the finished units for the next run. ``experiments``: run only the experiments of
    these names (`select_experiments`)."""
    from bounce_gym_experiments.config import load_config, validate_config

    # before the heavy imports below
    config = select_experiments(validate_config(load_config(config_path)), experiments)
    import shutil

    from bounce_gym.errors import ConfigError
    from bounce_gym.files import atomic_write, check_writable, refuse_links
    from bounce_gym.provenance import provenance
    from bounce_gym_experiments.executors import UnitStore
    from bounce_gym_experiments.leaderboard import verdicts, who_wins_text, write_leaderboard
    from bounce_gym_experiments.report import (
        families_of,
        format_table,
        notes_of,
        table_rows,
        warnings_of,
        write_plots,
        write_results,
    )
    from bounce_gym_experiments.run_folders import new_run_folder
    from bounce_gym_experiments.runner import run
    from bounce_gym_experiments.sweep import UnitsFailedError, store_folder

    output = Path(config["output"])
    check_writable("config.output", output)
    executor = executor_from(config.get("executor"), flags or {})
    store = UnitStore(store_folder(config))
    refuse_links("config.output", output, store.folder)
    try:
        rows, plots = run(config, progress=progress, executor=executor, store=store)
    except UnitsFailedError as exc:
        for line in exc.lines:
            print(f"error: {line}", file=sys.stderr)
        print(f"note: {exc.total - len(exc.failures)} of {exc.total} units finished and are "
              f"kept in {exc.store}; run the same command again to run only the others",
              file=sys.stderr)
        return 1
    families, made = families_of(plots), provenance()
    warned, notes = warnings_of(plots), notes_of(plots)
    summary, per_seed = table_rows(rows, families)
    episodes = [r.row() for r in rows]
    decided = verdicts(summary, episodes, families)  # the bootstraps, once
    table_text = format_table(summary, families)
    if show_tables:
        print(table_text)
    for line in warned:
        print(f"warning: {line}", file=sys.stderr)
    for note in notes:
        print(f"note: {note}")
    notes = warned + notes  # the files keep both
    run_folder = new_run_folder(config)
    with run_folder as folder:  # appears whole, once everything is written
        write_results(folder, episodes, summary, config, per_seed, notes, made)
        atomic_write(folder / TABLES_FILE, (table_text + "\n").encode())
        written = write_plots(folder, plots, summary, per_seed) if config["plots"] else []
        if config["leaderboard"]:
            written += write_leaderboard(folder, config, summary, decided, families, notes,
                                         made)
    try:  # the run folder now holds the results; never delete through a planted link
        refuse_links("config.output", output, store.folder)
    except ConfigError as exc:
        print(f"warning: {exc}; the finished units are left in place", file=sys.stderr)
    else:
        shutil.rmtree(store.folder, ignore_errors=True)
        with contextlib.suppress(OSError):  # the sweeps' folder, once no other sweep is kept
            store.folder.parent.rmdir()
    others = ["leaderboard.md, leaderboard.csv, verdicts.csv"] if config["leaderboard"] else []
    others += ["plots"] if config["plots"] else []
    print(f"\nwrote {run_folder.path}/episodes.csv, summary.csv, results.json, {TABLES_FILE}"
          + (f" and {len(written)} other files ({', '.join(others)})" if written else ""))
    report = run_folder.path / ("leaderboard.md" if config["leaderboard"] else TABLES_FILE)
    print("\n" + who_wins_text(decided, f"{report}"))
    return 0


#: the file of a run folder holding every table of the evaluation as text
TABLES_FILE = "tables.txt"


def select_experiments(config: dict, names: list[str] | None) -> dict:
    """``config`` with only the experiments named (in the configuration's order; None: all of
    them); an unknown name is a `ConfigError` that suggests the nearest."""
    from bounce_gym.errors import ConfigError
    from bounce_gym.validate import did_you_mean

    if names is None:
        return config
    known = [exp["name"] for exp in config["experiments"]]
    unknown = [name for name in names if name not in known]
    if unknown:
        raise ConfigError(f"--experiments: no experiment named {unknown[0]!r} in the "
                          f"configuration"
                          + (f"; {hint}" if (hint := did_you_mean(unknown[:1], known)) else ""))
    return {**config, "experiments": [exp for exp in config["experiments"]
                                      if exp["name"] in names]}


#: the executor flags, by the key of an ``executor`` block each sets
EXECUTOR_FLAGS = {"kind": "--executor", "workers": "--workers", "address": "--address"}


def executor_from(block: Mapping | None, flags: Mapping[str, str]):
    """The executor of a configuration's ``executor`` block (validated) with the flags given
    (``{"kind": "ray", "workers": "4"}``) over it; a bad flag is a `ConfigError` naming it."""
    from bounce_gym_experiments.executors import make_executor

    return make_executor(**executor_block(block, flags))


def executor_block(block: Mapping | None, flags: Mapping[str, str]) -> dict:
    """The checked and completed settings (`bounce_gym_experiments.executors.executor_settings`) of a
    configuration's ``executor`` block with the flags given over it; a Ray cluster it names
    must answer now (`bounce_gym_experiments.executors.check_ray_cluster`), not when the first unit
    starts."""
    from bounce_gym_experiments.executors import check_ray_cluster, executor_settings

    given = {key: _number(value) if key == "workers" else value
             for key, value in flags.items() if value is not None}
    names = {key: EXECUTOR_FLAGS[key] for key in given}
    settings = executor_settings({**(block or {}), **given}, "config.executor", names)
    if settings["address"] is not None:
        check_ray_cluster(names.get("address", "config.executor.address"), settings["address"])
    return settings


def _number(text: str) -> int | str:
    """A flag's digits as an int (of at most 9: no more is a count of workers); anything else
    stays text, for the check to name."""
    return int(text) if text.isascii() and text.isdigit() and len(text) <= 9 else text


def add_executor_flags(parser: argparse.ArgumentParser) -> None:
    """``--executor``, ``--workers`` and ``--address`` (`EXECUTOR_FLAGS`)."""
    parser.add_argument("--executor", metavar="local|ray",
                        help="where units run: local (a process pool; default) or ray")
    parser.add_argument("--workers", metavar="N",
                        help="units at once (default: the machine's cores; 1: in this process)")
    parser.add_argument("--address", metavar="ADDR",
                        help="a running Ray cluster's address (default: start a local one)")


def executor_flags(args: argparse.Namespace) -> dict[str, str | None]:
    """The executor flags of parsed arguments, by `EXECUTOR_FLAGS` key."""
    return {key: getattr(args, flag[2:]) for key, flag in EXECUTOR_FLAGS.items()}


#: The environment variable capping every training run (module docstring).
MAX_TIMESTEPS = "BOUNCE_GYM_MAX_TIMESTEPS"


def train_command(config_path: str, timesteps: int | None = None, resume: bool = False,
          progress: bool = True, seeds: list[int] | None = None,
          flags: Mapping[str, str | None] | None = None) -> int:
    """Train (or resume) the agents of a training configuration, one unit per seed on its
    executor (``flags``: the executor flags given, over the configuration's ``executor``;
    `bounce_gym_experiments.training`), report where they are saved, and draw the folder's learning
    curves. A seed that fails for good is reported (status 1) after the others are saved."""
    from bounce_gym_experiments.config import load_config
    from bounce_gym_experiments.training import sweep

    config = training_config(load_config(config_path), timesteps, resume, seeds)
    block = config.pop("executor", None) if isinstance(config, dict) else None
    paths, failures = sweep(config, executor_block(block, flags or {}),
                            folder=Path(config_path).parent, progress=progress)
    for path in paths:
        print(f"saved {path}")
    for failure in failures:
        print(f"error: {failure.key} failed after {failure.attempts} attempts: {failure.error}",
              file=sys.stderr)
    if paths:
        curves_command(str(paths[0].parent), required=False)
    return 1 if failures else 0


def training_config(config: object, timesteps: int | None = None, resume: bool = False,
                    seeds: list[int] | None = None) -> object:
    """A loaded training configuration with the command's overrides and the budget cap
    (`MAX_TIMESTEPS`) applied; a non-mapping is returned as it is, for the validation to
    report."""
    from bounce_gym.errors import ConfigError

    if not isinstance(config, dict):
        return config
    for key, value in (("total_timesteps", timesteps), ("seeds", seeds)):
        if value is not None:
            config[key] = value
    if seeds is not None:
        config.pop("seed", None)
    if resume:
        config["resume"] = True
    cap = os.environ.get(MAX_TIMESTEPS)
    if cap is not None:
        if not (cap.isascii() and cap.isdigit() and len(cap) <= 18) or int(cap) < 1:
            shown = cap if len(cap) <= 18 else f"{cap[:15]}..."  # no number of 19 digits is meant
            raise ConfigError(f"{MAX_TIMESTEPS}: expected an integer >= 1, got {shown!r}")
        budget = config.get("total_timesteps", int(cap))
        config["total_timesteps"] = min(budget, int(cap)) if isinstance(budget, int) \
            else budget
    return config


def tune_command(config_path: str, space: str | None = None, trials: int = 8, metric: str = "return",
         scheduler: str = "fifo", seed: int = 0, timesteps: int | None = None,
         resume: bool = False, workers: int | None = None, address: str | None = None,
         progress: bool = True) -> int:
    """Search hyperparameters of a training configuration with Ray Tune
    (`bounce_gym_experiments.search`), print the trials and write their table and the best entry. The
    flags are checked first, then the configuration and the search space, then every trial."""
    from bounce_gym_experiments.config import load_config
    from bounce_gym_experiments.search import (
        check_search,
        default_space,
        search_folder,
        trial_configs,
        tune_search,
    )

    check_search(metric, scheduler, workers, address)
    config = training_config(load_config(config_path), timesteps, resume)
    if isinstance(config, dict):
        config.pop("executor", None)  # the trials run on Ray Tune: --workers, --address
    path = Path(space) if space is not None else default_space(Path(config_path), config)
    prepared = trial_configs(config, path, trials, seed, folder=Path(config_path).parent)
    done = tune_search(prepared, metric, scheduler, workers, address, progress)
    for trial in done:
        print(f"trial {trial.index}: {trial.status}, {metric} {trial.metric:.4g} after "
              f"{trial.episodes} episodes ({trial.env_steps} env steps), {trial.hyperparams}")
    folder = search_folder(config)
    print(f"wrote {folder}/trials.csv" + (f" and {folder}/best_hyperparams.yaml"
                                          if (folder / "best_hyperparams.yaml").is_file()
                                          else ""))
    return 0


def curves_command(folder: str, window: int | None = None, required: bool = True) -> int:
    """Draw the learning curves of a models folder and print where each run ended (a
    `ConfigError` if no episode has finished yet, unless not ``required``)."""
    from baselines.rl.curves import WINDOW
    from bounce_gym.errors import ConfigError
    from bounce_gym_experiments.plots.learning_curves import write_learning_curves

    written, lines = write_learning_curves(Path(folder), WINDOW if window is None else window)
    if not written:
        if required:
            raise ConfigError(f"curves: {folder} holds no monitor file with a finished "
                              "episode; train first")
        print("no episode has finished yet: no learning curves")
        return 0
    print("\n".join(lines))
    print(f"wrote {' and '.join(str(p) for p in written)}")
    return 0


def trust_command(paths: list[str]) -> int:
    """Add the sha256 of these model files to the user's trusted digests, so that ``--resume``
    unpickles the resume state of checkpoints this user's runs did not sign."""
    from baselines.rl.model_files import trust as trust_file
    from bounce_gym.trust import TRUSTED_FILE, home

    for path in paths:
        print(f"trusted {path} (sha256 {trust_file(Path(path))}, in {home() / TRUSTED_FILE})")
    return 0


def schema_command(name: str | None, write: bool) -> int:
    """Print the JSON Schema of configuration ``name``, or write every schema where they
    ship."""
    from bounce_gym.errors import ConfigError
    from bounce_gym_experiments.schema import schema_text, write_schemas

    if write == (name is not None):
        raise ConfigError("schema: give a configuration (evaluation or training) to print its "
                          "schema, or --write to write them all")
    if write:
        print("\n".join(f"wrote {path}" for path in write_schemas()))
    else:
        print(schema_text(name), end="")
    return 0


class Parser(argparse.ArgumentParser):
    """argparse's parser, whose usage mistakes (an unknown flag, a value of the wrong type or
    not among the choices) are one line ``error: ...`` and exit status 2, as every mistake of
    the command is; ``--help`` shows the usage, as plain text (`plain`). A flag is given in
    full: argparse's abbreviations (``--worker`` for ``--workers``) are refused as unknown
    flags, so that a typo never becomes another flag, and the error says which flag it likely
    stands for and which positional took the word after it (`usage_mistake`). Its subcommands'
    parsers are of this class."""

    #: the subcommands' action, once `add_subparsers` made it
    commands: argparse._SubParsersAction | None = None

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **{**kwargs, "allow_abbrev": False})

    def add_subparsers(self, **kwargs) -> argparse._SubParsersAction:
        self.commands = super().add_subparsers(**kwargs)
        return self.commands

    def parse_args(self, args=None, namespace=None) -> argparse.Namespace:
        argv = sys.argv[1:] if args is None else list(args)
        parsed, extras = self.parse_known_args(argv, namespace)
        command = self.commands.choices[parsed.command] if self.commands else self
        mistake = usage_mistake(command, [self, command], parsed, argv, extras)
        if mistake:
            command.error(mistake)
        return parsed

    def format_help(self) -> str:
        return plain(super().format_help())

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"error: {message} (see {self.prog} --help)\n")


#: reST and Sphinx markup in docstrings: the backticks around a name and a role before them
_MARKUP = re.compile(r"(?::[\w.:-]+:)?`+")


def plain(text: str) -> str:
    """``text`` without its reST markup (````name````, ```name```, ``:role:`name```): help is
    read in a terminal."""
    return _MARKUP.sub("", text)


#: the positional that names a configuration file (evaluate, train, tune)
CONFIG = "config"


def usage_mistake(command: argparse.ArgumentParser, parsers: list[argparse.ArgumentParser],
                  parsed: argparse.Namespace, argv: list[str], extras: list[str]) -> str:
    """What is wrong with a command line (``argv``) that argparse parsed into ``parsed`` and
    ``extras``, the words it did not recognise (``""``: nothing): those words, with the flag
    each unknown flag likely stands for (among the flags of ``parsers``), and the positionals of
    ``command`` that took a word they should not have (`misread_words`)."""
    unknown = [word for word in extras if word.startswith("-")]
    misread = misread_words(command, parsed, argv, unknown)
    if not extras:
        return "; ".join(f"argument {dest}: {word} is neither a file nor a .yaml/.yml name"
                         for dest, word in misread)
    from bounce_gym.validate import did_you_mean

    flags = [flag for parser in parsers for action in parser._actions
             for flag in action.option_strings]
    hint = did_you_mean([word.split("=")[0] for word in unknown], flags)
    return (f"unrecognized arguments: {' '.join(extras)}" + (f" ({hint})" if hint else "")
            + "".join(f"; {word} was read as the {dest} argument" for dest, word in misread))


def misread_words(command: argparse.ArgumentParser, parsed: argparse.Namespace,
                  argv: list[str], unknown: list[str]) -> list[tuple[str, str]]:
    """The positionals of ``command`` (name, word) that took a word right after an unknown
    flag — ``--worker 1`` reads 1 as the configuration — or a configuration (`CONFIG`) that is
    neither a file nor named ``.yaml``/``.yml``."""
    followers = {argv[i + 1] for i, word in enumerate(argv[:-1]) if word in unknown}
    return [(action.dest, word) for action in command._actions if not action.option_strings
            for word in _words(getattr(parsed, action.dest, None))
            if word in followers or action.dest == CONFIG and not _config_like(word)]


def _words(value: object) -> list[str]:
    """The words a positional took: its value, or the values of one with ``nargs``."""
    return [value] if isinstance(value, str) else value if isinstance(value, list) else []


def _config_like(path: str) -> bool:
    """Whether ``path`` can name a configuration: an existing file, or a YAML name."""
    return path.endswith((".yaml", ".yml")) or Path(path).exists()


#: the distribution whose version ``--version`` prints (pyproject.toml's ``[project] name``)
DISTRIBUTION = "bounce-gym"


class VersionAction(argparse.Action):
    """``--version`` (or ``-V``): print ``bounce-gym <version>`` (the installed distribution's
    metadata, `importlib.metadata`) and exit 0; from a checkout that is not installed, a
    one-line error (status 2) that says so."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, **kwargs) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help="print the version and exit", **kwargs)

    def __call__(self, parser, namespace, values, option_string=None) -> NoReturn:
        try:
            version = importlib.metadata.version(DISTRIBUTION)
        except importlib.metadata.PackageNotFoundError:
            parser.exit(2, f"error: {DISTRIBUTION} is not installed, so it has no version "
                           f"(pip install . in the checkout)\n")
        print(f"{DISTRIBUTION} {version}")
        parser.exit(0)


def add_version_flag(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Give ``parser`` the ``-V``/``--version`` flag (`VersionAction`)."""
    parser.add_argument("-V", "--version", action=VersionAction)
    return parser


def evaluate_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument(CONFIG, nargs="?",
                        help="YAML configuration (default: eval_default.yaml)")
    add_executor_flags(parser)
    parser.add_argument("--experiments", nargs="+", metavar="NAME",
                        help="run only these experiments of the configuration")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    parser.add_argument("--tables", action="store_true",
                        help="also print every table (always written to the run folder's "
                             "tables.txt)")
    return parser


def learners() -> str:
    """Every learner ``train`` trains, by family (`baselines.rl.model_files.ALGO_FAMILIES`)."""
    return ", ".join(f"{', '.join(algos)} ({family})" for family, algos in ALGO_FAMILIES.items())


def train_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument(CONFIG, help=f"YAML training configuration; its algo is one of "
                                     f"{learners()}")
    parser.add_argument("--timesteps", type=int, help="override total_timesteps (per seed)")
    parser.add_argument("--seeds", type=int, nargs="+", metavar="S",
                        help="override the configuration's seeds")
    parser.add_argument("--resume", action="store_true",
                        help="continue every seed from its newest checkpoint")
    add_executor_flags(parser)
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    return parser


def tune_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument(CONFIG, help="YAML training configuration")
    parser.add_argument("--space", help="search space YAML (default: "
                                        "hyperparams/search/<algo>.yaml beside the config)")
    parser.add_argument("--trials", type=int, default=8, help="trials (default 8; at most "
                                                               "10,000)")
    parser.add_argument("--metric", default="return",
                        help="return (default) or success: its mean over the last 100 episodes "
                             "is maximised")
    parser.add_argument("--scheduler", default="fifo",
                        help="fifo (default: every trial runs its budget) or asha")
    parser.add_argument("--seed", type=int, default=0,
                        help="seed of the draws (default 0; at most 2**32 - 1)")
    parser.add_argument("--timesteps", type=int, help="override total_timesteps (per trial)")
    parser.add_argument("--resume", action="store_true",
                        help="skip finished trials, continue the others from checkpoints")
    parser.add_argument("--workers", type=int, metavar="N",
                        help="trials at once (default: the machine's cores)")
    parser.add_argument("--address", metavar="ADDR", help="a running Ray cluster's address")
    parser.add_argument("--no-progress", action="store_true", help="hide Tune's progress")
    return parser


def curves_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("folder", help="a models folder, models/<name>")
    parser.add_argument("--window", type=int,
                        help="episodes in the moving mean (default 100, as SB3's ep_rew_mean)")
    return parser


def trust_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("models", nargs="+", help="checkpoints (or models) whose content you "
                        "trust, e.g. received from a colleague")
    return parser


#: the modules each command needs beyond the core (`bounce_gym.extras.MODULE_EXTRAS` says
#: which extra installs each): checked before the command starts
COMMAND_MODULES = {
    "evaluate": ("matplotlib", "tqdm"),
    "train": ("matplotlib",),  # and those of the algorithm (`baselines.rl.train.prepare`)
    "tune": ("ray", "stable_baselines3", "sb3_contrib", "torch", "rich", "tqdm", "matplotlib"),
    "curves": ("matplotlib",),
    "trust": (),
    "schema": (),
    "tables": (),
    "envs": (),
}


def schema_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("name", nargs="?", choices=("evaluation", "training"),
                        help="the configuration whose schema to print")
    parser.add_argument("--write", action="store_true",
                        help="write every schema into configs/schema/")
    return parser


def tables_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("--write", action="store_true",
                        help="regenerate the tables (default: list those that differ from "
                             "their file, exit 1 if any)")
    parser.add_argument("--from", dest="run", metavar="RUN_FOLDER",
                        help="first copy this run's leaderboard files into --into")
    parser.add_argument("--into", metavar="FOLDER", default="docs/results/benchmark",
                        help="where --from copies to (default: docs/results/benchmark)")
    return parser


def tables_command(write: bool, run: str | None, into: str) -> int:
    """Check or regenerate the result tables of README.md and docs/ (run in the repository
    root; `bounce_gym_experiments.published`)."""
    from bounce_gym_experiments import published

    root = Path.cwd()
    if run is not None:
        for path in published.publish(Path(run), root / into):
            print(f"copied {path.relative_to(root)}")
    if write:
        for path in published.rewrite(root):
            print(f"rewrote the result tables of {path.relative_to(root)}")
        return 0
    old = published.stale(root)
    for line in old:
        print(f"stale: {line}")
    return 1 if old else 0




def envs_command() -> int:
    """List every registered id, Gymnasium's then PettingZoo's, each beside what it is in one
    line (`bounce_gym.envs.registration.SUMMARY`)."""
    from bounce_gym.envs.registration import ENV_IDS, SUMMARY

    column = max(map(len, ENV_IDS)) + 2
    for env_id in ENV_IDS:
        print(f"{env_id:<{column}}{SUMMARY[env_id]}")
    return 0


def os_error_text(exc: OSError) -> str:
    """An `OSError` as one line: the file it names (both, for a rename) and the system's
    reason."""
    reason = exc.strerror or " ".join(str(exc).split()) or type(exc).__name__
    names = [str(n) for n in (exc.filename, exc.filename2) if n is not None]
    return f"{' -> '.join(names)}: {reason}" if names else reason


def dispatch(args: argparse.Namespace) -> int:
    """Run the parsed command; an input error of this package (`BounceGymError`: a bad
    configuration, env argument or model file; a write that failed) becomes ``error: ...`` on
    stderr and status 2, as does any other `OSError` (`os_error_text`) and a missing extra
    (`bounce_gym.extras`): the command's own (`COMMAND_MODULES`), checked first, or one a
    configuration's choice needs (e.g. trained agents to evaluate)."""
    feature = f"bounce-gym {args.command}"
    try:
        require(feature, *COMMAND_MODULES[args.command])
        if args.command == "evaluate":
            return evaluate_command(args.config, progress=not args.no_progress,
                                    flags=executor_flags(args), experiments=args.experiments,
                                    show_tables=args.tables)
        if args.command == "trust":
            return trust_command(args.models)
        if args.command == "curves":
            return curves_command(args.folder, args.window)
        if args.command == "schema":
            return schema_command(args.name, args.write)
        if args.command == "tables":
            return tables_command(args.write, args.run, args.into)
        if args.command == "envs":
            return envs_command()
        if args.command == "tune":
            return tune_command(args.config, args.space, args.trials, args.metric, args.scheduler,
                        args.seed, args.timesteps, args.resume, args.workers, args.address,
                        progress=not args.no_progress)
        return train_command(args.config, args.timesteps, args.resume, progress=not args.no_progress,
                     seeds=args.seeds, flags=executor_flags(args))
    except BounceGymError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a fault met outside the package's own readers and writers
        print(f"error: {os_error_text(exc)}", file=sys.stderr)
        return 2
    except ImportError as exc:
        missing = from_import_error(feature, exc)
        if missing is None:  # not a module of an extra: a broken install, shown in full
            raise
        print(f"error: {missing}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        if args.command == "evaluate":
            print("interrupted: the finished units are kept; run the same command again to run "
                  "only the others", file=sys.stderr)
            return 130
        if args.command != "train":
            raise
        print("interrupted: run the same command with --resume to continue from the newest "
              "checkpoint", file=sys.stderr)
        return 130


def main(argv: list[str] | None = None) -> int:
    parser = add_version_flag(Parser(prog="bounce-gym", description=__doc__.splitlines()[0]))
    commands = parser.add_subparsers(dest="command", required=True)
    evaluate_parser(commands.add_parser("evaluate", help="evaluate policies side by side"))
    train_parser(commands.add_parser("train", help=f"train agents: {learners()}"))
    tune_parser(commands.add_parser("tune", help="search hyperparameters with Ray Tune"))
    curves_parser(commands.add_parser("curves", help="draw the learning curves of trained "
                                                     "agents"))
    trust_parser(commands.add_parser("trust", help="trust checkpoints from elsewhere for "
                                                   "--resume (user-level, by sha256)"))
    schema_parser(commands.add_parser("schema", help="the JSON Schema of the configuration "
                                                     "files"))
    tables_parser(commands.add_parser("tables", help="check or regenerate the result tables of "
                                                     "README.md and docs/ from a run's "
                                                     "leaderboard"))
    commands.add_parser("envs", help="list the registered environment ids")
    return dispatch(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
