"""Every registered id has its description (`registration.ABOUT`) beside its registration, and
the descriptions are all that is left of the per-id facts in the module's docstring."""

import gymnasium as gym
import pettingzoo

import bounce_gym  # noqa: F401 - registers the ids
from bounce_gym.envs import registration


def _registered() -> set[str]:
    """The ids of this package in Gymnasium's and PettingZoo's registries."""
    ids = {env_id for env_id in gym.registry if env_id.startswith("bounce_gym/")}
    for registry in (pettingzoo.parallel_registry, pettingzoo.aec_registry):
        ids |= {env_id for env_id in registry if env_id.startswith("bounce_gym/")}
    return ids


def test_every_registered_id_has_a_description_and_no_other_id_has_one():
    registered = _registered()
    assert len(registered) >= 11
    assert set(registration.ABOUT) == registered
    for env_id, about in registration.ABOUT.items():
        assert len(about.split()) >= 8, env_id  # a sentence or more, not a label
        assert about.rstrip().endswith("."), env_id


def test_the_module_docstring_describes_no_single_id():
    # the per-id facts live in ABOUT; the docstring keeps the conventions shared by every id
    for env_id in registration.ABOUT:
        assert env_id not in registration.__doc__
