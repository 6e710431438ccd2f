"""Issue 22: what ``bounce-gym evaluate``, ``train`` and ``curves`` write stays in the folders the
user gave, never goes through a symbolic link planted there, and a run folder looks finished
only once it is; a unit file the user did not sign is never unpickled."""

import hashlib
import os
import pickle
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

from bounce_gym.trust import HOME_VARIABLE  # noqa: E402
from bounce_gym_experiments.cli import main  # noqa: E402
from bounce_gym_experiments.config import load_config, validate_config  # noqa: E402
from bounce_gym_experiments.executors import UnitStore  # noqa: E402
from bounce_gym_experiments.run_folders import finished_runs  # noqa: E402
from bounce_gym_experiments.sweep import store_folder  # noqa: E402

NAV = {"world": "square", "backend": "cell", "angles": [90, 135]}
#: the evaluation's files that must come out the same
FILES = ("episodes.csv", "summary.csv", "results.json")
BAD_NAMES = ["../../ESCAPED", "a\0b", "a/b", "..", ".", ".hidden", "-rf", "two\nlines",
             "x" * 300, "é" * 60]


def _refused(name: str, message: str) -> str:
    """How a bad name is refused: a NUL already by the reader of the file (no control
    characters in its strings, `bounce_gym.documents`), anything else by the name's check."""
    return "error: config: " if "\0" in name else message


def _evaluation(tmp_path: Path, name: str = "safe", experiment: str = "nav") -> Path:
    """A small evaluation (three policies on 12 seeds: six units) writing into
    ``tmp_path/out/runs``; its configuration file."""
    config = {"name": name, "output": str(tmp_path / "out/runs"),
              "models": str(tmp_path / "models"),
              "experiments": [{"name": experiment, "env": "bounce_gym/BounceNavigation-v0",
                               "env_kwargs": NAV, "seeds": {"start": 10_000, "count": 12},
                               "max_steps": 5, "horizon_reason": "a quick test",
                               "policies": ["random", "fixed"]}]}
    path = tmp_path / "eval.yaml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    return path


def _evaluate(config: Path, *flags: str) -> int:
    return main(["evaluate", str(config), "--no-progress", "--workers", "1", *flags])


def _output(tmp_path: Path) -> Path:
    return tmp_path / "out/runs"


def _checksums(run: Path) -> dict[str, str]:
    return {f: hashlib.sha256((run / f).read_bytes()).hexdigest() for f in FILES}


def _take_run(tmp_path: Path, label: str) -> dict[str, str]:
    """The checksums of the one finished run, which is then moved out of the output folder."""
    (run,) = finished_runs(_output(tmp_path))
    return _checksums(run.rename(tmp_path / label))


def _everything(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


class _Plant:
    """Unpickled, it creates ``marker``: the payload of a planted unit file."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (Path(self.marker),))


def test_planted_and_foreign_unit_files_run_again_and_nothing_of_theirs_runs(tmp_path, capsys,
                                                                            monkeypatch):
    config = _evaluation(tmp_path)
    assert _evaluate(config) == 0
    expected = _take_run(tmp_path, "clean")
    store = store_folder(validate_config(load_config(config)))
    marker = tmp_path / "payload-ran"
    store.mkdir(parents=True)
    (store / "0-0-0.unit").write_bytes(pickle.dumps(_Plant(marker)))  # unsigned
    monkeypatch.setenv(HOME_VARIABLE, str(tmp_path / "another-user"))
    UnitStore(store).save("0-1-1", _Plant(marker))  # signed, with another user's key
    monkeypatch.undo()
    capsys.readouterr()
    assert _evaluate(config) == 0
    assert not marker.exists()
    warnings = [line for line in capsys.readouterr().err.splitlines() if line]
    assert len(warnings) == 2 and all(w.startswith("warning: ") for w in warnings)
    assert "0-0-0.unit: not taken as a unit result (not signed" in warnings[0]
    assert "0-1-1.unit: not taken as a unit result (its signature does not match" in warnings[1]
    assert _take_run(tmp_path, "replanted") == expected
    assert not store.exists()


@pytest.mark.parametrize("name", BAD_NAMES)
def test_a_run_name_that_is_not_a_plain_component_fails_at_once_writing_nothing(
        tmp_path, capsys, name):
    config = _evaluation(tmp_path / "a/b", name=name)
    assert _evaluate(config) == 2
    err = capsys.readouterr().err
    assert err.startswith(_refused(name, "error: config.name: expected a name for the run "
                                         "folder (one path component), got ")) \
        and err.count("\n") == 1
    assert _everything(tmp_path) == {"a", "a/b", "a/b/eval.yaml"}


@pytest.mark.parametrize("name", BAD_NAMES[:4])
def test_an_experiment_name_becomes_plot_file_names_and_is_checked_too(tmp_path, capsys, name):
    assert _evaluate(_evaluation(tmp_path, experiment=name)) == 2
    err = capsys.readouterr().err
    assert err.startswith(_refused(name, "error: config.experiments[0].name: expected a name "
                                         "for the plot files")) and err.count("\n") == 1
    assert _everything(tmp_path) == {"eval.yaml"}


@pytest.mark.parametrize("name", ["../../ESCAPED", "a\0b", "x" * 300, ".hidden"])
def test_a_training_name_that_is_not_a_plain_component_fails_at_once(tmp_path, capsys, name):
    config = {"name": name, "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
              "algo": "ppo", "total_timesteps": 64, "n_envs": 1,
              "models": str(tmp_path / "a/b/models"),
              "hyperparams": {"n_steps": 32, "batch_size": 32}}
    path = tmp_path / "train.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    assert main(["train", str(path), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(_refused(name, "error: config.name: expected the name of a folder "
                                         "in models/")) and err.count("\n") == 1
    assert _everything(tmp_path) == {"train.yaml"}


def test_a_link_planted_as_the_units_folder_is_refused(tmp_path, capsys):
    config = _evaluation(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    _output(tmp_path).mkdir(parents=True)
    os.symlink(elsewhere, _output(tmp_path) / "safe-units")
    assert _evaluate(config) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: config.output: ") and "safe-units is a symbolic link" in err
    assert list(elsewhere.iterdir()) == []


def test_a_report_that_fails_midway_leaves_no_run_folder_and_keeps_the_units(tmp_path,
                                                                              monkeypatch,
                                                                              capsys):
    import bounce_gym_experiments.report

    config = _evaluation(tmp_path)

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(bounce_gym_experiments.report, "write_plots", broken)
    capsys.readouterr()
    assert _evaluate(config) == 2  # one line naming the run folder, not a traceback
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {_output(tmp_path)}/safe-"), lines
    assert lines[0].endswith(": cannot write it: No space left on device"), lines
    assert os.listdir(_output(tmp_path)) == ["safe-units"]  # the half-written folder is gone
    monkeypatch.undo()
    assert _evaluate(config) == 0
    assert [p.name[:5] for p in _output(tmp_path).iterdir()] == ["safe-"]


def test_ctrl_c_during_the_report_leaves_no_run_folder(tmp_path, capsys, monkeypatch):
    import bounce_gym_experiments.report

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(bounce_gym_experiments.report, "write_plots", interrupted)
    assert _evaluate(_evaluation(tmp_path)) == 130
    assert "the finished units are kept" in capsys.readouterr().err
    assert os.listdir(_output(tmp_path)) == ["safe-units"]


_KILLED_IN_THE_REPORT = """
import os, signal, sys
import bounce_gym_experiments.report as report
report.write_plots = lambda *args, **kwargs: os.kill(os.getpid(), signal.SIGKILL)
from bounce_gym_experiments.cli import main
main(["evaluate", sys.argv[1], "--no-progress", "--workers", "1"])
"""


def test_a_kill_during_the_report_leaves_nothing_that_looks_finished(tmp_path):
    config = _evaluation(tmp_path)
    assert _evaluate(config) == 0
    expected = _take_run(tmp_path, "clean")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    killed = subprocess.run([sys.executable, "-c", _KILLED_IN_THE_REPORT, str(config)], env=env,
                            capture_output=True, text=True)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    left = [p for p in _output(tmp_path).iterdir() if p.name != "safe-units"]
    assert len(left) == 1 and left[0].name.startswith(".safe-")  # hidden, and ...
    assert (left[0] / "episodes.csv").is_file()  # ... killed after the rows were written
    assert finished_runs(_output(tmp_path)) == []
    assert _evaluate(config) == 0
    assert _take_run(tmp_path, "after-kill") == expected
    assert finished_runs(_output(tmp_path)) == []


def test_two_runs_of_one_name_in_the_same_second_get_two_folders(tmp_path, monkeypatch):
    import bounce_gym_experiments.run_folders

    monkeypatch.setattr(bounce_gym_experiments.run_folders.time, "strftime", lambda fmt: "20250101-000000")
    config = _evaluation(tmp_path)
    assert _evaluate(config) == 0 and _evaluate(config) == 0
    assert [p.name for p in finished_runs(_output(tmp_path))] == [
        "safe-20250101-000000", "safe-20250101-000000-2"]
    first, second = finished_runs(_output(tmp_path))
    assert _checksums(first)["episodes.csv"] == _checksums(second)["episodes.csv"]


def _training(tmp_path: Path) -> Path:
    config = {"name": "nav", "env": "bounce_gym/BounceNavigation-v0", "env_kwargs": NAV,
              "algo": "ppo", "total_timesteps": 64, "n_envs": 1, "seed": 0,
              "models": str(tmp_path / "models"),
              "hyperparams": {"n_steps": 32, "batch_size": 32}}
    path = tmp_path / "train.yaml"
    path.write_text(yaml.safe_dump(config), encoding="utf-8")
    return path


@pytest.mark.parametrize("resume", [False, True], ids=["new", "resume"])
def test_training_refuses_a_monitor_file_planted_as_a_link(tmp_path, capsys, resume):
    victim = tmp_path / "victim.csv"
    victim.write_text("precious\n")
    (tmp_path / "models/nav").mkdir(parents=True)
    os.symlink(victim, tmp_path / "models/nav/ppo_seed0.monitor.csv")
    assert main(["train", str(_training(tmp_path)), "--no-progress",
                 *(["--resume"] if resume else [])]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: config.models: ") and err.count("\n") == 1
    assert "ppo_seed0.monitor.csv is a symbolic link" in err
    assert victim.read_text() == "precious\n"


def test_training_refuses_a_checkpoints_folder_planted_as_a_link(tmp_path, capsys):
    victim = tmp_path / "victim"
    victim.mkdir()
    (tmp_path / "models/nav").mkdir(parents=True)
    os.symlink(victim, tmp_path / "models/nav/checkpoints")
    assert main(["train", str(_training(tmp_path)), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: config.models: ") and "checkpoints is a symbolic link" in err
    assert list(victim.iterdir()) == []


def test_curves_replace_planted_links_and_leave_their_targets(tmp_path, capsys):
    from baselines.rl.monitor import open_monitor_file

    folder = tmp_path / "models/nav"
    writer = open_monitor_file(folder / "ppo_seed0.monitor.csv", 0.0, "x", ("is_success",))
    for k in range(3):
        writer.write_row({"r": float(k), "l": 5, "t": 0.1 * k, "is_success": k > 1})
    writer.close()
    victims = {}
    for name in ("learning_curves.png", "learning_curves.csv"):
        victims[name] = tmp_path / f"victim-{name}"
        victims[name].write_text("precious")
        os.symlink(victims[name], folder / name)
    assert main(["curves", str(folder)]) == 0
    for name, victim in victims.items():
        assert victim.read_text() == "precious"
        assert not (folder / name).is_symlink() and (folder / name).stat().st_size > 0


def test_tune_tables_replace_planted_links_and_leave_their_targets(tmp_path):
    from bounce_gym_experiments.search import Trial, write_trials

    victim = tmp_path / "victim.csv"
    victim.write_text("precious")
    os.symlink(victim, tmp_path / "trials.csv")
    write_trials(tmp_path, [Trial(0, {"learning_rate": 0.001}, "done", 1.5, 10, 320)], "return")
    assert victim.read_text() == "precious"
    assert (tmp_path / "trials.csv").read_text().startswith("trial,status,return")
