"""How something was made: package versions, the source commit, the Python, the platform and the
machine. One record serves both the evaluation's ``results.json`` (``provenance``) and every
trained model's metadata (``trained_with``), so that a result or an
agent can be traced to the code and the machine that produced it.

The machine matters for trained weights: the same configuration, seed and library versions give
the same weights bit for bit on one machine, but a CPU with other vector units (AVX-512 or not,
fused multiply-add or not) may pick other kernels in torch or XLA, whose float sums round
differently; ``docs/learning.md`` says what is compared where.
"""

from __future__ import annotations

import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path

#: Distributions whose versions are recorded (``None`` when not installed).
PACKAGES = ("bounce-gym", "gymnasium", "pettingzoo", "pymunk", "numpy", "scipy",
            "stable-baselines3", "sb3-contrib", "torch", "jax", "jaxlib", "optax")
#: Where Linux describes the processor, and the most bytes of it read.
CPUINFO = Path("/proc/cpuinfo")
_CPUINFO_BYTES = 1 << 16
#: The ``/proc/cpuinfo`` fields naming the processor, the first present wins (x86, then ARM).
_CPU_FIELDS = ("model name", "Hardware", "Processor", "cpu model")


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


def cpu_model(cpuinfo: Path = CPUINFO) -> str | None:
    """The processor's model name: from ``cpuinfo`` (its first `_CPUINFO_BYTES` bytes) where it
    names one, else what `platform.processor` says; ``None`` when neither does."""
    try:
        with cpuinfo.open("rb") as fh:
            text = fh.read(_CPUINFO_BYTES).decode("utf-8", "replace")
    except OSError:
        text = ""
    fields: dict[str, str] = {}
    for line in text.splitlines():
        key, sep, value = line.partition(":")
        if sep and value.strip():
            fields.setdefault(key.strip(), value.strip())
    for key in _CPU_FIELDS:
        if key in fields:
            return fields[key][:200]
    return platform.processor() or None


def provenance() -> dict[str, object]:
    """Versions, git state, Python version, platform (the OS), machine architecture and
    processor model: the ``provenance`` of ``results.json`` and the ``trained_with`` of a
    model's metadata."""
    return {"packages": package_versions(), "git": git_state(),
            "python": sys.version.split()[0], "platform": platform.platform(),
            "machine": platform.machine() or None, "cpu": cpu_model()}
