"""Every public name of the packages means one thing: no class or function name is public in two
modules with different objects (re-exports of one object are fine).

A module's public names are its ``__all__`` when it has one, else the classes and functions it
defines whose names do not start with ``_``; only the definitions count (an object whose
``__module__`` is the module).
"""

from __future__ import annotations

import importlib
import inspect
import os
import types
from collections import defaultdict
from pathlib import Path

from bounce_gym.errors import ConfigError

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

ROOT = Path(__file__).parents[1]
PACKAGES = ("bounce_gym", "baselines", "bounce_gym_experiments")

#: names that several modules define on purpose, as an interface read through the module:
#: PettingZoo's env-module convention (``from bounce_gym.envs import multi_bounce_v0;
#: multi_bounce_v0.parallel_env()``) and the ``main`` of a ``python -m`` module.
INTERFACE_NAMES = {"env", "parallel_env", "raw_env", "main"}


def module_names() -> list[str]:
    """Every module of the packages, from the files (a folder without ``__init__.py`` too)."""
    names = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


def public_definitions(module) -> dict[str, object]:
    """The classes and functions ``module`` defines and makes public (module docstring)."""
    names = getattr(module, "__all__", None)
    if names is None:
        names = [n for n in vars(module) if not n.startswith("_")]
    out = {}
    for name in names:
        obj = getattr(module, name, None)
        if ((inspect.isclass(obj) or inspect.isfunction(obj))
                and getattr(obj, "__module__", None) == module.__name__):
            out[name] = obj
    return out


def imported_modules() -> list:
    """Every module of the packages that imports with the installed extras."""
    modules = []
    for name in module_names():
        try:
            modules.append(importlib.import_module(name))
        except ModuleNotFoundError as e:  # an extra that is not installed (e.g. ray, torch)
            if (e.name or "").split(".")[0] in PACKAGES:
                raise
        except ConfigError as e:  # bounce_gym.jax without JAX says which extra to install
            if "pip install" not in str(e):
                raise
    return modules


def definitions(modules) -> dict[str, dict[str, object]]:
    """name -> {module name: object} of the public definitions of ``modules``."""
    found: dict[str, dict[str, object]] = defaultdict(dict)
    for module in modules:
        for public, obj in public_definitions(module).items():
            found[public][module.__name__] = obj
    return found


def clashes(found: dict[str, dict[str, object]]) -> dict[str, list[str]]:
    """The names bound to more than one object, with their modules (`INTERFACE_NAMES` aside)."""
    return {name: sorted(where) for name, where in found.items()
            if name not in INTERFACE_NAMES and len({id(o) for o in where.values()}) > 1}


def test_every_public_name_is_defined_once():
    assert clashes(definitions(imported_modules())) == {}


def test_the_walk_sees_the_namespace_folders_and_the_renamed_pairs():
    """The walk covers bounce_gym/jax/tasks (no ``__init__.py``), and the names that clashed
    before (issue 27) are each defined once now."""
    assert "bounce_gym.jax.tasks.navigation" in module_names()
    found = definitions(imported_modules())
    assert set(found["DrifterReachability"]) == {"baselines.drifters.reachability"}
    assert set(found["SafeGraphReachability"]) == {"baselines.visibility.graph"}
    assert set(found["persistent_behavior"]) == {"baselines.drifters.behavior"}
    assert set(found["joint_monitoring_cycles"]) == {"baselines.multirobot.monitoring"}
    assert set(found["RunFiles"]) == {"baselines.rl.train"}
    assert set(found["RunCurves"]) == {"baselines.rl.curves"}


def _module(name: str, source: str) -> types.ModuleType:
    module = types.ModuleType(name)
    exec(compile(source, name, "exec"), module.__dict__)
    return module


def test_a_clash_is_found_and_a_re_export_or_a_private_helper_is_not():
    first = _module("pkg.first", "__all__ = ['Shared', 'f']\nclass Shared: ...\ndef f(): ...\n"
                                 "def helper(): ...\n")
    second = _module("pkg.second", "class Shared: ...\ndef _f(): ...\n")
    assert clashes(definitions([first, second])) == {"Shared": ["pkg.first", "pkg.second"]}
    # a re-export is the same object; a name left out of __all__ is not public
    third = _module("pkg.third", "def helper(): ...\n")
    reexport = _module("pkg.reexport", "")
    reexport.Shared = first.Shared
    assert clashes(definitions([first, third, reexport])) == {}
    # an interface name (PettingZoo's env()) may be defined by every env module
    envs = [_module(f"pkg.env{k}", "def env(): ...\n") for k in range(2)]
    assert clashes(definitions(envs)) == {}
