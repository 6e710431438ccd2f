"""JAX's persistent compilation cache for the JAX learners: XLA programs compiled once are kept
on disk and read back by later processes, so a training run's start-up — the chunk of
iterations, and the small programs of initialisation and reset — is compiled once per machine,
configuration shape and JAX version, not once per run.

The programs are kept in ``<cache>/jax`` (`bounce_gym.model_cache.cache_folder`: the folder of
``$BOUNCE_GYM_CACHE``, by default ``<home>/cache``), where JAX names each by a hash of the
program, the compile options, the device and the JAX version; deleting the folder is always
safe (the next run compiles again). A compiled program is machine code that JAX runs as it
reads it, so the folder is used only where nobody else can write into it: it is created
with mode 0700, and one that belongs to another user or that its group or others can write is
not used (a warning says so, and the run compiles as before). A process whose JAX already has a
cache folder set (``jax_compilation_cache_dir``, e.g. by the user's own code or
``$JAX_COMPILATION_CACHE_DIR``) keeps it.
"""

from __future__ import annotations

import os
import stat

from gymnasium import logger

from bounce_gym import model_cache
from bounce_gym.trust import is_mine

__all__ = ["KIND", "enable"]

#: the kind of model in the cache folder (``<cache>/<KIND>``)
KIND = "jax"


def enable() -> None:
    """Point JAX's persistent compilation cache at ``<cache>/jax`` (module docstring), every
    program kept however quickly it compiled; nothing if JAX has a cache folder already or the
    folder is not safe."""
    import jax

    if jax.config.jax_compilation_cache_dir:
        return
    folder = model_cache.cache_folder(KIND)
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    info = os.stat(folder)
    if not is_mine(info.st_uid) or info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        logger.warn(f"the JAX compilation cache {folder} is not used: others could write "
                    f"programs into it (chmod go-w {folder}, or delete it)")
        return
    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
