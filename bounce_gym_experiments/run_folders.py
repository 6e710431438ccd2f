"""An evaluation's run folder, ``<output>/<name>-<timestamp>/``, and finding the finished ones.

The folder appears whole or not at all (`bounce_gym.files.NewFolder`): everything is written
into a hidden sibling, ``.<name>-<timestamp>.tmp-<random>``, which is renamed to its name once
complete. Two runs of one name in the same second get ``<name>-<timestamp>-2``, … A run killed
while writing its report leaves only the hidden folder, which `finished_runs` (and anything that
collects run folders) skips; it may be deleted.
"""

from __future__ import annotations

import re
import time
from collections.abc import Mapping
from pathlib import Path

from bounce_gym.files import NewFolder

#: a finished run folder's name: ``<name>-<YYYYmmdd>-<HHMMSS>``, perhaps with ``-<n>``
RUN_FOLDER = re.compile(r"(?P<name>[^.].*)-(?P<stamp>\d{8}-\d{6})(?:-(?P<n>\d+))?")


def new_run_folder(config: Mapping) -> NewFolder:
    """The run folder of a validated evaluation configuration, to be written now: ``with`` it
    as ``folder``, write into ``folder``; its ``path`` is then the finished folder's."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    return NewFolder(Path(config["output"]) / f"{config['name']}-{stamp}")


def finished_runs(output: Path) -> list[Path]:
    """The finished run folders in ``output``, by name: not the units folders, nor the hidden
    folders of runs still writing or killed while writing."""
    if not Path(output).is_dir():
        return []
    return [path for path in sorted(Path(output).iterdir())
            if RUN_FOLDER.fullmatch(path.name) and path.is_dir()]
