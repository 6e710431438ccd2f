"""The optional dependency groups (extras) of the distribution, and the one-line error of a
feature whose extra is missing.

``pip install bounce-gym`` installs the core: every Gymnasium and PettingZoo env of the package
(made, reset and stepped) and the planners. What needs more is an extra,
``pip install 'bounce-gym[<extra>]'``; `MODULE_EXTRAS` says which extra installs which
importable module. A feature checks its modules with `require` before it starts, and a missing
one is a `MissingExtraError` of one line:

    executor ray needs the 'distributed' extra: pip install 'bounce-gym[distributed]'

A script run from the command line (the ``examples/``) checks with `exit_unless_installed`,
which prints that line as the ``bounce-gym`` commands do and exits with status 2.
"""

from __future__ import annotations

import importlib.util
import sys

from bounce_gym.errors import MissingExtraError

#: the distribution's name, as ``pip install`` takes it
DISTRIBUTION = "bounce-gym"

#: top-level module -> the extra (pyproject's ``[project.optional-dependencies]``) that installs it
MODULE_EXTRAS = {
    "pygame": "render",
    "PIL": "render",
    "xarray": "drifters",
    "netCDF4": "drifters",
    "matplotlib": "experiments",
    "tqdm": "experiments",
    "stable_baselines3": "rl",
    "sb3_contrib": "rl",
    "torch": "rl",
    "rich": "rl",
    "jax": "jax",
    "optax": "jax",
    "tensorboard": "tensorboard",
    "ray": "distributed",
    "parcels": "drifters-check",
    "cvxpy": "patrol-check",
}


def install_command(extras: list[str] | tuple[str, ...]) -> str:
    """``pip install 'bounce-gym[a,b]'`` for these extras."""
    return f"pip install '{DISTRIBUTION}[{','.join(extras)}]'"


def missing_extra(feature: str, extras: list[str] | tuple[str, ...]) -> MissingExtraError:
    """The one-line error of ``feature`` that needs ``extras`` (not installed)."""
    named = " and ".join(f"'{extra}'" for extra in extras)
    noun = "extra" if len(extras) == 1 else "extras"
    return MissingExtraError(f"{feature} needs the {named} {noun}: {install_command(extras)}")


def installed(module: str) -> bool:
    """Whether the top-level ``module`` can be imported (found without importing it)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):  # an import hook refused it, or a half-set-up module
        return False


def require(feature: str, *modules: str) -> None:
    """Raise `MissingExtraError` naming ``feature`` and the extras to install unless every one
    of ``modules`` (top-level names, keys of `MODULE_EXTRAS`) can be imported."""
    unknown = [module for module in modules if module not in MODULE_EXTRAS]
    if unknown:
        raise KeyError(f"no extra installs {unknown}")  # a bug of the caller, not user input
    extras = [MODULE_EXTRAS[module] for module in modules if not installed(module)]
    if extras:
        raise missing_extra(feature, list(dict.fromkeys(extras)))


def exit_unless_installed(feature: str, *modules: str) -> None:
    """`require` for a script: where an extra is missing, print ``error: <its one line>`` on
    stderr and exit with status 2, without a traceback (as the ``bounce-gym`` commands do)."""
    try:
        require(feature, *modules)
    except MissingExtraError as exc:
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None


def from_import_error(feature: str, exc: ImportError) -> MissingExtraError | None:
    """The `MissingExtraError` of ``feature`` for an `ImportError` of a module an extra
    installs; None for any other module (a bug or a broken install, to be raised as it is)."""
    name = (exc.name or "").split(".")[0]
    if name not in MODULE_EXTRAS:
        return None
    return missing_extra(feature, [MODULE_EXTRAS[name]])
