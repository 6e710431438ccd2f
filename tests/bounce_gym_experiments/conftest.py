"""The experiments tests' helper modules on ``sys.path``, and this checkout with them on
``PYTHONPATH``, so that the worker processes of a sweep — a pool process, a Ray worker — import
the helpers by name and this checkout's package (not another install of it)."""

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
_paths = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
os.environ["PYTHONPATH"] = os.pathsep.join(
    [str(HERE), str(ROOT), *(p for p in _paths if p not in (str(HERE), str(ROOT)))])
