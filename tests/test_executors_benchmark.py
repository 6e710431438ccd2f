"""The executors benchmark (issue #17) on a tiny evaluation: a row per executor, identical
files."""

import importlib.util
import shutil
import subprocess

import pytest
import yaml

from benchmarks import executors
from bounce_gym_experiments.config import load_config


def _tiny(tmp_path):
    experiment = next(e for e in load_config()["experiments"] if e["name"] == "localization-lab")
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump({"name": "tiny", "experiments": [experiment]}))
    return config


@pytest.mark.slow  # three whole evaluate.py runs, one on Ray: ~45 s on two cores
def test_executors_benchmark_runs_and_finds_identical_files(tmp_path, capsys):
    config = _tiny(tmp_path)
    out = executors.main(["--config", str(config), "--seeds", "2"])
    rows = out[str(config)]
    text = capsys.readouterr().out
    ray = importlib.util.find_spec("ray") is not None
    assert list(rows) == list(executors.EXECUTORS)[:3 if ray else 2]
    assert all(r["seconds"] > 0 for r in rows.values())
    assert len({(r["episodes.csv"], r["results.json"]) for r in rows.values()}) == 1
    assert "identical files for every executor" in text and "load average" in text
    assert ray or "ray (local, 2 CPUs): skipped" in text


def _git(folder, *args):
    return subprocess.run(["git", "-C", str(folder), "-c", "user.name=test",
                           "-c", "user.email=test@example.org", "-c", "commit.gpgsign=false",
                           *args], capture_output=True, check=True).stdout


@pytest.mark.slow  # two evaluations in a checkout of its own: ~25 s on two cores
def test_the_checkout_changing_between_runs_changes_no_file(tmp_path, monkeypatch):
    """Someone editing the checkout while the benchmark runs (minutes on a loaded machine) made
    the next executor's ``results.json`` record another git state (``dirty``) than the one
    before: the runs execute a copy of the checkout taken before the first."""
    if shutil.which("git") is None or not (executors.ROOT / ".git").exists():
        pytest.skip("needs the project's git checkout")
    checkout = tmp_path / "checkout"  # a checkout of its own, edited below
    for name in filter(None, _git(executors.ROOT, "ls-files", "-z").decode().split("\0")):
        if (executors.ROOT / name).is_file():
            (checkout / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(executors.ROOT / name, checkout / name)
    _git(checkout, "init", "-q")
    _git(checkout, "add", "-A")
    _git(checkout, "commit", "-q", "-m", "the checkout the benchmark starts from")
    monkeypatch.setattr(executors, "ROOT", checkout)
    # two runs in one process each (which executor makes no difference to the git state a run
    # records; a pool would only add its workers' start)
    monkeypatch.setattr(executors, "EXECUTORS", {"1 worker": ["--workers", "1"],
                                                 "1 worker, after an edit": ["--workers", "1"]})
    run_one, edits = executors.run_one, []

    def run_then_edit(*args):
        out = run_one(*args)
        readme = checkout / "README.md"
        readme.write_text(readme.read_text(encoding="utf-8") + "\nan edit\n", encoding="utf-8")
        edits.append(_git(checkout, "status", "--porcelain", "--untracked-files=no"))
        return out

    monkeypatch.setattr(executors, "run_one", run_then_edit)
    rows = executors.bench(_tiny(tmp_path), 2)
    assert edits[0].strip() == b"M README.md"  # the checkout did change after the first run
    assert len(rows) == 2
    assert len({(r["episodes.csv"], r["results.json"]) for r in rows.values()}) == 1
