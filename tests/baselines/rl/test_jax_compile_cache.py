"""JAX's persistent compilation cache for the JAX learners (`baselines.rl.jaxrl.compile_cache`):
programs land in ``<cache>/jax``, a folder others can write is not used, and a cache folder the
process's JAX already has is kept. Each case runs in its own process (JAX's configuration is
global)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("jax")

ROOT = Path(__file__).parents[3]
#: enables the cache, compiles one small program, prints the cache folder JAX uses
PROGRAM = (
    "import jax, jax.numpy as jnp\n"
    "from baselines.rl.jaxrl import compile_cache\n"
    "compile_cache.enable()\n"
    "jax.jit(lambda x: jnp.sin(x) * 2)(jnp.arange(3.0)).block_until_ready()\n"
    "print(jax.config.jax_compilation_cache_dir)\n")


def _run(cache: Path, **extra: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith("JAX_")}
    env.update(BOUNCE_GYM_CACHE=str(cache), PYTHONPATH=str(ROOT), **extra)
    return subprocess.run([sys.executable, "-c", PROGRAM], env=env, capture_output=True,
                          text=True, timeout=300, check=True)


def test_compiled_programs_are_kept_in_the_cache_folder(tmp_path):
    done = _run(tmp_path)
    folder = tmp_path / "jax"
    assert done.stdout.strip() == str(folder)
    assert any(folder.iterdir())  # the program, kept
    assert folder.stat().st_mode & 0o777 == 0o700


def test_a_folder_others_can_write_is_not_used(tmp_path):
    folder = tmp_path / "jax"
    folder.mkdir(mode=0o777)
    folder.chmod(0o777)
    done = _run(tmp_path)
    assert done.stdout.strip() == "None"
    assert "others could write programs into it" in done.stderr
    assert not any(folder.iterdir())


def test_a_cache_folder_jax_already_has_is_kept(tmp_path):
    own = tmp_path / "mine"
    done = _run(tmp_path, JAX_COMPILATION_CACHE_DIR=str(own))
    assert done.stdout.strip() == str(own)
    assert not (tmp_path / "jax").exists()
