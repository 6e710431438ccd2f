"""The experiment families: what the runner and the report need to know about each kind of task.

A family is recognised from an experiment and its env (the env's task, whether it is a
PettingZoo parallel env, the experiment's keys); it supplies the task's planner, follows an
episode to give its metrics, says which columns the printed table shows (and which of them
describe the row rather than measure it), which column ranks policies, and draws the family's
plots. `FAMILIES` lists them in the order they are tried; a new family is one module in
`bounce_gym_experiments.families` plus one line here.
"""

from __future__ import annotations

from collections.abc import Mapping

from bounce_gym.errors import ConfigError
from bounce_gym_experiments.families import (
    bouncing,
    coverage,
    drifter_deployment,
    drifters,
    localization,
    multirobot,
    multirobot_coverage,
    multirobot_monitoring,
    navigation,
    patrolling,
    visibility,
)
from bounce_gym_experiments.families.base import Family

FAMILIES: tuple[Family, ...] = (
    patrolling.FAMILY,
    drifters.FAMILY,
    drifter_deployment.FAMILY,
    visibility.FAMILY,
    navigation.FAMILY,
    coverage.FAMILY,
    localization.FAMILY,
    bouncing.FAMILY,
    multirobot_coverage.FAMILY,
    multirobot_monitoring.FAMILY,
    multirobot.FAMILY,
)


def family_for(experiment: Mapping, env) -> Family:
    """The first family of `FAMILIES` that recognises the experiment on its env."""
    for family in FAMILIES:
        if family.recognises(experiment, env):
            return family
    raise ConfigError(f"{experiment['name']}: no experiment family for task "
                      f"{env.unwrapped.task.name!r}")
