"""The experiments tests' helper modules on ``sys.path`` (and on ``PYTHONPATH``), so that the
worker processes of a sweep — a spawned pool process, a Ray worker — import them by name too."""

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
_paths = os.environ.get("PYTHONPATH", "").split(os.pathsep)
if str(HERE) not in _paths:
    os.environ["PYTHONPATH"] = os.pathsep.join([str(HERE), *filter(None, _paths)])
