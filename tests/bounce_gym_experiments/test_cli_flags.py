"""``--version`` (``-V``) on every command line of the package, and no abbreviated flags: a flag
is given in full, or it is an unknown flag (exit status 2, one line), never another flag; the
line names the flag meant and the positional that took the word after it."""

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


@pytest.mark.parametrize("flag", ["--version", "-V"])
@pytest.mark.parametrize("main", [cli.main, train.main, evaluate.main])
def test_version_prints_the_installed_distributions_version(capsys, main, flag):
    code, out, err = _exit(capsys, main, [flag])
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


#: the line of a word read as a positional after an unknown flag, by command line
MISREAD = [
    (cli.main, ["evaluate", "--worker", "1"],
     "error: unrecognized arguments: --worker (did you mean '--workers'?); 1 was read as the "
     "config argument (see bounce-gym evaluate --help)"),
    (cli.main, ["train", "--timestep", "100", "c.yaml"],
     "error: unrecognized arguments: --timestep c.yaml (did you mean '--timesteps'?); 100 was "
     "read as the config argument (see bounce-gym train --help)"),
    (cli.main, ["tune", "--trial", "5", "c.yaml"],
     "error: unrecognized arguments: --trial c.yaml (did you mean '--trials'?); 5 was read as "
     "the config argument (see bounce-gym tune --help)"),
    (cli.main, ["curves", "--win", "3", "models/x"],
     "error: unrecognized arguments: --win models/x (did you mean '--window'?); 3 was read as "
     "the folder argument (see bounce-gym curves --help)"),
    (cli.main, ["trust", "--sha", "a.zip", "b.zip"],
     "error: unrecognized arguments: --sha; a.zip was read as the models argument (see "
     "bounce-gym trust --help)"),
    (cli.main, ["schema", "--wrte", "training"],
     "error: unrecognized arguments: --wrte (did you mean '--write'?); training was read as the "
     "name argument (see bounce-gym schema --help)"),
    (cli.main, ["tables", "--wrte"],
     "error: unrecognized arguments: --wrte (did you mean '--write'?) (see bounce-gym tables "
     "--help)"),
    (evaluate.main, ["--worker", "1"],
     "error: unrecognized arguments: --worker (did you mean '--workers'?); 1 was read as the "
     "config argument (see "),
    (train.main, ["--timestep", "5"],
     "error: unrecognized arguments: --timestep (did you mean '--timesteps'?); 5 was read as "
     "the config argument (see "),
]


@pytest.mark.parametrize(("main", "argv", "line"), MISREAD)
def test_a_word_after_an_unknown_flag_names_the_positional_it_became(capsys, main, argv, line):
    code, out, err = _exit(capsys, main, argv)
    assert (code, out) == (2, "")
    assert err.startswith(line) and err.count("\n") == 1, err


@pytest.mark.parametrize(("argv", "line"), [
    (["evaluate", "1"], "error: argument config: 1 is neither a file nor a .yaml/.yml name (see "
                        "bounce-gym evaluate --help)"),
    (["train", "--resume", "3", "c.yaml"], "error: unrecognized arguments: c.yaml; 3 was read as "
                                           "the config argument (see bounce-gym train --help)"),
])
def test_a_configuration_is_a_file_or_a_yaml_name(capsys, argv, line):
    code, out, err = _exit(capsys, cli.main, argv)
    assert (code, out, err) == (2, "", line + "\n")


def test_an_existing_file_of_any_name_is_read_as_the_configuration(capsys, tmp_path):
    """The name check leaves a file that exists to the configuration's own checks."""
    config = tmp_path / "settings"
    config.write_text("name: x\n", encoding="utf-8")
    assert cli.main(["evaluate", str(config)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: config") and "argument config" not in err, err
