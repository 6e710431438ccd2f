"""The environment pages of the docs site (docs/site_scripts/site_pages.py): for every registered
id, the sections of Gymnasium's env pages in order, action and observation tables that match the
env as built, the registered arguments beside the defaults, and a picture the env rendered."""

import io
import os
import re
import sys
from pathlib import Path

import pytest

pytest.importorskip("PIL", reason="the env pages' pictures need pillow")
os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # the pictures are drawn with no display

import gymnasium as gym  # noqa: E402 - after the skip
import numpy as np  # noqa: E402
import pettingzoo  # noqa: E402
from PIL import Image, ImageSequence  # noqa: E402

from bounce_gym.envs import registration  # noqa: E402

sys.path.insert(0, str(Path(__file__).parents[1] / "docs" / "site_scripts"))
import site_pages  # noqa: E402

GYM_IDS = registration.GYMNASIUM_IDS
IDS = (*GYM_IDS, *site_pages.PZ_IDS)
#: a table row: its first cell (an index, or a span ``first–last``) and the others
ROW = re.compile(r"^\| (\d+)(?:–(\d+))? \| (.+) \|$")


@pytest.fixture(scope="module")
def site() -> tuple[dict[str, str], dict[str, bytes]]:
    """The generated pages and pictures."""
    return site_pages.env_pages()


def _page(site, env_id: str) -> str:
    return site[0][f"envs/{env_id.split('/')[-1]}.md"]


def _section(page: str, title: str) -> str:
    return page.split(f"\n## {title}\n", 1)[1].split("\n## ", 1)[0]


def _make(env_id: str):
    if env_id in GYM_IDS:
        return gym.make(env_id)
    return pettingzoo.make("parallel", env_id)


def _agents(env) -> list[str | None]:
    return [None] if isinstance(env, gym.Env) else list(env.possible_agents)


def _space_of(env, which: str, agent: str | None) -> gym.Space:
    space = getattr(env, which)
    return space if agent is None else space(agent)


def _tables(section: str, agent: str | None) -> str:
    """The part of a space section about ``agent`` (the whole section for a lone agent)."""
    if agent is None:
        return section
    groups = re.split(r"^### (.+)$", section, flags=re.M)
    return next(text for title, text in zip(groups[1::2], groups[2::2], strict=True)
                if f"`{agent}`" in title.split(", "))


def _rows(table: str) -> list[tuple[int, int, str]]:
    """(first, last, other cells) of every row of a table of actions or indices."""
    return [(int(m[1]), int(m[2] or m[1]), m[3]) for m in map(ROW.match, table.splitlines()) if m]


def _expand(table: str) -> list[str]:
    """One entry per action or index: the row's other cells; the rows cover 0, 1, … once."""
    out = []
    for first, last, cells in _rows(table):
        assert first == len(out), table
        out += [cells] * (last - first + 1)
    return out


def test_every_id_has_a_page_with_the_eight_sections_in_order(site):
    assert len(IDS) == len(set(IDS)) >= 11
    for env_id in IDS:
        headings = re.findall(r"^## (.+)$", _page(site, env_id), re.M)
        assert tuple(headings) == site_pages.SECTIONS, env_id


@pytest.mark.parametrize("env_id", IDS)
def test_the_action_table_lists_the_env_actions(site, env_id):
    section = _section(_page(site, env_id), "Action Space")
    env = _make(env_id)
    unwrapped = env.unwrapped
    for agent in _agents(env):
        space = _space_of(env, "action_space", agent)
        actions = _expand(_tables(section, agent))
        assert len(actions) == space.n, (env_id, agent)
        assert actions == list(unwrapped.action_labels(agent)), (env_id, agent)
        if hasattr(unwrapped.options, "angles"):  # the bouncing robots: their angles, in order
            robot = 0 if agent is None else unwrapped.agent_index[agent]
            shown = [float(re.search(r"bounce angle (\S+)°", a)[1]) for a in actions
                     if "bounce angle" in a]
            np.testing.assert_allclose(shown, np.degrees(unwrapped.options.angles[robot]))
    env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_the_observation_tables_have_the_env_shapes_and_bounds(site, env_id):
    section = _section(_page(site, env_id), "Observation Space")
    env = _make(env_id)
    for agent in _agents(env):
        space = _space_of(env, "observation_space", agent)
        text = _tables(section, agent)
        boxes = dict(space.items()) if isinstance(space, gym.spaces.Dict) else {None: space}
        for key, box in boxes.items():
            table = text if key is None else text.split(f"`{key}`\n", 1)[1].split("\n#", 1)[0]
            assert f"`Box` of shape {box.shape}, dtype {box.dtype}." in table, (env_id, key)
            rows = _expand(table)
            assert len(rows) == box.shape[0], (env_id, agent, key)
            bounds = [tuple(float(v) for v in row.split(" | ")[:2]) for row in rows]
            expected = zip(box.low.tolist(), box.high.tolist(), strict=True)
            assert bounds == list(expected), (env_id, key)
    env.close()


def test_the_goal_navigation_observation_is_the_clock(site):
    page = _page(site, "bounce_gym/BounceNavigation-v1")
    observation = _section(page, "Observation Space").split("### `observation`", 1)[1]
    assert "`Box` of shape (1,)" in observation
    assert _rows(observation.split("\n#", 1)[0])[0][2].endswith("| clock: ticks since the last "
                                                                "bump / max_clock")
    about = registration.ABOUT["bounce_gym/BounceNavigation-v1"]
    assert "`observation` (the clock" in about and "one-hot cell pose)" not in about


@pytest.mark.parametrize("env_id", IDS)
def test_the_arguments_table_shows_the_registered_values_beside_the_defaults(site, env_id):
    if env_id in GYM_IDS:
        registered = dict(gym.spec(env_id).kwargs)
    else:
        spec = pettingzoo.parallel_registry[env_id]
        registered = {**spec.kwargs, "max_cycles": spec.max_cycles}
    section = _section(_page(site, env_id), "Arguments")
    assert "| argument | type | registered value | default | description |" in section
    cells = {m[1]: m[2] for m in re.finditer(r"^\| `(\w+)` \| `.*?` \| (`.*?`|—) \| `", section,
                                             re.M)}
    assert len(cells) >= 5, env_id
    # PettingZoo's horizon is a parameter of the class itself where it is not declared
    assert set(registered) - set(cells) <= {"max_cycles"}, env_id
    for name in registered.keys() & cells.keys():
        assert cells[name] == f"`{registered[name]!r}`", (env_id, name)
    assert all(value == "—" for name, value in cells.items() if name not in registered)


@pytest.mark.parametrize("env_id", IDS)
def test_the_picture_is_an_animation_the_env_rendered(site, env_id):
    page = _page(site, env_id)
    name = env_id.split("/")[-1]
    assert f"![{env_id}]({name}.gif)" in page
    data = site[1][f"envs/{name}.gif"]
    assert len(data) <= 150_000
    image = Image.open(io.BytesIO(data))
    assert image.format == "GIF" and sum(1 for _ in ImageSequence.Iterator(image)) >= 2
    env = (gym.make(env_id, render_mode="rgb_array") if env_id in GYM_IDS
           else pettingzoo.make("parallel", env_id, render_mode="rgb_array"))
    env.reset(seed=0)
    height, width, _ = env.render().shape
    env.close()
    assert image.size == (width, height)


def test_the_version_history_lists_the_family_from_the_changelog(site):
    v0 = _section(_page(site, "bounce_gym/BounceNavigation-v0"), "Version History")
    v1 = _section(_page(site, "bounce_gym/BounceNavigation-v1"), "Version History")
    assert v0.index("**v0** (this id)") < v0.index("**v1** ([`bounce_gym/BounceNavigation-v1`]")
    assert "**v0** ([`bounce_gym/BounceNavigation-v0`](BounceNavigation-v0.md))" in v1
    assert "Kept unchanged when v1 was added" in v0 and "Kept unchanged when v1" in v1
    assert _section(_page(site, "bounce_gym/Patrol-v0"), "Version History").count("* **v") == 1


def test_a_docstring_without_the_sections_fails_the_build():
    class Undocumented:
        """Summary.

        ## Description

        Something.

        ## Rewards

        None.
        """

    with pytest.raises(ValueError, match="has the sections"):
        site_pages._documentation(Undocumented)
