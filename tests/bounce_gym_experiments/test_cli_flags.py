"""``--version`` on every command line of the package, and no abbreviated flags: a flag is
given in full, or it is an unknown flag (exit status 2, one line), never another flag."""

import importlib.metadata
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402
import train  # noqa: E402
from bounce_gym import demo  # noqa: E402
from bounce_gym_experiments import cli  # noqa: E402

#: every command line of the package: its main, and the arguments it needs besides a flag
COMMANDS = {
    "bounce-gym evaluate": (cli.main, ["evaluate"], ["c.yaml"]),
    "bounce-gym train": (cli.main, ["train"], ["c.yaml"]),
    "bounce-gym tune": (cli.main, ["tune"], ["c.yaml"]),
    "bounce-gym curves": (cli.main, ["curves"], ["models/x"]),
    "bounce-gym": (cli.main, [], ["trust", "m.zip"]),
    "train.py": (train.main, [], ["c.yaml"]),
    "evaluate.py": (evaluate.main, [], ["c.yaml"]),
}


def _exit(capsys, main, argv) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as stop:
        main(argv)
    captured = capsys.readouterr()
    return stop.value.code, captured.out, captured.err


@pytest.mark.parametrize("main", [cli.main, train.main, evaluate.main])
def test_version_prints_the_installed_distributions_version(capsys, main):
    code, out, err = _exit(capsys, main, ["--version"])
    assert (code, err) == (0, "")
    assert out == f"bounce-gym {importlib.metadata.version('bounce-gym')}\n"
    assert re.fullmatch(r"bounce-gym \d+\.\d+\.\d+\S*\n", out)


def test_version_of_a_checkout_that_is_not_installed_is_one_line_error(capsys, monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "version", missing)
    code, out, err = _exit(capsys, cli.main, ["--version"])
    assert (code, out) == (2, "")
    assert err.count("\n") == 1 and err.startswith("error: bounce-gym is not installed")


@pytest.mark.parametrize(("main", "argv", "flag"), [
    (cli.main, ["evaluate", "--worker", "2"], "--worker"),
    (evaluate.main, ["--worker", "2"], "--worker"),
    (cli.main, ["train", "--timestep", "100", "c.yaml"], "--timestep"),
    (train.main, ["--timestep", "100", "c.yaml"], "--timestep"),
    (cli.main, ["--vers", "trust", "m.zip"], "--vers"),
])
def test_the_issues_abbreviations_are_unknown_flags(capsys, main, argv, flag):
    code, out, err = _exit(capsys, main, argv)
    assert (code, out) == (2, "")
    assert err.count("\n") == 1 and f"unrecognized arguments: {flag}" in err


def test_the_demo_takes_no_abbreviation(capsys):
    code, out, err = _exit(capsys, demo.main, ["--see", "3"])
    assert (code, out) == (2, "")
    assert "unrecognized arguments: --see 3" in err


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_no_flag_of_any_command_can_be_abbreviated(capsys, command):
    main, prefix, positional = COMMANDS[command]
    code, usage, _ = _exit(capsys, main, [*prefix, "--help"])
    assert code == 0
    flags = set(re.findall(r"(?<![\w-])--[a-z][a-z-]+", usage)) - {"--help"}
    assert flags  # the help names the command's flags
    abbreviations = {flag[:-1] for flag in flags if len(flag) > 4} - flags
    for short in sorted(abbreviations):
        code, out, err = _exit(capsys, main, [*prefix, short, *positional])
        assert (code, out) == (2, ""), short
        assert f"unrecognized arguments: {short}" in err and err.count("\n") == 1, err
