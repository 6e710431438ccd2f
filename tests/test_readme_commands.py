"""The README's training commands run exactly as written (with the documented budget cap,
``BOUNCE_GYM_MAX_TIMESTEPS``), and every module they import comes from a declared dependency."""

import importlib.metadata
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

tomllib = pytest.importorskip("tomllib", reason="reading pyproject.toml needs Python >= 3.11")

ROOT = Path(__file__).parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
#: the README and the docs pages, where training commands are shown
PAGES = "\n".join([README, *(page.read_text(encoding="utf-8")
                              for page in sorted((ROOT / "docs").rglob("*.md")))])
#: training commands, in ```bash blocks or inline code: python train.py …, bounce-gym
#: train|curves|tune …
#: (not the templates, such as ``bounce-gym curves models/<name>``)
COMMANDS = [c.strip() for c in re.findall(
    r"(?:^|`)((?:\.venv/bin/)?(?:python train\.py|bounce-gym (?:train|curves|tune)) [^#`\n]*)",
    PAGES, re.M) if "<" not in c]
#: the extras `make install` installs besides the core dependencies (dev only adds test tools)
EXTRAS = ("experiments", "rl", "jax", "distributed")
OURS = {"bounce_gym", "baselines", "bounce_gym_experiments", "train", "evaluate"}
#: optional imports that libraries try and do without (imported only because they happen to be
#: installed here)
OPTIONAL = {"charset_normalizer": "numpy.f2py.crackfortran: try/except ImportError",
            "tabulate": "torch._dynamo.utils.tabulate: try/except ImportError, at exit"}
#: modules shipped inside a declared distribution (ray puts ray/thirdparty_files on sys.path),
#: whose names are also distributions of their own
VENDORED = {"psutil": "ray", "colorama": "ray"}


def _argv(command: str) -> list[str]:
    """The command's words; only the interpreter and the console script are found in the
    environment running the tests (the README assumes it is activated). Where the console
    script is not installed, its entry point (pyproject.toml) is run as the script would."""
    words = command.split()
    program = words[0].removeprefix(".venv/bin/")
    if program == "python":
        return [sys.executable, *words[1:]]
    script = Path(sys.executable).parent / program
    if script.is_file():
        return [str(script), *words[1:]]
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    module, function = project["scripts"][program].split(":")
    return [sys.executable, "-c", f"import sys; sys.argv[0] = {program!r}; "
            f"from {module} import {function}; sys.exit({function}())", *words[1:]]


def _imported(stderr: str) -> set[str]:
    """Top-level names of the modules a run imported (from ``PYTHONPROFILEIMPORTTIME``)."""
    names = re.findall(r"^import time:\s+\d+ \|\s+\d+ \|\s+(\S+)", stderr, re.M)
    return {name.split(".")[0] for name in names}


def _declared() -> set[str]:
    """The distributions the declared requirements pull in (transitively, markers evaluated)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    todo = [Requirement(r) for r in project["dependencies"]]
    for extra in EXTRAS:
        todo += [Requirement(r) for r in project["optional-dependencies"][extra]]
    seen: set[str] = set()
    while todo:
        requirement = todo.pop()
        name = canonicalize_name(requirement.name)
        if name in seen or name == "bounce-gym":
            continue
        seen.add(name)
        for line in importlib.metadata.requires(name) or []:
            sub = Requirement(line)
            extras = ("", *requirement.extras)
            if sub.marker is None or any(sub.marker.evaluate({"extra": e}) for e in extras):
                todo.append(sub)
    return seen


def test_the_readme_documents_training_commands():
    assert any(c.startswith("python train.py configs/train_navigation.yaml") for c in COMMANDS)
    assert any("--resume" in c for c in COMMANDS) and any(" curves " in c for c in COMMANDS)


def _run_as_written(folder: Path, commands: list[str]) -> set[str]:
    """Run ``commands`` in ``folder`` (with the budget cap) in turn, each to success; the
    top-level modules they imported."""
    for name in ("train.py", "configs"):
        (folder / name).symlink_to(ROOT / name)
    env = {**os.environ, "BOUNCE_GYM_MAX_TIMESTEPS": "512", "PYTHONPROFILEIMPORTTIME": "1",
           "PYTHONPATH": str(ROOT), "SDL_VIDEODRIVER": "dummy"}
    imported: set[str] = set()
    for command in commands:
        done = subprocess.run(_argv(command), cwd=folder, env=env, capture_output=True,
                              text=True, timeout=600, check=False)
        errors = [line for line in done.stderr.splitlines()
                  if not line.startswith("import time:")]
        assert done.returncode == 0, f"{command}\n" + "\n".join(errors[-20:])
        imported |= _imported(done.stderr)
    return imported


def _check_declared(imported: set[str]) -> None:
    """Every module of ``imported`` that a distribution ships comes from a declared one."""
    distributions = importlib.metadata.packages_distributions()
    declared = _declared()
    undeclared = {}
    others = imported - OURS - set(OPTIONAL) - set(VENDORED) - set(sys.stdlib_module_names)
    for module in sorted(others):
        owners = {canonicalize_name(d) for d in distributions.get(module, [])}
        if owners and not owners & (declared | {"bounce-gym", "setuptools"}):
            undeclared[module] = sorted(owners)
    assert not undeclared, f"imported but not declared in pyproject.toml: {undeclared}"


def test_the_first_training_commands_run_as_written(tmp_path):
    """The README's first training run, its resume and its curves (``make test``), and what
    they import. The slow suite runs every other command of the README and the docs: each
    command is run, and its imports checked, in one of the two tests (CI runs both)."""
    assert COMMANDS[:3] == ["python train.py configs/train_navigation.yaml",
                            "python train.py configs/train_navigation.yaml --resume",
                            "bounce-gym curves models/navigation-lab"]
    imported = _run_as_written(tmp_path, COMMANDS[:3])
    assert (tmp_path / "models/navigation-lab/learning_curves.png").is_file()
    assert (tmp_path / "models/navigation-lab/ppo_seed0.monitor.csv").is_file()
    _check_declared(imported)


@pytest.mark.slow  # 11 training commands, ~2 minutes
@pytest.mark.long
def test_readme_training_commands_run_as_written(tmp_path):
    """The commands after the first three (`test_the_first_training_commands_run_as_written`
    runs those), in order, and what they import."""
    imported = _run_as_written(tmp_path, COMMANDS[3:])
    assert (tmp_path / "models/navigation-lab/learning_curves.png").is_file()
    assert (tmp_path / "models/navigation-lab-tune/trials.csv").is_file()
    assert (tmp_path / "models/navigation-lab-v1/dqn_seed40.zip").is_file()  # docs/learning.md
    _check_declared(imported)


@pytest.mark.parametrize("cap", ["0", "many", "-5"])
def test_a_bad_budget_cap_is_one_error(tmp_path, cap):
    done = subprocess.run([sys.executable, "train.py", "configs/train_navigation.yaml"],
                          cwd=ROOT, env={**os.environ, "BOUNCE_GYM_MAX_TIMESTEPS": cap},
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2
    assert done.stderr.splitlines() == [f"error: BOUNCE_GYM_MAX_TIMESTEPS: expected an integer "
                                        f">= 1, got {cap!r}"]
