"""docs/choices/: one page per subject, all listed by its index, and every reference to a choice
in the code, tests and docs (``docs/choices/<page>.md, "<heading>"``) names a heading of that
page."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).parents[1]
CHOICES = ROOT / "docs" / "choices"
#: a reference by heading, the heading possibly wrapped over lines (with a comment's ``#:``)
REFERENCE = re.compile(r"choices/(\w+)\.md,?\s*[\"“]([^\"”]+)[\"”]")


def _headings(page: Path) -> set[str]:
    return {m.group(1).strip() for m in re.finditer(r"^#{1,3} (.+)$",
                                                     page.read_text(encoding="utf-8"), re.M)}


def _tracked_text_files() -> list[Path]:
    names = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                           check=True).stdout.split()
    return [ROOT / n for n in names if n.endswith((".py", ".md", ".yaml", ".yml", ".cff"))]


def test_the_index_lists_every_page():
    index = (CHOICES / "index.md").read_text(encoding="utf-8")
    pages = sorted(p.name for p in CHOICES.glob("*.md") if p.name != "index.md")
    assert len(pages) >= 10
    assert [p for p in pages if f"]({p})" not in index] == []
    assert "## The papers" in index


def test_every_reference_by_heading_names_a_heading_of_its_page():
    found, wrong = 0, []
    for path in _tracked_text_files():
        if not path.exists():
            continue
        for m in REFERENCE.finditer(path.read_text(encoding="utf-8")):
            page = CHOICES / f"{m.group(1)}.md"
            heading = re.sub(r"\s*\n\s*(#:?\s*)?", " ", m.group(2)).strip()
            stem = heading.removesuffix("...").removesuffix("…").strip()
            found += 1
            if not page.exists() or not any(h == heading or h.startswith(stem)
                                            for h in _headings(page)):
                wrong.append(f"{path.relative_to(ROOT)}: {m.group(0)!r}")
    assert found > 50  # the docstrings cite the choices by heading
    assert wrong == []


def test_no_reference_to_the_old_single_page():
    single_page = "docs/choices" + ".md"  # split so that this file does not name it
    old = [str(p.relative_to(ROOT)) for p in _tracked_text_files()
           if p.exists() and single_page in p.read_text(encoding="utf-8")]
    assert old == []
