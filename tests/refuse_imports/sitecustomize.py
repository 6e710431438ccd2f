"""Makes the top-level modules named in ``$REFUSED_MODULES`` (comma-separated) unimportable, as
if not installed, in a Python started with this folder first on ``PYTHONPATH`` (the interpreter
imports ``sitecustomize`` at start-up, before any code of the test runs). A finder in front of
the others raises `ModuleNotFoundError` for them, so ``import`` fails and
`importlib.util.find_spec` raises, which `bounce_gym.extras.installed` counts as missing."""

import os
import sys

REFUSED = set(filter(None, os.environ.get("REFUSED_MODULES", "").split(",")))


class Refuse:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in REFUSED:
            raise ModuleNotFoundError(f"No module named {name!r} (refused)", name=name)


sys.meta_path.insert(0, Refuse())
