"""What a user installs, reads and cites: the licence, the citation file, the changelog with the
history of every registered id, and the wheel's metadata and ``py.typed`` markers."""

import email
import importlib.metadata
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import gymnasium as gym
import pettingzoo
import pytest
import yaml
from packaging.version import Version

import bounce_gym  # noqa: F401  (registers the environments)

ROOT = Path(__file__).parents[1]
tomllib = pytest.importorskip("tomllib")  # Python 3.11+
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
#: every id this package registers, Gymnasium and PettingZoo
IDS = sorted({env_id for env_id in [*gym.registry, *pettingzoo.parallel_registry,
                                    *pettingzoo.aec_registry]
              if env_id.startswith("bounce_gym/")})


def test_the_licence_is_mit_for_the_bounce_gym_authors():
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("MIT License\n\nCopyright (c) 2026 the bounce_gym authors\n")
    assert "THE SOFTWARE IS PROVIDED \"AS IS\", WITHOUT WARRANTY OF ANY KIND" in text
    assert (PROJECT["license"], PROJECT["license-files"]) == ("MIT", ["LICENSE"])


def test_the_citation_file_cites_this_version_and_the_papers():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert (cff["cff-version"], cff["type"], cff["license"]) == ("1.2.0", "software", "MIT")
    assert cff["version"] == PROJECT["version"]
    assert cff["title"] and cff["message"] and cff["authors"]
    references = cff["references"]
    # the five texts in the seeds: the navigation/coverage and localization papers, the
    # multi-robot article, Alam's dissertation and Nilles et al.
    assert len(references) == 5
    for ref in references:
        assert ref["type"] in {"article", "conference-paper", "thesis"}
        assert ref["title"] and ref["authors"] and isinstance(ref["year"], int)
        for author in ref["authors"]:
            assert author["family-names"] and author["given-names"]
    by_title = {ref["title"]: ref for ref in references}
    filters = by_title["Space-efficient filters for mobile robot localization from discrete "
                       "limit cycles"]
    assert (filters["journal"], filters["volume"], filters["year"]) == (
        "IEEE Robotics and Automation Letters", 3, 2018)
    thesis = by_title["A Dynamical System Approach for Resource-Constrained Mobile Robotics"]
    assert thesis["doi"] == "10.25148/etd.FIDC006561"


def test_the_changelog_has_the_history_of_every_registered_id():
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert IDS and len(IDS) >= 11
    rows = dict(re.findall(r"^\| `(bounce_gym/[\w-]+)` \| (.+) \|$", text, re.M))
    assert sorted(rows) == IDS
    for env_id, history in rows.items():
        assert re.match(r"\d+\.\d+\.\d+: added\. ", history), env_id
    assert "Kept unchanged when v1 was added" in rows["bounce_gym/BounceNavigation-v0"]


def test_the_changelog_has_an_entry_for_this_version():
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    versions = re.findall(r"^## \[(\d+\.\d+\.\d+)\]", text, re.M)
    assert versions and versions[0] == PROJECT["version"]
    Version(PROJECT["version"])  # a valid version


def test_the_project_metadata_is_complete():
    assert PROJECT["readme"] == "README.md" and (ROOT / "README.md").is_file()
    assert [author["name"] for author in PROJECT["authors"]] == ["the bounce_gym authors"]
    assert len(PROJECT["keywords"]) >= 5
    assert "Typing :: Typed" in PROJECT["classifiers"]
    # a license expression excludes the deprecated license classifiers (PEP 639)
    assert not any(c.startswith("License ::") for c in PROJECT["classifiers"])
    for url in PROJECT.get("urls", {}).values():
        assert url.startswith("https://"), url


def test_the_typed_packages_carry_their_marker():
    package_data = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))[
        "tool"]["setuptools"]["package-data"]
    for package in ("bounce_gym", "baselines"):
        assert (ROOT / package / "py.typed").is_file()
        assert "py.typed" in package_data[package]


def test_the_wheel_ships_the_licence_the_markers_and_the_metadata(tmp_path):
    if Version(importlib.metadata.version("setuptools")) < Version("77"):
        pytest.skip("pyproject.toml's build-system needs setuptools >= 77 (PEP 639)")
    source = tmp_path / "source"
    for name in ("pyproject.toml", "setup.py", "README.md", "LICENSE"):
        (source / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / name, source / name)
    for folder in ("bounce_gym", "baselines", "bounce_gym_experiments", "configs"):
        shutil.copytree(ROOT / folder, source / folder,
                        ignore=shutil.ignore_patterns("__pycache__", "agents", "*.zip"))
    build = ("from setuptools import build_meta; "
             f"print(build_meta.build_wheel({str(tmp_path / 'dist')!r}))")
    done = subprocess.run([sys.executable, "-c", build], cwd=source, capture_output=True,
                          text=True, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    wheel = zipfile.ZipFile(tmp_path / "dist" / done.stdout.strip().splitlines()[-1])
    names = set(wheel.namelist())
    assert {"bounce_gym/py.typed", "baselines/py.typed"} <= names
    # the design's two top-level packages, and the runner under a name of this project's own
    assert {name.split("/")[0] for name in names if not name.startswith("bounce_gym-")} == {
        "bounce_gym", "baselines", "bounce_gym_experiments"}
    dist_info = f"bounce_gym-{PROJECT['version']}.dist-info"
    assert f"{dist_info}/licenses/LICENSE" in names
    metadata = email.message_from_bytes(wheel.read(f"{dist_info}/METADATA"))
    assert metadata["License-Expression"] == "MIT"
    assert metadata["License-File"] == "LICENSE"
    assert metadata["Author"] == "the bounce_gym authors"
    assert metadata["Description-Content-Type"] == "text/markdown"
    assert metadata.get_all("Classifier") == PROJECT["classifiers"]
    assert metadata["Keywords"].split(",") == PROJECT["keywords"]
