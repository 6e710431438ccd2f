"""The curated public API: every package of bounce_gym, baselines and bounce_gym_experiments says
what users import from it (``__all__``), every name listed exists, ``from <package> import *``
gives exactly those names, and the docs' API reference has a page for every package that
exports any (docs/site_scripts/hooks.py, ``REFERENCE``)."""

from __future__ import annotations

import ast
import importlib
import os
from pathlib import Path

import pytest

from bounce_gym.errors import ConfigError

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

ROOT = Path(__file__).parents[1]
PACKAGES = ("bounce_gym", "baselines", "bounce_gym_experiments")


def _name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


#: every package (a folder with an ``__init__.py``) and every module file of the three packages
PACKAGE_NAMES = sorted(_name(p) for top in PACKAGES for p in (ROOT / top).rglob("__init__.py"))
MODULE_NAMES = sorted(_name(p) for top in PACKAGES for p in (ROOT / top).rglob("*.py"))


def _import(name: str):
    """The module, or a skip when it needs an extra that is not installed."""
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as e:
        if (e.name or "").split(".")[0] in PACKAGES:
            raise
        pytest.skip(f"{name} needs {e.name}, not installed")
    except ConfigError as e:  # bounce_gym.jax without JAX
        if "pip install" not in str(e):
            raise
        pytest.skip(str(e))


def _reference() -> tuple[str, ...]:
    """``REFERENCE`` of the docs hooks, read without importing mkdocs."""
    tree = ast.parse((ROOT / "docs" / "site_scripts" / "hooks.py").read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "REFERENCE"
                                                for t in node.targets):
            return tuple(ast.literal_eval(node.value))
    raise AssertionError("docs/site_scripts/hooks.py has no REFERENCE")


@pytest.mark.parametrize("name", PACKAGE_NAMES)
def test_every_package_lists_its_public_names(name):
    module = _import(name)
    assert isinstance(getattr(module, "__all__", None), list), f"{name} has no __all__ list"


@pytest.mark.parametrize("name", MODULE_NAMES)
def test_every_name_in_all_exists_once(name):
    module = _import(name)
    names = getattr(module, "__all__", [])
    assert len(names) == len(set(names)), f"{name}.__all__ repeats a name"
    missing = [n for n in names if not hasattr(module, n)]
    assert missing == []


@pytest.mark.parametrize("name", PACKAGE_NAMES)
def test_star_import_gives_exactly_all(name):
    module = _import(name)
    namespace: dict = {}
    exec(f"from {name} import *", namespace)
    namespace.pop("__builtins__")
    assert set(namespace) == set(module.__all__)


def test_the_api_reference_shows_every_package_that_exports_names():
    reference = set(_reference())
    exporting = {name for name in PACKAGE_NAMES if _literal_all_size(name) > 0}
    assert "bounce_gym.worlds" in exporting
    assert exporting - reference == set()


def _literal_all_size(name: str) -> int:
    """How many names the package's ``__init__.py`` lists in a literal ``__all__``."""
    tree = ast.parse((ROOT / Path(*name.split(".")) / "__init__.py").read_text(encoding="utf-8"))
    for node in tree.body:
        targets = node.targets if isinstance(node, ast.Assign) else (
            [node.target] if isinstance(node, ast.AnnAssign) else [])
        if any(getattr(t, "id", None) == "__all__" for t in targets):
            return len(ast.literal_eval(node.value))
    return 0


def test_the_env_classes_load_on_first_use_only():
    """``import bounce_gym`` registers the ids without importing an env; the classes of
    `bounce_gym.envs` are the modules' own objects once asked for."""
    import subprocess
    import sys

    code = ("import sys, bounce_gym\n"
            "print(sorted(m for m in sys.modules if m.startswith('bounce_gym.envs.')))\n"
            "from bounce_gym.envs import BounceEnv, PatrolEnv\n"
            "from bounce_gym.envs.bounce_env import BounceEnv as B\n"
            "from bounce_gym.envs.patrol.env import PatrolEnv as P\n"
            "print(BounceEnv is B and PatrolEnv is P)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}).stdout.split("\n")
    assert out[0] == "['bounce_gym.envs.registration']"
    assert out[1] == "True"
    import bounce_gym.envs

    with pytest.raises(AttributeError, match="has no attribute 'BounceEnvv'"):
        bounce_gym.envs.BounceEnvv  # noqa: B018


#: the packages whose public API `make lint` type-checks (pyproject [tool.mypy] ``files``)
TYPE_CHECKED = ("bounce_gym", "bounce_gym.envs", "bounce_gym.worlds", "bounce_gym.jax", "baselines")


@pytest.mark.parametrize("package", TYPE_CHECKED)
def test_the_type_checker_covers_the_modules_behind_all(package):
    """Every class and function in ``__all__`` of these packages is defined in a file that
    mypy checks (a listed file, or one under a listed folder)."""
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+
    files = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))[
        "tool"]["mypy"]["files"]
    checked = [(ROOT / f).resolve() for f in files]
    assert all(p.exists() for p in checked), files
    module = _import(package)
    uncovered = []
    for name in module.__all__:
        obj = getattr(module, name)
        if not callable(obj) or not getattr(obj, "__module__", "").startswith(PACKAGES):
            continue  # constants, submodules, __version__
        path = Path(importlib.import_module(obj.__module__).__file__).resolve()
        if not any(path == c or c in path.parents for c in checked):
            uncovered.append(f"{name} ({obj.__module__})")
    assert uncovered == []
