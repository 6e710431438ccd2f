"""MkDocs hooks of the docs site (mkdocs.yml, ``hooks:``): the generated pages.

Nothing on the environment pages is typed by hand: each registered id (the tables of
`bounce_gym.envs.registration`) is built with its registered arguments, and its page has the
sections of Gymnasium's env pages, from the env's docstring and the env as built, with a short
animation the env renders (`site_pages`). The API reference has one page per module of
`REFERENCE`, rendered by mkdocstrings. The pages and pictures exist only in the build (virtual
paths under ``envs/`` and ``reference/``); the site's navigation lists the pages.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[2]
#: the modules of the API reference, in navigation order: every package with a curated
#: ``__all__`` (its page shows exactly those names; tests/test_public_api.py checks the list) and
#: the env modules
REFERENCE = (
    "bounce_gym",
    "bounce_gym.envs",
    "bounce_gym.envs.registration",
    "bounce_gym.envs.bounce_env",
    "bounce_gym.envs.goal_navigation_env",
    "bounce_gym.envs.vector_env",
    "bounce_gym.envs.multi_bounce_env",
    "bounce_gym.envs.tasks",
    "bounce_gym.envs.drifters",
    "bounce_gym.envs.patrol",
    "bounce_gym.envs.render",
    "bounce_gym.worlds",
    "bounce_gym.dynamics",
    "bounce_gym.cells",
    "bounce_gym.markov",
    "bounce_gym.flows",
    "bounce_gym.jax",
    "bounce_gym.extras",
    "baselines",
    "baselines.navigation",
    "baselines.coverage",
    "baselines.localization",
    "baselines.multirobot",
    "baselines.patrolling",
    "baselines.drifters",
    "baselines.visibility",
    "baselines.rl",
    "bounce_gym_experiments",
)
#: the packages of `REFERENCE` that export nothing themselves: their pages show their modules
WITH_SUBMODULES = ("baselines.rl", "bounce_gym_experiments")


def _on_path() -> None:
    """Make the checkout's package and the page generators beside this file importable (at
    build time, not at module import, so that the checkout's own package is documented)."""
    for folder in (ROOT, Path(__file__).parent):  # the checkout's package, then site_pages
        if str(folder) not in sys.path:
            sys.path.insert(0, str(folder))


def _env_pages() -> tuple[dict[str, str], dict[str, bytes]]:
    """Page path -> Markdown of every registered id, and picture path -> GIF."""
    _on_path()
    from site_pages import env_pages

    return env_pages()


def _config_pages() -> dict[str, str]:
    """The configuration reference, generated from the configuration models
    (`config_pages`)."""
    _on_path()
    from config_pages import config_pages

    return config_pages()


def _reference_pages() -> dict[str, str]:
    """Page path -> the mkdocstrings directive of each module of `REFERENCE`."""
    submodules = "\n    options:\n      show_submodules: true"
    return {f"reference/{module}.md":
            f"# `{module}`\n\n::: {module}{submodules if module in WITH_SUBMODULES else ''}\n"
            for module in REFERENCE}


_PAGES: dict[str, str] = {}
#: the generated pictures: path -> image file
_PICTURES: dict[str, bytes] = {}


def on_config(config):
    """Build the generated pages once and list them in the navigation's placeholders:
    ``Environments: envs/`` and ``API reference: reference/``."""
    _PAGES.clear()
    _PICTURES.clear()
    env_pages, pictures = _env_pages()
    _PAGES.update(env_pages)
    _PICTURES.update(pictures)
    _PAGES.update(_config_pages())
    _PAGES.update(_reference_pages())
    _fill(config["nav"])
    return config


def _fill(nav: list) -> None:
    """Replace the placeholders ``envs/`` and ``reference/`` in ``nav`` and its sections."""
    for entry in nav:
        if isinstance(entry, dict):
            (title, target), = entry.items()
            if target in ("envs/", "reference/"):
                entry[title] = [{_title(path): path} for path in _PAGES
                                if path.startswith(target)]
            elif isinstance(target, list):
                _fill(target)


def _title(path: str) -> str:
    """The navigation title of a generated page: its first heading, without backticks."""
    return _PAGES[path].split("\n", 1)[0].lstrip("# ").strip("`")


def on_files(files, config):
    """Add the generated pages and pictures to the site's files."""
    for path, content in {**_PAGES, **_PICTURES}.items():
        files.append(File.generated(config, path, content=content))
    return files
