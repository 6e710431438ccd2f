"""Writes the bump tables that ship with the package (`bounce_gym.dynamics.bump_table`,
``SHIPPED_TABLES``): every table the shipped evaluations of `SHIPPED_FOR` build.

``python -m bounce_gym_experiments.shipped_tables`` removes the shipped tables, plays one seed of
every experiment of those configurations with an empty cache folder of its own
(``$BOUNCE_GYM_CACHE``), so that each table they ask for is built, and stores each one
compressed (`numpy.savez_compressed`: a fifth to a sixth of the size) in the package. Run it
after a change to the simulator's physics or to a table's layout (``bump_table.FORMAT``) or to
those configurations' dynamic-physics experiments: tables are found by fingerprint, so a stale
one is never read, and tests/dynamics/test_shipped_tables.py fails until they are rewritten.
"""

from __future__ import annotations

import argparse
import io
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from bounce_gym.dynamics.bump_table import SHIPPED_TABLES
from bounce_gym.files import atomic_write
from bounce_gym.model_cache import CACHE_VARIABLE

#: the shipped evaluations whose tables ship (configs/)
SHIPPED_FOR = ("eval_default.yaml",)
_KIND = "bump_tables"


def one_seed(config: dict) -> dict:
    """A validated configuration with one seed per experiment."""
    return {**config, "experiments": [{**exp, "seeds": exp["seeds"][:1]}
                                      for exp in config["experiments"]]}


def tables_built(config_names: tuple[str, ...]) -> dict[str, bytes]:
    """Fingerprint -> the compressed file of every table the configurations build."""
    from bounce_gym_experiments.config import configs_folder, load_config, validate_config
    from bounce_gym_experiments.runner import run

    before = os.environ.get(CACHE_VARIABLE)
    with tempfile.TemporaryDirectory() as cache:
        os.environ[CACHE_VARIABLE] = cache
        try:
            for name in config_names:
                run(one_seed(validate_config(load_config(configs_folder() / name))),
                    progress=False)
            return {p.stem: _compressed(p) for p in sorted((Path(cache) / _KIND).glob("*.npz"))}
        finally:
            if before is None:
                del os.environ[CACHE_VARIABLE]
            else:
                os.environ[CACHE_VARIABLE] = before


def _compressed(path: Path) -> bytes:
    with np.load(io.BytesIO(path.read_bytes()), allow_pickle=False) as npz:
        arrays = {name: npz[name] for name in npz.files}
    out = io.BytesIO()
    np.savez_compressed(out, **arrays)
    return out.getvalue()


def main(argv: list[str] | None = None) -> int:
    argparse.ArgumentParser(prog="python -m bounce_gym_experiments.shipped_tables",
                            description=__doc__.splitlines()[0]).parse_args(argv)
    shutil.rmtree(SHIPPED_TABLES, ignore_errors=True)
    tables = tables_built(SHIPPED_FOR)
    SHIPPED_TABLES.mkdir()
    for key, data in tables.items():
        atomic_write(SHIPPED_TABLES / f"{key}.npz", data)
        print(f"{SHIPPED_TABLES / key}.npz: {len(data) / 2**20:.2f} MiB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
