"""The core install and its extras (`bounce_gym.extras`): without any extra every registered
Gymnasium and PettingZoo env is made, reset and stepped; a feature whose extra is missing is one
line naming the extra and its ``pip install``; the docs list exactly the extras pyproject.toml
declares. Missing extras are simulated in a subprocess whose start-up marks their modules
missing (tests/refuse_imports); the slow test installs the core into a fresh virtual
environment."""

import importlib.metadata
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
import venv
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from bounce_gym.errors import BounceGymError, MissingExtraError
from bounce_gym.extras import MODULE_EXTRAS, require

tomllib = pytest.importorskip("tomllib", reason="reading pyproject.toml needs Python >= 3.11")

ROOT = Path(__file__).parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
EXTRAS = PROJECT["optional-dependencies"]
#: what the core must do without: every module an extra installs, and pandas (xarray's)
BLOCKED = sorted({*MODULE_EXTRAS, "pandas", "jaxlib"})

#: the folder whose ``sitecustomize`` refuses the modules of $REFUSED_MODULES in a subprocess
REFUSER = ROOT / "tests" / "refuse_imports"

#: makes, resets and steps every id of the package's registries, then prints what it made and
#: which of the modules of argv[1] got imported (JSON)
EVERY_ENV = textwrap.dedent("""
    import json, sys
    import gymnasium as gym
    import pettingzoo
    import bounce_gym

    def ours(registry):
        return sorted(i for i in registry if i.startswith("bounce_gym/"))

    made = []
    for env_id in ours(gym.registry):
        env = gym.make(env_id)
        env.reset(seed=0)
        env.step(env.action_space.sample())
        env.close()
        if gym.registry[env_id].vector_entry_point is not None:
            envs = gym.make_vec(env_id, num_envs=2)
            envs.reset(seed=0)
            envs.step(envs.action_space.sample())
            envs.close()
        made.append(env_id)
    for env_id in ours(pettingzoo.parallel_registry):
        env = pettingzoo.make("parallel", env_id)
        env.reset(seed=0)
        env.step({agent: env.action_space(agent).sample() for agent in env.agents})
        env.close()
        made.append("parallel " + env_id)
    for env_id in ours(pettingzoo.aec_registry):
        env = pettingzoo.make("aec", env_id)
        env.reset(seed=0)
        env.step(env.action_space(env.agent_selection).sample())
        env.close()
        made.append("aec " + env_id)
    wanted = set(sys.argv[1].split(","))
    print(json.dumps({"made": made,
                      "imported": sorted({m.split(".")[0] for m in sys.modules} & wanted)}))
""")


def _run(code: str, *args: str, cwd: Path = ROOT, blocked=BLOCKED, timeout: int = 300):
    """Run ``code`` in a fresh interpreter of this environment with ``blocked`` refused."""
    env = {"PYTHONPATH": f"{REFUSER}{os.pathsep}{ROOT}", "REFUSED_MODULES": ",".join(blocked),
           "SDL_VIDEODRIVER": "dummy", "PATH": "/usr/bin:/bin", "HOME": str(cwd)}
    return subprocess.run([sys.executable, "-c", code, *args],
                          cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout,
                          check=False)


def _registered_ids() -> list[str]:
    import gymnasium as gym
    import pettingzoo

    import bounce_gym  # noqa: F401  (registers the environments)

    return sorted({i for registry in (gym.registry, pettingzoo.parallel_registry,
                                      pettingzoo.aec_registry)
                   for i in registry if i.startswith("bounce_gym/")})


def test_every_env_runs_without_any_extra():
    done = _run(EVERY_ENV, ",".join(BLOCKED))
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.splitlines()[-1])
    assert report["imported"] == []
    made = {entry.split()[-1] for entry in report["made"]}
    assert made == set(_registered_ids()) and len(made) >= 11
    # the PettingZoo ids as both parallel and AEC envs
    assert sum(entry.startswith("aec ") for entry in report["made"]) >= 5


def test_the_core_packages_import_without_any_extra():
    """Every module of bounce_gym and baselines imports with no extra installed (an optional
    library is imported where a feature needs it), but the JAX and RL learners'."""
    code = textwrap.dedent("""
        import importlib, json, pkgutil, sys
        import baselines, bounce_gym
        names = [m.name for package in (bounce_gym, baselines)
                 for m in pkgutil.walk_packages(package.__path__, package.__name__ + ".")
                 if not m.name.startswith(("bounce_gym.jax", "baselines.rl"))]
        for name in names:
            importlib.import_module(name)
        print(json.dumps(names))
    """)
    done = _run(code)
    assert done.returncode == 0, done.stderr[-3000:]
    names = json.loads(done.stdout.splitlines()[-1])
    assert {"bounce_gym.envs.render.renderer", "bounce_gym.flows.netcdf",
            "baselines.drifters"} <= set(names)


def _one_line_naming(text: str, extra: str) -> None:
    lines = text.strip().splitlines()
    assert len(lines) == 1, text
    assert f"'{extra}' extra" in lines[0] and f"pip install 'bounce-gym[{extra}]'" in lines[0]


def test_a_netcdf_flow_without_the_drifters_extra_is_one_line(tmp_path):
    from bounce_gym import flows

    path = flows.save_flow(flows.get_flow("scb_like"), tmp_path / "flow.nc")
    code = textwrap.dedent("""
        import sys
        import gymnasium as gym
        import pettingzoo
        import bounce_gym
        from bounce_gym import flows
        from bounce_gym.errors import MissingExtraError
        try:
            flows.load_flow(sys.argv[1])
        except MissingExtraError as exc:
            print(exc)
        for make in (lambda: gym.make("bounce_gym/Drifter-v0", flow=sys.argv[1]),
                     lambda: pettingzoo.make("parallel", "bounce_gym/MultiDrifter-v0",
                                             flow=sys.argv[1])):
            try:
                make()
            except MissingExtraError as exc:
                print(exc)
    """)
    done = _run(code, str(path))
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.strip().splitlines()
    assert len(lines) == 3
    for line in lines:
        _one_line_naming(line, "drifters")
    assert lines[1].startswith("flow: ")


def test_rendering_without_the_render_extra_is_one_line():
    code = textwrap.dedent("""
        import gymnasium as gym
        import bounce_gym
        from bounce_gym.envs.render.gif import save_gif
        import numpy as np
        env = gym.make("bounce_gym/Bounce-v0", render_mode="rgb_array")
        env.reset(seed=0)
        for draw in (env.render, lambda: save_gif([np.zeros((4, 4, 3), np.uint8)], "x.gif")):
            try:
                draw()
            except gym.error.DependencyNotInstalled as exc:
                print(exc)
    """)
    done = _run(code)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.strip().splitlines()
    assert len(lines) == 2
    for line in lines:
        _one_line_naming(line, "render")


TRAIN_JAX = """name: nav-jax
env: bounce_gym/BounceNavigation-v1
algo: jax_ppo
total_timesteps: 64
seeds: [0]
models: models
"""


@pytest.mark.parametrize("argv, blocked, extra", [
    (["bounce-gym", "evaluate", "configs/eval_default.yaml"], ["matplotlib"], "experiments"),
    (["bounce-gym", "evaluate"], ["tqdm"], "experiments"),
    (["evaluate.py"], ["matplotlib"], "experiments"),
    (["bounce-gym", "evaluate", "configs/eval_default.yaml", "--executor", "ray"], ["ray"],
     "distributed"),
    (["bounce-gym", "curves", "models/nothing"], ["matplotlib"], "experiments"),
    (["bounce-gym", "train", "configs/train_navigation.yaml"], ["matplotlib"], "experiments"),
    (["train.py", "configs/train_navigation.yaml"], ["torch"], "rl"),
    (["bounce-gym", "train", "configs/train_navigation.yaml"], ["stable_baselines3"], "rl"),
    (["bounce-gym", "train", "jax.yaml"], ["jax"], "jax"),
    (["bounce-gym", "tune", "configs/train_navigation.yaml"], ["ray"], "distributed"),
    (["bounce-gym", "tune", "configs/train_navigation.yaml"], ["torch"], "rl"),
])
def test_a_command_without_its_extra_is_one_line_and_status_2(tmp_path, argv, blocked, extra):
    (tmp_path / "configs").symlink_to(ROOT / "configs")
    (tmp_path / "jax.yaml").write_text(TRAIN_JAX, encoding="utf-8")
    if argv[0] == "bounce-gym":
        code = ("import sys\nfrom bounce_gym_experiments.cli import main\n"
                "sys.exit(main(sys.argv[1:]))\n")
    else:
        code = ("import runpy\nimport sys\n"
                f"sys.argv[0] = {str(ROOT / argv[0])!r}\n"
                "runpy.run_path(sys.argv[0], run_name='__main__')\n")
    done = _run(code, *argv[1:], cwd=tmp_path, blocked=blocked)
    assert done.returncode == 2, done.stderr[-3000:]
    assert done.stdout == ""
    _one_line_naming(done.stderr.removeprefix("error: "), extra)
    assert not (tmp_path / "models").exists()  # refused before any work
    if argv == ["bounce-gym", "evaluate"]:  # the example the install guide shows
        guide = (ROOT / "docs" / "getting_started.md").read_text(encoding="utf-8")
        assert f"\n{done.stderr.removeprefix('error: ')}" in guide


def test_require_names_the_extras_of_the_missing_modules(monkeypatch):
    monkeypatch.setitem(sys.modules, "cvxpy", None)
    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(MissingExtraError) as raised:
        require("the feature", "cvxpy", "ray")
    assert str(raised.value) == ("the feature needs the 'patrol-check' and 'distributed' "
                                 "extras: pip install 'bounce-gym[patrol-check,distributed]'")
    assert isinstance(raised.value, (BounceGymError, ImportError))
    with pytest.raises(KeyError):
        require("a bug", "numpy")  # not a module of an extra


def _extras_of(requirements: list[str]) -> set[str]:
    """The distributions these requirements name, through this project's own extras."""
    names = set()
    for line in requirements:
        requirement = Requirement(line)
        if canonicalize_name(requirement.name) == "bounce-gym":
            for extra in requirement.extras:
                names |= _extras_of(EXTRAS[extra])
        else:
            names.add(canonicalize_name(requirement.name))
    return names


def test_each_module_of_an_extra_is_declared_there_and_not_in_the_core():
    core = _extras_of(PROJECT["dependencies"])
    assert "pydantic" in core
    distributions = importlib.metadata.packages_distributions()
    for module, extra in MODULE_EXTRAS.items():
        assert extra in EXTRAS, module
        owners = {canonicalize_name(d) for d in distributions.get(module, [module])}
        assert owners & _extras_of(EXTRAS[extra]), (module, extra)
        assert not owners & core, module
    assert not {"pandas", "matplotlib", "xarray", "netcdf4", "torch", "ray", "jax",
                "pygame", "pillow", "tqdm"} & core


def test_the_docs_name_exactly_the_declared_extras():
    guide = (ROOT / "docs" / "getting_started.md").read_text(encoding="utf-8")
    table = set(re.findall(r"^\| `([\w-]+)` \|", guide, re.M))
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    install = readme.split("## Install", 1)[1].split("\n## ", 1)[0]
    lines = set(re.findall(r'pip install "\.\[([\w-]+)\]"', install))
    assert table == set(EXTRAS) and lines == set(EXTRAS)
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    made = set(re.search(r'-e "\.\[([\w,-]+)\]"', makefile).group(1).split(","))
    assert made == set(EXTRAS) - {"tensorboard"}  # as the docs say


@pytest.mark.slow
def test_the_core_installs_into_a_fresh_venv_without_the_extras(tmp_path):
    """``pip install <checkout>`` (core only, constraints.txt) into a new virtual environment:
    every env runs there, and no module of an extra (nor pandas) is installed."""
    source = tmp_path / "source"
    for name in ("pyproject.toml", "setup.py", "README.md", "LICENSE", "constraints.txt"):
        (source / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / name, source / name)
    for folder in ("bounce_gym", "baselines", "bounce_gym_experiments", "configs"):
        shutil.copytree(ROOT / folder, source / folder,
                        ignore=shutil.ignore_patterns("__pycache__", "agents", "*.zip"))
    venv.EnvBuilder(with_pip=True).create(tmp_path / "venv")
    python = str(tmp_path / "venv" / "bin" / "python")
    done = subprocess.run([python, "-m", "pip", "install", "-q", "-c", "constraints.txt", "."],
                          cwd=source, capture_output=True, text=True, timeout=1800, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    absent = ["pandas", "matplotlib", "xarray", "netCDF4", "torch", "ray", "jax",
              "stable_baselines3", "pygame", "PIL", "tqdm"]
    check = ("import importlib.util, json, sys\n"
             f"print(json.dumps([m for m in {absent!r} if importlib.util.find_spec(m)]))\n")
    done = subprocess.run([python, "-c", check + EVERY_ENV, ",".join(absent)], cwd=tmp_path,
                          env={"SDL_VIDEODRIVER": "dummy", "PATH": "/usr/bin:/bin"},
                          capture_output=True, text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    installed, report = (json.loads(line) for line in done.stdout.splitlines()[-2:])
    assert installed == []
    assert {entry.split()[-1] for entry in report["made"]} == set(_registered_ids())
