"""The environment pages of the docs site, generated from the registration and the envs.

`env_pages` builds every registered id with its registered arguments and writes, per id: how to
make it, what the id is (its description, `bounce_gym.envs.registration.ABOUT`), the
registration (entry point, arguments, horizon), the spaces the env reports — a Box's bounds per
index, runs of equal bounds joined — the table of the keyword arguments the env
class takes, generated from their declaration (`bounce_gym.envs.arguments.arguments_table`), and
the sections of the env class's docstring (or of its module's, where the class points there).
Plus an overview page.
"""

from __future__ import annotations

import inspect
import re
import sys
import warnings

import gymnasium as gym
import numpy as np
import pettingzoo

import bounce_gym  # noqa: F401 - registers the ids
from bounce_gym.envs import registration
from bounce_gym.envs.arguments import TakesArguments, arguments_table

#: where a docstring's sections start: its Markdown level-2 headings
SECTION = re.compile(r"^## (.+)$", re.M)


def env_pages() -> dict[str, str]:
    """Page path (``envs/<name>.md``) -> Markdown, the overview first."""
    rows, pages = [], {}
    pz_ids = (*registration.PETTINGZOO_ENVS, *registration.DRIFTER_PETTINGZOO_ENVS,
              *registration.PATROL_PETTINGZOO_ENVS)
    kinds = ((registration.GYMNASIUM_IDS, gym.make, _gymnasium_page),
             (pz_ids, lambda env_id: pettingzoo.make("parallel", env_id), _pettingzoo_page))
    for ids, make, page_of in kinds:
        for env_id in ids:
            env = make(env_id)
            try:
                page, row = page_of(env_id, env)
            finally:
                env.close()
            pages[_path(env_id)] = page
            rows.append(row)
    return {"envs/index.md": _overview(rows), **pages}


def _path(env_id: str) -> str:
    return f"envs/{env_id.split('/')[-1]}.md"


def _overview(rows: list[tuple[str, ...]]) -> str:
    lines = [
        "# Environments",
        "",
        "Every id that `import bounce_gym` registers (`bounce_gym.envs.registration`), built "
        "with its registered arguments when this site was built. Each page gives what the id "
        "is, its registration, the spaces the env reports and its class's documentation.",
        "",
        "| id | API | class | horizon | observation space | action space |",
        "|---|---|---|---|---|---|",
    ]
    for env_id, api, cls, horizon, obs, act in rows:
        page = _path(env_id).removeprefix("envs/")
        lines.append(f"| [`{env_id}`]({page}) | {api} | `{cls}` | {horizon} | {obs} | {act} |")
    return "\n".join(lines) + "\n"


def _gymnasium_page(env_id: str, env: gym.Env) -> tuple[str, tuple[str, ...]]:
    spec = env.spec
    cls = type(env.unwrapped)
    vector = spec.vector_entry_point or "none (`gym.make_vec` wraps copies of the env)"
    horizon = str(spec.max_episode_steps)
    if env_id in registration.MAP_HORIZON:
        horizon += (" on the registered map; derived from the map (three times its longest "
                    "optimal plan), so another `world` gets its own (`MapHorizon`)")
    lines = [
        f"# `{env_id}`",
        "",
        f"A Gymnasium environment: `{cls.__name__}` (`{cls.__module__}`).",
        "",
        "```python",
        "import gymnasium as gym",
        "import bounce_gym  # registers the ids",
        "",
        f'env = gym.make("{env_id}")',
        "```",
        "",
        *_about(env_id),
        "## Registration",
        "",
        "| | |",
        "|---|---|",
        f"| entry point | `{spec.entry_point}` |",
        f"| registered arguments | {_kwargs(spec.kwargs)} |",
        f"| horizon (`max_episode_steps`) | {horizon} |",
        f"| vector entry point | {_code(vector) if spec.vector_entry_point else vector} |",
        "",
        "## Observation space",
        "",
        *_space(env.observation_space),
        "## Action space",
        "",
        *_space(env.action_space),
        *_arguments(cls),
        *_docstring_sections(cls),
    ]
    row = (env_id, "Gymnasium", cls.__name__, str(spec.max_episode_steps),
           _code(_short(env.observation_space)), _code(_short(env.action_space)))
    return "\n".join(lines) + "\n", row


def _pettingzoo_page(env_id: str, env) -> tuple[str, tuple[str, ...]]:
    spec = pettingzoo.parallel_registry[env_id]
    aec_spec = pettingzoo.aec_registry[env_id]
    cls = type(env.unwrapped)
    lines = [
        f"# `{env_id}`",
        "",
        f"A PettingZoo environment: `{cls.__name__}` (`{cls.__module__}`), parallel and AEC.",
        "",
        "```python",
        "import pettingzoo",
        "import bounce_gym  # registers the ids",
        "",
        f'env = pettingzoo.make("parallel", "{env_id}")  # or "aec"',
        "```",
        "",
        *_about(env_id),
        "## Registration",
        "",
        "| | |",
        "|---|---|",
        f"| parallel entry point | `{spec.entry_point}` |",
        f"| AEC entry point | `{aec_spec.entry_point}` |",
        f"| registered arguments | {_kwargs(spec.kwargs)} |",
        f"| horizon (`max_cycles`) | {spec.max_cycles} |",
        f"| agents | {', '.join(_code(agent) for agent in env.possible_agents)} |",
        "",
    ]
    for title, space_of in (("Observation spaces", env.observation_space),
                            ("Action spaces", env.action_space)):
        lines += [f"## {title}", ""]
        for agents, space in _groups(env.possible_agents, space_of):
            lines += [f"### {', '.join(_code(agent) for agent in agents)}", "", *_space(space)]
    lines += [*_arguments(cls), *_docstring_sections(cls)]
    row = (env_id, "PettingZoo", cls.__name__, str(spec.max_cycles),
           _per_agent(env.possible_agents, env.observation_space),
           _per_agent(env.possible_agents, env.action_space))
    return "\n".join(lines) + "\n", row


def _about(env_id: str) -> list[str]:
    """The "About this id" section: the id's description, stored with its registration
    (`bounce_gym.envs.registration.ABOUT`)."""
    return ["## About this id", "", registration.ABOUT[env_id], ""]


def _groups(agents, space_of) -> list[tuple[list[str], gym.Space]]:
    """The agents grouped by equal spaces, in agent order."""
    groups: list[tuple[list[str], gym.Space]] = []
    for agent in agents:
        space = space_of(agent)
        for members, known in groups:
            if known == space:
                members.append(agent)
                break
        else:
            groups.append(([agent], space))
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


def _space(space: gym.Space, heading: str = "###") -> list[str]:
    """Markdown lines describing a space; a Box with a table of its bounds per index."""
    if isinstance(space, gym.spaces.Dict):
        lines = [f"`Dict` of {len(space)} spaces.", ""]
        for key, sub in space.items():
            lines += [f"{heading} `{key}`", "", *_space(sub, heading + "#")]
        return lines
    if not isinstance(space, gym.spaces.Box):
        return [_code(repr(space)), ""]
    lines = [f"`Box` of shape {space.shape}, dtype {space.dtype}.", ""]
    if len(space.shape) != 1:
        return lines
    lines += ["| index | low | high |", "|---|---|---|"]
    low, high = space.low, space.high
    start = 0
    for index in range(1, len(low) + 1):
        if index == len(low) or (low[index], high[index]) != (low[start], high[start]):
            span = str(start) if index - 1 == start else f"{start}–{index - 1}"
            lines.append(f"| {span} | {_number(low[start])} | {_number(high[start])} |")
            start = index
    return [*lines, ""]


def _number(value: np.floating) -> str:
    return f"{float(value):g}"


def _code(text: str) -> str:
    return f"`{text}`"


def _kwargs(kwargs: dict) -> str:
    if not kwargs:
        return "none (the class's defaults)"
    return ", ".join(f"`{key}={value!r}`" for key, value in kwargs.items())


def _arguments(cls: type) -> list[str]:
    """The "Arguments" section: the class's own parameters, then the table of the declared
    keyword arguments it takes (name, type, default, description)."""
    if not issubclass(cls, TakesArguments):
        return []
    model = cls.options_model
    own = [str(parameter) for parameter in inspect.signature(cls).parameters.values()
           if parameter.kind is not inspect.Parameter.KEYWORD_ONLY]
    return ["## Arguments", "",
            f"`{cls.__name__}({', '.join(own)}, **arguments)`: the keyword arguments below, "
            f"declared in `{model.__module__}.{model.__name__}` (the defaults are this "
            "class's; the registered arguments above replace some of them).", "",
            *arguments_table(cls), ""]


def _docstring_sections(cls: type) -> list[str]:
    """The documentation of the env class: its docstring's sections, or those of its module's
    docstring where the class's has none (the PettingZoo classes point to their module). The
    sections' headings move one level down, under one heading naming the source."""
    doc, source = inspect.getdoc(cls) or "", f"`{cls.__name__}`"
    if not SECTION.search(doc):
        doc, source = inspect.getdoc(sys.modules[cls.__module__]) or "", f"`{cls.__module__}`"
    if not SECTION.search(doc):
        warnings.warn(f"{cls.__name__} has no documented sections", stacklevel=2)
        return []
    demoted = SECTION.sub(r"### \1", doc)
    return ["", f"## Documentation (from the docstring of {source})", "", demoted, ""]
