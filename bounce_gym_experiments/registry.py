"""The experiment families: what the runner and the report need to know about each kind of task.

A family is recognised from an experiment alone (`Family.claims`: the env id, the env's task,
the experiment's keys), before any env is built, and checks the experiment's keys it reads
(`Family.validate`, called by `bounce_gym_experiments.config`); it supplies the task's planner, follows an
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
from bounce_gym_experiments.families.base import Family, env_task

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


def family_of(experiment: Mapping, where: str = "experiment") -> Family:
    """The first family of `FAMILIES` that claims the experiment; ``where`` names it in the
    error if none does."""
    for family in FAMILIES:
        if family.claims(experiment):
            return family
    raise ConfigError(f"{where}.env: no experiment family runs {experiment['env']} with task "
                      f"{env_task(experiment)!r}")


def world_name(experiment: Mapping) -> str:
    """The world an experiment runs on, as its family names it (`Family.world_name`): a map or
    flow by its name."""
    return family_of(experiment).world_name(experiment)
