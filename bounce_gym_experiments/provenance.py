"""What a results file must say about how it was made: package versions, the source commit, the
Python and the platform."""

from __future__ import annotations

import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path

#: Distributions whose versions are recorded (``None`` when not installed).
PACKAGES = ("bounce-gym", "gymnasium", "pettingzoo", "pymunk", "numpy", "scipy",
            "stable-baselines3", "sb3-contrib", "torch")


def package_versions() -> dict[str, str | None]:
    """The installed version of each of `PACKAGES`, ``None`` for one that is not installed."""
    out: dict[str, str | None] = {}
    for name in PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def git_state(folder: Path | None = None) -> dict[str, object]:
    """The commit of the git checkout holding ``folder`` (default: this package's source) and
    whether its tracked files differ from it; ``"unknown"`` and ``None`` outside a checkout or
    without git."""
    folder = Path(__file__).resolve().parent if folder is None else Path(folder)

    def git(*args: str) -> str | None:
        try:
            done = subprocess.run(["git", "-C", str(folder), *args], capture_output=True,
                                  text=True, timeout=10, check=False)
        except (OSError, subprocess.SubprocessError):
            return None
        return done.stdout.strip() if done.returncode == 0 else None

    commit = git("rev-parse", "HEAD")
    if commit is None:
        return {"commit": "unknown", "dirty": None}
    status = git("status", "--porcelain", "--untracked-files=no")
    return {"commit": commit, "dirty": None if status is None else bool(status)}


def provenance() -> dict[str, object]:
    """Versions, git state, Python version and platform, for ``results.json``."""
    return {"packages": package_versions(), "git": git_state(),
            "python": sys.version.split()[0], "platform": platform.platform()}
