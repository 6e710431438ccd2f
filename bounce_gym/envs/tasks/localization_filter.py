"""The built-in filter of the localization task."""

from __future__ import annotations

from bounce_gym.cells import CellModel
from bounce_gym.errors import ConfigError
from bounce_gym.markov.filters import ActiveLocalizationFilter, LocalizationFilter


def task_filter(options) -> LocalizationFilter | ActiveLocalizationFilter:
    """The filter for the environments' localization task.

    Plug it in with ``task_kwargs={"filter_factory": "bounce_gym.envs.tasks.localization_filter:task_filter"}`` (the
    registered ``bounce_gym/BounceLocalization-v0`` does). ``options`` are the env's validated
    `EnvOptions`: the world is discretised with cell size = ``step_length``, the cell backend's
    ``n_bins`` (8 otherwise) and the robot's radius. One bounce angle gives the O(1) DFA filter
    (Def. 8/9); several give the active filter. The filter is closed-world only on the noise-free
    ``cell`` backend, where the robot steps the model exactly; elsewhere it is open-world and
    reports ``trapped`` once the robot's observations leave the model.
    """
    if options.action_type != "discrete":
        raise ConfigError("localization filter: needs discrete actions (each bounce angle must "
                          "be a whole orientation bin of the cell model)")
    n_bins = options.backend_options.get("n_bins", 8)
    model = CellModel(options.world, cell_size=options.step_length, n_bins=n_bins,
                      robot_radius=options.robot_radius,
                      corner_rule=options.backend_options.get("corner_rule", "target_only"))
    exact = options.backend == "cell" and type(options.noise).__name__ == "Exact"
    angles = options.angles[0]
    if len(angles) == 1:
        return LocalizationFilter.from_model(model, float(angles[0]), open_world=not exact)
    return ActiveLocalizationFilter(model, angles, open_world=not exact)

