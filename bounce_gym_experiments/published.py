"""Result tables in README.md and the docs, generated from the files an evaluation wrote.

A published table is a marker block in a Markdown file that cites a file of a run's
leaderboard, copied into the repository (``docs/results/<name>/``)::

    <!-- results: docs/results/benchmark/verdicts.csv -->
    ...the generated table...
    <!-- end results -->

``verdicts.csv`` gives the "Who wins" table (`bounce_gym_experiments.leaderboard.headline_markdown`);
``leaderboard.csv`` a table per experiment, optionally limited to some experiments and columns:
``<!-- results: docs/results/benchmark/leaderboard.csv experiments=navigation-lab,coverage-lab
columns=success,ticks -->`` (the family's score is always shown, a listed column only where the
experiment has it). `stale` lists the blocks
that differ from their file (a test runs it); `rewrite` regenerates them (``bounce-gym tables
--write``), after `publish` copied a run's files in (``--from RUN_FOLDER``). Paths are relative
to the repository root; a block never cites a file outside it.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

from bounce_gym.errors import ConfigError
from bounce_gym.files import atomic_write
from bounce_gym_experiments.leaderboard import headline_markdown
from bounce_gym_experiments.report import cell

#: the files of a run that a published table may cite (and `publish` copies)
PUBLISHED_FILES = ("leaderboard.md", "leaderboard.csv", "verdicts.csv")
#: the largest file a block may cite
MAX_BYTES = 8_000_000
BLOCK = re.compile(r"(<!-- results: (?P<spec>[^>]*?) -->\n)(?P<body>.*?)(<!-- end results -->)",
                   re.S)


def documents(root: Path) -> list[Path]:
    """The Markdown files that may hold published tables: README.md and docs/**/*.md but the
    published leaderboards themselves (docs/results/)."""
    results = root / "docs" / "results"
    return [root / "README.md", *sorted(p for p in (root / "docs").rglob("*.md")
                                        if results not in p.parents)]


def _read_csv(root: Path, name: str) -> list[dict]:
    path = (root / name).resolve()
    if root.resolve() not in path.parents or path.name not in PUBLISHED_FILES[1:]:
        raise ConfigError(f"results block: {name!r} is not a verdicts.csv or leaderboard.csv "
                          "inside the repository")
    if not path.is_file() or path.stat().st_size > MAX_BYTES:
        raise ConfigError(f"results block: {name} is missing or larger than {MAX_BYTES} bytes")
    return list(csv.DictReader(io.StringIO(path.read_text(encoding="utf-8"))))


def _number(text: str):
    if text in ("", "None"):
        return None
    try:
        value = float(text)
    except ValueError:
        return text
    return int(value) if value.is_integer() and "." not in text else value


def render(root: Path, spec: str) -> str:
    """The table a block's ``spec`` (its marker's text) stands for."""
    name, *options = spec.split()
    chosen = dict(option.split("=", 1) for option in options if "=" in option)
    rows = _read_csv(root, name)
    if Path(name).name == "verdicts.csv":
        return "\n".join(headline_markdown(rows)) + "\n"
    wanted = chosen.get("experiments")
    experiments = [e for e in dict.fromkeys(r["experiment"] for r in rows)
                   if wanted is None or e in wanted.split(",")]
    lines = []
    for experiment in experiments:
        mine = [{k: _number(v) for k, v in r.items()} for r in rows
                if r["experiment"] == experiment]
        score = str(mine[0]["score"])
        columns = [score] + [c for c in chosen.get("columns", "").split(",")
                             if c and c != score and any(r.get(c) is not None for r in mine)]
        lines += [f"**{experiment}** ({mine[0]['difficulty']}; score: {score})", "",
                  "| policy | " + " | ".join(columns) + " |",
                  "|---|" + "---|" * len(columns)]
        lines += ["| " + " | ".join(cell(r, c) for c in ["policy", *columns]) + " |"
                  for r in mine]
        lines.append("")
    return "\n".join(lines)


def _blocks(path: Path):
    text = path.read_text(encoding="utf-8")
    return text, list(BLOCK.finditer(text))


def stale(root: Path) -> list[str]:
    """``<file>: <spec>`` for every block whose table differs from the file it cites."""
    out = []
    for path in documents(root):
        text, blocks = _blocks(path)
        out += [f"{path.relative_to(root)}: {m['spec']}" for m in blocks
                if m["body"] != render(root, m["spec"])]
    return out


def rewrite(root: Path) -> list[Path]:
    """Regenerate every block; returns the files that changed."""
    changed = []
    for path in documents(root):
        text, blocks = _blocks(path)
        if not blocks:
            continue
        new = BLOCK.sub(lambda m: m.group(1) + render(root, m["spec"]) + m.group(4), text)
        if new != text:
            atomic_write(path, new.encode("utf-8"))
            changed.append(path)
    return changed


def publish(run_folder: Path, into: Path) -> list[Path]:
    """Copy a run's `PUBLISHED_FILES` into ``into`` (e.g. ``docs/results/benchmark``)."""
    missing = [n for n in PUBLISHED_FILES if not (run_folder / n).is_file()]
    if missing:
        raise ConfigError(f"--from: {run_folder} has no {', '.join(missing)} (a run of a "
                          "configuration with leaderboard: true writes them)")
    into.mkdir(parents=True, exist_ok=True)
    for name in PUBLISHED_FILES:
        atomic_write(into / name, (run_folder / name).read_bytes())
    return [into / n for n in PUBLISHED_FILES]
