"""Families own their configuration checks: the configuration and the runner name no family and
no env id, the registry maps an experiment to its family, and a newly registered family's
`validate` is what checks its experiments."""

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[2]
sys.path.insert(0, str(ROOT))

from bounce_gym.envs.registration import (  # noqa: E402
    DRIFTER_GYM_ENVS,
    DRIFTER_PETTINGZOO_ENVS,
    GYM_ENVS,
    PATROL_PETTINGZOO_ENVS,
    PETTINGZOO_ENVS,
)
from bounce_gym.errors import ConfigError  # noqa: E402
from bounce_gym_experiments import registry  # noqa: E402
from bounce_gym_experiments.config import validate_config  # noqa: E402
from bounce_gym_experiments.families.base import Family  # noqa: E402

GENERIC = [ROOT / "bounce_gym_experiments" / name for name in ("config.py", "runner.py")]
ENV_IDS = [*GYM_ENVS, *DRIFTER_GYM_ENVS, *PETTINGZOO_ENVS, *DRIFTER_PETTINGZOO_ENVS,
           *PATROL_PETTINGZOO_ENVS]


@pytest.mark.parametrize("path", GENERIC, ids=lambda p: p.name)
def test_the_generic_modules_name_no_family_and_no_env_id(path):
    text = path.read_text(encoding="utf-8")
    family_names = {f.name for f in registry.FAMILIES} | {
        type(f).__module__.rsplit(".", 1)[1] for f in registry.FAMILIES}
    family_names -= {"visibility"}  # also the experiment key its family is recognised by
    for word in [*ENV_IDS, *family_names, "is_drifter_id", "PATROL", "Patrol", "Drifter",
                 "families."]:
        assert not re.search(rf"(?<![\w.]){re.escape(word)}(?![\w])", text), (path.name, word)


@pytest.mark.parametrize(("env", "family"), [
    ("bounce_gym/Bounce-v0", "bouncing"), ("bounce_gym/BounceNavigation-v0", "navigation"),
    ("bounce_gym/BounceNavigation-v1", "navigation"), ("bounce_gym/BounceCoverage-v0", "coverage"),
    ("bounce_gym/BounceLocalization-v0", "localization"), ("bounce_gym/Drifter-v0", "drifters"),
    ("bounce_gym/MultiBounce-v0", "multirobot"),
    ("bounce_gym/MultiBounceCoverage-v0", "multirobot coverage"),
    ("bounce_gym/MultiBounceMonitoring-v0", "multirobot monitoring"),
    ("bounce_gym/MultiDrifter-v0", "drifter-deployment"), ("bounce_gym/Patrol-v0", "patrolling"),
])
def test_the_registry_maps_every_env_id_to_its_family(env, family):
    assert registry.family_of({"name": "a", "env": env, "env_kwargs": {}}).name == family
    assert ENV_IDS.count(env) == 1


def test_a_task_override_or_a_visibility_block_picks_the_family():
    experiment = {"name": "a", "env": "bounce_gym/Bounce-v0", "env_kwargs": {"task": "coverage"}}
    assert registry.family_of(experiment).name == "coverage"
    assert registry.family_of({**experiment, "visibility": {}}).name == "visibility"
    with pytest.raises(ConfigError, match=r"^x\.env: no experiment family runs "
                                          r"bounce_gym/Drifter-v0 with task 'stay'$"):
        registry.family_of({"name": "a", "env": "bounce_gym/Drifter-v0",
                            "env_kwargs": {"task": "stay"}}, "x")


class Juggling(Family):
    """A family registered by a test: it claims the free task's experiments named juggle-*,
    runs its own kinds, and needs ``planner_kwargs.balls``."""

    name = "juggling"
    policy_kinds = ("planner", "random")
    takes_planner_kwargs = True

    def claims(self, experiment):
        return experiment["name"].startswith("juggle")

    def validate(self, experiment):
        super().validate(experiment)
        if not isinstance(experiment["planner_kwargs"].get("balls"), int):
            raise ConfigError("planner_kwargs.balls: expected the number of balls")


def test_a_new_family_registered_with_validate_is_consulted(monkeypatch):
    monkeypatch.setattr(registry, "FAMILIES", (Juggling(), *registry.FAMILIES))
    experiment = {"name": "juggle-a", "env": "bounce_gym/Bounce-v0",
                  "planner_kwargs": {"balls": 3}}
    checked = validate_config({"experiments": [{"name": "plain", "env": "bounce_gym/Bounce-v0"},
                                               experiment]})
    assert checked["experiments"][1]["policies"] == ["planner", "random"]  # its default
    assert checked["experiments"][0]["policies"] == ["planner", "random", "fixed", "rl"]
    with pytest.raises(ConfigError, match=r"^config\.experiments\[1\]\.planner_kwargs\.balls: "
                                          r"expected the number of balls$"):
        validate_config({"experiments": [{"name": "plain", "env": "bounce_gym/Bounce-v0"},
                                         {**experiment, "planner_kwargs": {}}]})
    with pytest.raises(ConfigError, match=r"^config\.experiments\[0\]\.policies: unknown "
                                          r"\['fixed'\]; juggling experiments run "):
        validate_config({"experiments": [{**experiment, "policies": ["fixed"]}]})
    # without it, the bouncing family takes the experiment and refuses the planner options
    monkeypatch.undo()
    with pytest.raises(ConfigError, match=r"planner_kwargs: bouncing experiments take no "):
        validate_config({"experiments": [experiment]})
