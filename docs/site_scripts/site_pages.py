"""The environment pages of the docs site, generated from the registration and the envs.

`env_pages` builds every registered id with its registered arguments and ``render_mode=
"rgb_array"`` and writes its page with the sections of Gymnasium's env pages, in their order
(`SECTIONS`):

* Description — a short animation of the env (`picture`, rendered by the env), the env class's
  docstring ("Description", after its summary), what the id is (its description,
  `bounce_gym.envs.registration.ABOUT`) and its registration (entry point, horizon);
* Action Space and Observation Space — the spaces the env reports, a table per space with a row
  per action or index (runs of equal rows joined): its bounds and what it is, as the env says
  (``action_labels``, ``observation_labels``), then the docstring's section; per agent for the
  PettingZoo ids;
* Rewards, Starting State, Episode End — the docstring's sections;
* Arguments — the table of the keyword arguments the class takes, each with the id's registered
  value beside the class's default (`bounce_gym.envs.arguments.arguments_table`), then the
  docstring's section;
* Version History — every registered version of the id's family (``-v0``, ``-v1``, …), each
  with its row of the id history in CHANGELOG.md.

The docstring is the env class's, or its module's where the class points there; it must have
exactly the sections `DOCUMENTED`, in order, or the build fails. Plus an overview page.
"""

from __future__ import annotations

import inspect
import io
import re
import sys
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np
import pettingzoo
from PIL import Image

import bounce_gym  # noqa: F401 - registers the ids
from bounce_gym.envs import registration
from bounce_gym.envs.arguments import arguments_table

#: the sections of every env page, in order: those of Gymnasium's env pages
SECTIONS = ("Description", "Action Space", "Observation Space", "Rewards", "Starting State",
            "Episode End", "Arguments", "Version History")
#: the sections an env's docstring writes, in order (the version history is CHANGELOG.md's)
DOCUMENTED = SECTIONS[:-1]
#: where a docstring's sections start: its Markdown level-2 headings
SECTION = re.compile(r"^## (.+)$", re.M)
#: the table of CHANGELOG.md with a row per registered id: its history
CHANGELOG = Path(__file__).resolve().parents[2] / "CHANGELOG.md"
ID_HISTORY = re.compile(r"^\| `(bounce_gym/[\w-]+)` \| (.+) \|$", re.M)
#: an id's version suffix; what is left is the id's family
VERSION = re.compile(r"-v(\d+)$")
#: the animation of each page: the steps after the reset it shows, ms per frame, the seed
PICTURE_STEPS, FRAME_MS, SEED = 7, 400, 0

PZ_IDS = (*registration.PETTINGZOO_ENVS, *registration.DRIFTER_PETTINGZOO_ENVS,
          *registration.PATROL_PETTINGZOO_ENVS)


def env_pages() -> tuple[dict[str, str], dict[str, bytes]]:
    """Page path (``envs/<name>.md``) -> Markdown, the overview first, and picture path
    (``envs/<name>.gif``) -> GIF."""
    histories = dict(ID_HISTORY.findall(CHANGELOG.read_text(encoding="utf-8")))
    all_ids = (*registration.GYMNASIUM_IDS, *PZ_IDS)
    rows, pages, pictures = [], {}, {}
    kinds = ((registration.GYMNASIUM_IDS, _make_gymnasium, _gymnasium_page),
             (PZ_IDS, _make_pettingzoo, _pettingzoo_page))
    for ids, make, page_of in kinds:
        for env_id in ids:
            env = make(env_id)
            try:
                page, row = page_of(env_id, env)
                pictures[_picture_path(env_id)] = picture(env)
            finally:
                env.close()
            history = _version_history(env_id, all_ids, histories)
            pages[_path(env_id)] = page + "\n".join(history) + "\n"
            rows.append(row)
    return {"envs/index.md": _overview(rows), **pages}, pictures


def _make_gymnasium(env_id: str) -> gym.Env:
    return gym.make(env_id, render_mode="rgb_array")


def _make_pettingzoo(env_id: str):
    return pettingzoo.make("parallel", env_id, render_mode="rgb_array")


def _path(env_id: str) -> str:
    return f"envs/{_name(env_id)}.md"


def _picture_path(env_id: str) -> str:
    return f"envs/{_name(env_id)}.gif"


def _name(env_id: str) -> str:
    return env_id.split("/")[-1]


def _overview(rows: list[tuple[str, ...]]) -> str:
    lines = [
        "# Environments",
        "",
        "Every id that `import bounce_gym` registers (`bounce_gym.envs.registration`), built "
        "with its registered arguments when this site was built. Each id's page has the "
        "sections of Gymnasium's environment pages — " + ", ".join(SECTIONS) + " — with a "
        "short animation rendered by the env, a table of what each action and each index of "
        "the observation is, and its arguments with the id's registered values.",
        "",
        "| id | what it is | API | class | horizon | observation space | action space |",
        "|---|---|---|---|---|---|---|",
    ]
    for env_id, api, cls, horizon, obs, act in rows:
        page = _path(env_id).removeprefix("envs/")
        lines.append(f"| [`{env_id}`]({page}) | {registration.SUMMARY[env_id]} | {api} | "
                     f"`{cls}` | {horizon} | {obs} | {act} |")
    return "\n".join(lines) + "\n"


def picture(env) -> bytes:
    """A GIF of ``env`` (made with ``render_mode="rgb_array"``): its frame after
    ``reset(seed=SEED)`` and after each of `PICTURE_STEPS` steps of seeded random actions (fewer
    where the episode ends first)."""
    frames = [_reset(env)]
    for _ in range(PICTURE_STEPS):
        if not _step(env):
            break
        frames.append(env.render())
    images = [Image.fromarray(frame) for frame in frames]
    out = io.BytesIO()
    images[0].save(out, format="GIF", save_all=True, append_images=images[1:],
                   duration=FRAME_MS, loop=0, optimize=True)
    return out.getvalue()


def _reset(env) -> np.ndarray:
    env.reset(seed=SEED)
    if isinstance(env, gym.Env):
        env.action_space.seed(SEED)
    else:
        for k, agent in enumerate(env.possible_agents):
            env.action_space(agent).seed(SEED + k)
    return env.render()


def _step(env) -> bool:
    """One step of random actions; whether the episode goes on."""
    if isinstance(env, gym.Env):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        return not (terminated or truncated)
    env.step({agent: env.action_space(agent).sample() for agent in env.agents})
    return bool(env.agents)


def _gymnasium_page(env_id: str, env: gym.Env) -> tuple[str, tuple[str, ...]]:
    # the registry's spec: the env's own holds the render mode it was made with
    spec, steps, unwrapped = gym.spec(env_id), env.spec.max_episode_steps, env.unwrapped
    cls = type(unwrapped)
    vector = spec.vector_entry_point or "none (`gym.make_vec` wraps copies of the env)"
    horizon = str(steps)
    if env_id in registration.MAP_HORIZON:
        horizon += (" on the registered map; derived from the map (three times its longest "
                    "optimal plan), so another `world` gets its own (`MapHorizon`)")
    intro = [
        f"A Gymnasium environment: `{cls.__name__}` (`{cls.__module__}`).",
        "",
        "```python",
        "import gymnasium as gym",
        "import bounce_gym  # registers the ids",
        "",
        f'env = gym.make("{env_id}")',
        "```",
    ]
    facts = [
        f"| entry point | `{spec.entry_point}` |",
        f"| registered arguments | {_kwargs(spec.kwargs)} |",
        f"| horizon (`max_episode_steps`) | {horizon} |",
        f"| vector entry point | {_code(vector) if spec.vector_entry_point else vector} |",
    ]
    generated = {
        "Action Space": _space(env.action_space, unwrapped.action_labels()),
        "Observation Space": _space(env.observation_space, unwrapped.observation_labels()),
    }
    page = _page(env_id, cls, intro, facts, generated, spec.kwargs)
    row = (env_id, "Gymnasium", cls.__name__, str(steps),
           _code(_short(env.observation_space)), _code(_short(env.action_space)))
    return page, row


def _pettingzoo_page(env_id: str, env) -> tuple[str, tuple[str, ...]]:
    spec = pettingzoo.parallel_registry[env_id]
    aec_spec = pettingzoo.aec_registry[env_id]
    unwrapped = env.unwrapped
    cls = type(unwrapped)
    intro = [
        f"A PettingZoo environment: `{cls.__name__}` (`{cls.__module__}`), parallel and AEC.",
        "",
        "```python",
        "import pettingzoo",
        "import bounce_gym  # registers the ids",
        "",
        f'env = pettingzoo.make("parallel", "{env_id}")  # or "aec"',
        "```",
    ]
    facts = [
        f"| parallel entry point | `{spec.entry_point}` |",
        f"| AEC entry point | `{aec_spec.entry_point}` |",
        f"| registered arguments | {_kwargs(spec.kwargs)} |",
        f"| horizon (`max_cycles`) | {spec.max_cycles} |",
        f"| agents | {', '.join(_code(agent) for agent in env.possible_agents)} |",
    ]
    generated = {
        "Action Space": _per_agent_spaces(env.possible_agents, env.action_space,
                                          unwrapped.action_labels),
        "Observation Space": _per_agent_spaces(env.possible_agents, env.observation_space,
                                               unwrapped.observation_labels),
    }
    page = _page(env_id, cls, intro, facts, generated,
                 {**spec.kwargs, "max_cycles": spec.max_cycles})
    row = (env_id, "PettingZoo", cls.__name__, str(spec.max_cycles),
           _per_agent(env.possible_agents, env.observation_space),
           _per_agent(env.possible_agents, env.action_space))
    return page, row


def _page(env_id: str, cls: type, intro: list[str], facts: list[str],
          generated: dict[str, list[str]], registered: dict) -> str:
    """The page without its version history: the title, the picture and ``intro``, then the
    documented sections, each with what is generated for it first."""
    summary, documented, source = _documentation(cls)
    before = {**generated, "Description": [summary, ""], "Arguments": _arguments(cls, registered)}
    after = {"Description": ["### About this id", "", registration.ABOUT[env_id], "",
                             "### Registration", "", "| | |", "|---|---|", *facts, ""]}
    lines = [f"# `{env_id}`", "", f"![{env_id}]({_name(env_id)}.gif)", "", *intro, "",
             f"The sections below follow the docstring of {source} and the env as built.", ""]
    for title in DOCUMENTED:
        lines += [f"## {title}", "", *before.get(title, []), documented[title], "",
                  *after.get(title, [])]
    return "\n".join(lines) + "\n"


def _documentation(cls: type) -> tuple[str, dict[str, str], str]:
    """The env's docstring: its text before the first section, its sections (title -> text)
    and its source. The class's docstring, or its module's where the class's has no sections
    (the PettingZoo classes point to their module)."""
    doc, source = inspect.getdoc(cls) or "", f"`{cls.__name__}`"
    if not SECTION.search(doc):
        doc, source = inspect.getdoc(sys.modules[cls.__module__]) or "", f"`{cls.__module__}`"
    summary, *parts = SECTION.split(doc)
    sections = {title: text.strip() for title, text in zip(parts[::2], parts[1::2], strict=True)}
    if tuple(sections) != DOCUMENTED:
        raise ValueError(f"the docstring of {source} has the sections {list(sections)}; an env "
                         f"page needs {list(DOCUMENTED)}, in this order")
    return summary.strip(), sections, source


def _version_history(env_id: str, all_ids: tuple[str, ...],
                     histories: dict[str, str]) -> list[str]:
    """The "Version History" section: every registered id of ``env_id``'s family, oldest
    first, with its history (CHANGELOG.md)."""
    family = VERSION.sub("", env_id)
    versions = sorted((int(VERSION.search(other)[1]), other) for other in all_ids
                      if VERSION.sub("", other) == family)
    lines = ["## Version History", ""]
    for number, other in versions:
        if other not in histories:
            raise ValueError(f"CHANGELOG.md has no history of {other}")
        name = "this id" if other == env_id else f"[`{other}`]({_name(other)}.md)"
        lines.append(f"* **v{number}** ({name}): {histories[other]}")
    return [*lines, ""]


def _per_agent_spaces(agents, space_of, labels_of: Callable) -> list[str]:
    """A table per group of agents with equal spaces and labels, in agent order."""
    lines = []
    for members, (space, labels) in _groups(agents, lambda a: (space_of(a), labels_of(a))):
        lines += [f"### {', '.join(_code(agent) for agent in members)}", "",
                  *_space(space, labels, "####")]
    return lines


def _groups(agents, key_of) -> list[tuple[list[str], object]]:
    """The agents grouped by equal keys, in agent order."""
    groups: list[tuple[list[str], object]] = []
    for agent in agents:
        key = key_of(agent)
        for members, known in groups:
            if known == key:
                members.append(agent)
                break
        else:
            groups.append(([agent], key))
    return groups


def _per_agent(agents, space_of) -> str:
    return "; ".join(f"{', '.join(members)}: {_code(_short(space))}"
                     for members, space in _groups(agents, space_of))


def _short(space: gym.Space) -> str:
    """A one-line name of a space (a Box by its shape and dtype, bounds on its page)."""
    if isinstance(space, gym.spaces.Box):
        return f"Box{space.shape} {space.dtype}"
    if isinstance(space, gym.spaces.Dict):
        return "Dict(" + ", ".join(f"{key}: {_short(sub)}" for key, sub in space.items()) + ")"
    return repr(space)


def _space(space: gym.Space, labels, heading: str = "###") -> list[str]:
    """Markdown lines describing a space and what each of its actions or indices is
    (``labels``: one per action of a ``Discrete``, per index of a 1-d ``Box``, or per key of a
    ``Dict`` those of its space)."""
    if isinstance(space, gym.spaces.Dict):
        lines = [f"`Dict` of {len(space)} spaces.", ""]
        for key, sub in space.items():
            lines += [f"{heading} `{key}`", "", *_space(sub, labels[key], heading + "#")]
        return lines
    size = (space.n,) if isinstance(space, gym.spaces.Discrete) else space.shape
    if (len(labels),) != size:
        raise ValueError(f"{space!r}: the env labels {len(labels)} actions or indices")
    if isinstance(space, gym.spaces.Discrete):
        rows = [(str(space.start + k), label) for k, label in enumerate(labels)]
        return [f"`{space!r}`.", "", "| action | meaning |", "|---|---|", *_rows(rows), ""]
    bounds = zip(space.low, space.high, labels, strict=True)
    rows = [(str(index), _number(low), _number(high), label)
            for index, (low, high, label) in enumerate(bounds)]
    return [f"`Box` of shape {space.shape}, dtype {space.dtype}.", "",
            "| index | low | high | meaning |", "|---|---|---|---|", *_rows(rows), ""]


def _rows(rows: list[tuple[str, ...]]) -> list[str]:
    """Table rows; runs of rows equal but for their first cell (an index) become one row
    ``first–last``."""
    lines, start = [], 0
    for end in range(1, len(rows) + 1):
        if end == len(rows) or rows[end][1:] != rows[start][1:]:
            span = rows[start][0] if end - 1 == start else f"{rows[start][0]}–{rows[end - 1][0]}"
            lines.append("| " + " | ".join((span, *rows[start][1:])) + " |")
            start = end
    return lines


def _number(value: np.floating) -> str:
    return f"{float(value):g}"


def _code(text: str) -> str:
    return f"`{text}`"


def _kwargs(kwargs: dict) -> str:
    if not kwargs:
        return "none (the class's defaults)"
    return ", ".join(f"`{key}={value!r}`" for key, value in kwargs.items())


def _arguments(cls: type, registered: dict) -> list[str]:
    """The generated part of the "Arguments" section: the class's own parameters, then the
    table of the declared keyword arguments it takes, with the id's registered values."""
    model = cls.options_model
    own = [str(parameter) for parameter in inspect.signature(cls).parameters.values()
           if parameter.kind is not inspect.Parameter.KEYWORD_ONLY]
    return [f"`{cls.__name__}({', '.join(own)}, **arguments)`: the keyword arguments below, "
            f"declared in `{model.__module__}.{model.__name__}`; \"registered value\" is what "
            "this id passes (— : it keeps the class's default).", "",
            *arguments_table(cls, registered), ""]
