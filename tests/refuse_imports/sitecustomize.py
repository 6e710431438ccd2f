"""Makes the top-level modules named in ``$REFUSED_MODULES`` (comma-separated) look not
installed in a Python started with this folder first on ``PYTHONPATH`` (the interpreter imports
``sitecustomize`` at start-up, before any code of the test runs): the finder of the modules on
``sys.path`` is replaced by one that finds nothing under those names, so importing one raises
`ModuleNotFoundError` and `importlib.util.find_spec` returns None, as for a missing module
(libraries that probe for optional modules, such as torch and scipy, carry on)."""

import os
import sys
from importlib.machinery import PathFinder

REFUSED = set(filter(None, os.environ.get("REFUSED_MODULES", "").split(",")))


class PathFinderWithoutRefused:
    @staticmethod
    def find_spec(name, path=None, target=None):
        if name.partition(".")[0] in REFUSED:
            return None
        return PathFinder.find_spec(name, path, target)

    @staticmethod
    def invalidate_caches():
        PathFinder.invalidate_caches()


sys.meta_path[sys.meta_path.index(PathFinder)] = PathFinderWithoutRefused
