"""The docs site builds with ``mkdocs build --strict`` (no warning), and has a page for every
registered id and for every page of docs/."""

import os
import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest

pytest.importorskip("mkdocs", reason="the docs site needs the docs extra (pip install '.[docs]')")
pytest.importorskip("material", reason="the docs site needs the docs extra (mkdocs-material)")
pytest.importorskip("mkdocstrings_handlers.python",
                    reason="the docs site needs the docs extra (mkdocstrings[python])")

import gymnasium as gym  # noqa: E402 - after the skips

from bounce_gym.envs import registration  # noqa: E402 - after the skips

ROOT = Path(__file__).parents[1]
IDS = (*registration.GYM_ENVS, *registration.DRIFTER_GYM_ENVS, *registration.PETTINGZOO_ENVS,
       *registration.DRIFTER_PETTINGZOO_ENVS, *registration.PATROL_PETTINGZOO_ENVS)


class _Text(HTMLParser):
    """The text of a page's main article (its ``<article>`` element)."""

    def __init__(self):
        super().__init__()
        self.depth, self.parts = 0, []

    def handle_starttag(self, tag, attrs):
        self.depth += tag == "article"

    def handle_endtag(self, tag):
        self.depth -= tag == "article"

    def handle_data(self, data):
        if self.depth:
            self.parts.append(data)


def _article(page: Path) -> str:
    parser = _Text()
    parser.feed(page.read_text(encoding="utf-8"))
    return " ".join(" ".join(parser.parts).split())


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "NO_MKDOCS_2_WARNING": "1"}
    result = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-4000:]
    assert not re.search(r"^WARNING", result.stderr, re.M), result.stderr[-4000:]
    return out


def test_every_registered_id_has_a_page(site):
    assert len(IDS) == len(set(IDS)) >= 11
    overview = _article(site / "envs" / "index.html")
    for env_id in IDS:
        text = _article(site / "envs" / env_id.split("/")[-1] / "index.html")
        assert env_id in text and env_id in overview
        # the sections of Gymnasium's env pages (tests/test_env_pages.py checks their order),
        # from the env's docstring and the env as built, and the env's picture
        assert all(title in text for title in ("Description", "Action Space",
                                               "Observation Space", "Rewards", "Starting State",
                                               "Episode End", "Arguments", "Version History"))
        assert "The sections below follow the docstring of" in text
        assert (site / "envs" / f"{env_id.split('/')[-1]}.gif").stat().st_size > 1000
        assert len(text) > 1500


def test_gymnasium_pages_show_the_registered_horizon_and_bounds(site):
    for env_id, (kwargs, registered) in registration.GYM_ENVS.items():
        text = _article(site / "envs" / env_id.split("/")[-1] / "index.html")
        # an id of MAP_HORIZON registers none: its page shows the one of its registered map
        steps = registered or gym.make(env_id).spec.max_episode_steps
        assert re.search(rf"horizon \( ?max_episode_steps ?\) {steps}\b", text)
        assert f"world='{kwargs['world']}'" in text
        assert "index low high meaning" in text and "action meaning" in text
    navigation = _article(site / "envs" / "BounceNavigation-v0" / "index.html")
    # the clock and the history in [0, 1], the start and goal poses in [-1, 1]
    assert "0 0 1 clock" in navigation and "9 -1 1 task: start x" in navigation
    assert "16 -1 1 task: goal sin θ" in navigation


def test_every_docs_page_and_reference_page_is_built(site):
    pages = sorted((ROOT / "docs").rglob("*.md"))
    assert ROOT / "docs" / "choices" / "drifters.md" in pages  # the pages of the subfolders too
    for page in pages:
        folder = page.parent.relative_to(ROOT / "docs")
        built = site / folder / ("" if page.stem == "index" else page.stem) / "index.html"
        assert len(_article(built)) > 200, page.relative_to(ROOT).as_posix()
    reference = sorted((site / "reference").iterdir())
    assert len(reference) >= 5
    for folder in reference:
        assert len(_article(folder / "index.html")) > 100, folder.name


def test_the_configuration_reference_lists_every_key_of_every_model(site):
    from baselines.rl.train_config import TrainingConfig
    from bounce_gym_experiments.config import (
        EvaluationConfig,
        ExecutorSettings,
        Experiment,
        ModelFolder,
        SeedRange,
    )

    text = _article(site / "configuration" / "index.html")
    assert "yaml-language-server: $schema=schema/evaluation.schema.json" in text
    for model in (EvaluationConfig, Experiment, SeedRange, ModelFolder, ExecutorSettings,
                  TrainingConfig):
        table = text.split(f"{model.__name__} ", 1)[1]
        for key, field in model.model_fields.items():
            assert f"{key} " in table and " ".join(field.description.split())[:40] in table, \
                (model.__name__, key)


def test_every_id_page_shows_its_description_before_its_spaces(site):
    for env_id, about in registration.ABOUT.items():
        text = _article(site / "envs" / env_id.split("/")[-1] / "index.html")
        # the article's text without spaces: code spans split the text into separate parts
        flat, words = "".join(text.split()), "".join(about.replace("`", "").split())
        assert "Aboutthisid" in flat and words in flat, env_id
        assert flat.index("Aboutthisid") < flat.index(words) < flat.index("ObservationSpace"), \
            env_id
