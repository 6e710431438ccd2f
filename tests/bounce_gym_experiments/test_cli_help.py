"""What the commands' help and ``bounce-gym envs`` print: plain text (no reST markup), every
learner ``train`` trains, and every registered environment id in one line each."""

import sys
from pathlib import Path

import gymnasium as gym
import pettingzoo
import pytest

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

import evaluate  # noqa: E402
import train  # noqa: E402
from baselines.rl.model_files import ALGOS  # noqa: E402
from bounce_gym.envs.registration import ENV_IDS, SUMMARY, SUMMARY_WIDTH  # noqa: E402
from bounce_gym_experiments import cli  # noqa: E402

COMMANDS = ("evaluate", "train", "tune", "curves", "trust", "schema", "tables", "envs")
#: every help: the main that prints it and its arguments
HELPS = {"bounce-gym": (cli.main, ["--help"]),
         **{f"bounce-gym {name}": (cli.main, [name, "--help"]) for name in COMMANDS},
         "train.py": (train.main, ["--help"]), "evaluate.py": (evaluate.main, ["--help"])}


def _help(capsys, name: str) -> str:
    main, argv = HELPS[name]
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 0
    return capsys.readouterr().out


def test_every_command_has_a_help():
    assert set(cli.COMMAND_MODULES) == set(COMMANDS)


@pytest.mark.parametrize("name", sorted(HELPS))
def test_help_is_plain_text(capsys, name):
    assert "`" not in _help(capsys, name)


def test_the_top_level_help_keeps_the_words_of_its_markup(capsys):
    assert "The bounce-gym command: evaluate" in _help(capsys, "bounce-gym")


@pytest.mark.parametrize(("text", "plain"), [
    ("``bounce-gym train``", "bounce-gym train"),
    ("see `bounce_gym.trust`", "see bounce_gym.trust"),
    ("a :class:`Parser` and :py:func:`main`", "a Parser and main"),
    ("at 10:30 no markup", "at 10:30 no markup"),
])
def test_plain_leaves_out_rest_markup(text, plain):
    assert cli.plain(text) == plain


@pytest.mark.parametrize("name", ["bounce-gym", "bounce-gym train", "train.py"])
def test_the_training_help_names_every_learner(capsys, name):
    words = _help(capsys, name).replace(",", " ").split()
    assert set(ALGOS) <= set(words)
    assert "Stable-Baselines3 agent" not in " ".join(words)


def _registered() -> set[str]:
    """The package's ids in Gymnasium's and PettingZoo's registries."""
    return {env_id for registry in (gym.registry, pettingzoo.parallel_registry)
            for env_id in registry if env_id.startswith("bounce_gym/")}


def test_envs_lists_every_registered_id_in_one_line_each(capsys):
    assert cli.main(["envs"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == list(ENV_IDS)
    assert set(ENV_IDS) == _registered()
    assert all(len(line) <= 100 for line in lines)
    summaries = [line[len(env_id):].strip() for line, env_id in zip(lines, ENV_IDS, strict=True)]
    assert all(summaries) and len(set(summaries)) == len(summaries)  # what sets each apart
    columns = {line.index(summary) for line, summary in zip(lines, summaries, strict=True)}
    assert len(columns) == 1  # aligned
    assert "`" not in "".join(summaries)
    assert summaries == [SUMMARY[env_id] for env_id in ENV_IDS]
    assert max(map(len, SUMMARY.values())) <= SUMMARY_WIDTH
