"""The README's code — and that of the docs pages — runs, prints what the page says it
prints, and writes nothing into the folder it runs in."""

import contextlib
import io
import os
import re
from collections import Counter
from pathlib import Path

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

ROOT = Path(__file__).parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
PATTERN = r"```python\n(.*?)```(?:\n\nprints\n\n```\n(.*?)```)?"
#: (page, code, expected output) of every python block, in page order
BLOCKS = [(page.relative_to(ROOT).as_posix(), code, expected) for page in PAGES
          for code, expected in re.findall(PATTERN, page.read_text(encoding="utf-8"), re.S)]


def _ids() -> list[str]:
    """``block<i>`` for the README's blocks, ``<page>-block<i>`` for the docs pages'."""
    seen: Counter = Counter()
    ids = []
    for page, _, _ in BLOCKS:
        prefix = "" if page == "README.md" else f"{Path(page).stem}-"
        ids.append(f"{prefix}block{seen[page]}")
        seen[page] += 1
    return ids


@pytest.mark.parametrize(("page", "code", "expected"), BLOCKS, ids=_ids())
def test_readme_block_runs(page, code, expected, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, page, "exec"), {"__name__": "readme"})
    if expected:
        assert out.getvalue() == expected
    # run from a checkout, a block leaves nothing behind: what it writes goes to a temporary folder
    assert sorted(path.name for path in tmp_path.iterdir()) == []


def test_readme_has_code_and_outputs():
    readme = [expected for page, _, expected in BLOCKS if page == "README.md"]
    assert len(readme) >= 4 and any(readme)
    assert any(page == "docs/continuous_models.md" and expected for page, _, expected in BLOCKS)
