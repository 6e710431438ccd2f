"""Makes the top-level modules named in ``$REFUSED_MODULES`` (comma-separated) look not
installed in a Python started with this folder first on ``PYTHONPATH`` (the interpreter imports
``sitecustomize`` at start-up, before any code of the test runs): the finder of the modules on
``sys.path`` is replaced by one that finds nothing under those names (their distributions'
metadata stays visible), so importing one raises `ModuleNotFoundError` and
`importlib.util.find_spec` returns None, as for a missing module; libraries that probe for
optional modules (torch, scipy, xarray) carry on."""

import os
import sys
from importlib.machinery import PathFinder

REFUSED = set(filter(None, os.environ.get("REFUSED_MODULES", "").split(",")))


class PathFinderWithoutRefused(PathFinder):
    @classmethod
    def find_spec(cls, name, path=None, target=None):
        if name.partition(".")[0] in REFUSED:
            return None
        return super().find_spec(name, path, target)


sys.meta_path[sys.meta_path.index(PathFinder)] = PathFinderWithoutRefused
