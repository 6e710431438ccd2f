"""Every script in ``examples/`` runs with a small budget, writes the files it announces into
its ``--out`` folder, and writes nothing into the checkout; runs at its defaults with the modules
of every other extra refused; without a module of its own extra stops with the package's one
line naming that extra (status 2); and is listed in the README and the docs."""

import importlib.metadata
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from bounce_gym.extras import MODULE_EXTRAS, install_command

ROOT = Path(__file__).parents[1]
#: script -> (modules it needs beyond the core dependencies, small-budget arguments, the files
#: it announces under ``--out``, as paths relative to it)
EXAMPLES = {
    "jax_ppo_navigation.py": (("jax", "optax"), ["--steps", "2048", "--episodes", "5"],
                              ["jax-ppo-example/jax_ppo_seed0.zip"]),
    "sb3_native_vector_env.py": (("stable_baselines3", "torch", "rich"),
                                 ["--steps", "1024", "--episodes", "5"], ["ppo_navigation.zip"]),
    "pettingzoo_rollout_gif.py": (("pygame", "PIL"), ["--steps", "20"], ["multi_coverage.gif"]),
    "drifter_from_netcdf.py": (("xarray", "netCDF4"), ["--episodes", "10"], ["channel.nc"]),
    "planners_on_custom_map.py": ((), ["--episodes", "10", "--samples", "100"], ["l_room.yaml"]),
}
#: the examples that take more than ~20 s at their defaults (they train)
TRAINING = {"jax_ppo_navigation.py", "sb3_native_vector_env.py"}
#: the folder whose ``sitecustomize`` refuses the modules of $REFUSED_MODULES in a subprocess
REFUSER = ROOT / "tests" / "refuse_imports"


def _extra(script: str) -> str | None:
    """The one extra the example needs (None: the core is enough)."""
    extras = {MODULE_EXTRAS[module] for module in EXAMPLES[script][0]}
    assert len(extras) <= 1, extras
    return next(iter(extras), None)


def _modules_of(extra: str | None) -> set[str]:
    """The modules of `MODULE_EXTRAS` that ``extra`` installs, by the distributions
    pyproject.toml declares for it (tqdm: the `rl` extra's as well as `experiments`')."""
    if extra is None:
        return set()
    tomllib = pytest.importorskip("tomllib", reason="reading pyproject.toml needs Python >= 3.11")
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    declared = {canonicalize_name(Requirement(line).name)
                for line in project["optional-dependencies"][extra]}
    distributions = importlib.metadata.packages_distributions()
    return {module for module in MODULE_EXTRAS
            if {canonicalize_name(d) for d in distributions.get(module, [module])} & declared}


def _run(script: str, *args: str, refused=(), timeout: int = 600, **env):
    """Run the example with ``args`` in a fresh interpreter, ``refused`` modules refused."""
    env = {**os.environ, "PYTHONPATH": f"{REFUSER}{os.pathsep}{ROOT}",
           "REFUSED_MODULES": ",".join(refused), "PYTHONDONTWRITEBYTECODE": "1",
           "SDL_VIDEODRIVER": "dummy", "MPLBACKEND": "Agg", **env}
    return subprocess.run([sys.executable, str(ROOT / "examples" / script), *args], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=timeout)


def _skip_unless_installed(script: str) -> None:
    for module in EXAMPLES[script][0]:
        if importlib.util.find_spec(module) is None:
            pytest.skip(f"{script} needs {module}")


def _checkout_state() -> str:
    """Everything git sees in the checkout, ignored files included."""
    return subprocess.run(["git", "status", "--porcelain", "--ignored", "--untracked-files=all"],
                          cwd=ROOT, capture_output=True, text=True, check=True).stdout


def test_every_example_is_listed():
    assert sorted(p.name for p in (ROOT / "examples").glob("*.py")) == sorted(EXAMPLES)


@pytest.mark.parametrize("script", sorted(EXAMPLES))
def test_example_runs_into_its_out_folder(script, tmp_path):
    _skip_unless_installed(script)
    _, args, files = EXAMPLES[script]
    before = _checkout_state()
    done = _run(script, *args, "--out", str(tmp_path))
    assert done.returncode == 0, done.stderr[-3000:]
    assert _checkout_state() == before
    # nothing else at the top of --out (a training run writes its folder, with more files)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted({f.split("/")[0] for f in files})
    assert all((tmp_path / name).stat().st_size > 0 for name in files)
    assert str(tmp_path) in done.stdout  # the folder is named at the end


@pytest.mark.parametrize("script", [
    pytest.param(script, marks=pytest.mark.slow) if script in TRAINING else script
    for script in sorted(EXAMPLES)])
def test_example_runs_at_its_defaults_with_only_its_extra(script, tmp_path):
    """No arguments, and every module of the other extras refused. The cap is far above the
    minute an example takes at its defaults on the project's 2-core machine (a time is not
    asserted: docs/examples.md gives the measured ones)."""
    _skip_unless_installed(script)
    own = _modules_of(_extra(script))
    others = sorted(module for module in MODULE_EXTRAS if module not in own)
    # the default output folder is a fresh temporary one: made under tmp_path here
    done = _run(script, refused=others, timeout=180, TMPDIR=str(tmp_path))
    assert done.returncode == 0, done.stderr[-3000:]
    assert str(tmp_path) in done.stdout.splitlines()[-1]  # the folder is named at the end


@pytest.mark.parametrize(("script", "module"), [(script, module)
                                                for script, (needs, _, _) in sorted(EXAMPLES.items())
                                                for module in needs])
def test_example_without_its_extra_is_one_line_and_status_2(script, module, tmp_path):
    done = _run(script, "--out", str(tmp_path), refused=[module], timeout=120)
    assert done.returncode == 2, done.stderr[-3000:]
    extra = _extra(script)
    assert done.stderr.splitlines() == [
        f"error: examples/{script} needs the '{extra}' extra: {install_command([extra])}"]
    assert done.stdout == "" and not any(tmp_path.iterdir())  # refused before any work


def test_the_readme_and_the_docs_list_every_example_with_its_extra():
    """A line each in the README's Examples section, a section each in docs/examples.md."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    lines = readme.split("\n## Examples\n", 1)[1].split("\n## ", 1)[0].splitlines()
    sections = (ROOT / "docs" / "examples.md").read_text(encoding="utf-8").split("\n## ")[1:]
    assert "examples.md" in (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    for script in EXAMPLES:
        extra = _extra(script)
        (line,) = [line for line in lines if f"examples/{script}" in line]
        assert line.startswith(f"python examples/{script}")
        assert (f"extra: {extra}" if extra else "no extra") in line
        (section,) = [text for text in sections if f"python examples/{script}" in text]
        assert (f"Needs the `{extra}` extra" if extra else "Needs no extra") in section


def test_default_out_is_a_fresh_temporary_folder():
    """Without ``--out`` an example writes into a new temporary folder and names it."""
    done = _run("planners_on_custom_map.py", "--episodes", "2", "--samples", "10")
    assert done.returncode == 0, done.stderr[-3000:]
    written = Path(done.stdout.split("map file written to ")[-1].strip())
    try:
        assert written.is_file() and ROOT not in written.parents
    finally:
        written.unlink(missing_ok=True)
        written.parent.rmdir()
