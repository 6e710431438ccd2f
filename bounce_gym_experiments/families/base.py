"""The interface of an experiment family (`bounce_gym_experiments.registry`) and of the object that
follows one episode."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

from baselines.policy import (
    CONTACT_AND_CLOCK,
    POSE_OBSERVED,
    FixedAnglePolicy,
    Policy,
    RandomAnglePolicy,
    is_parallel_env,
    labelled,
)
from bounce_gym.envs.registration import is_pettingzoo_id
from bounce_gym.errors import ConfigError
from bounce_gym.extras import installed, require
from bounce_gym_experiments.config import registered_kwargs

#: the kinds of policy most families run (``planner``, ``random``, ``fixed``, ``rl``;
#: `Family.policies`); a family may run others (its ``policy_kinds``)
POLICY_KINDS = ("planner", "random", "fixed", "rl")


class Episode:
    """Follows one episode for its family: the start options, when it ends, the metrics."""

    def start_options(self, seed: int) -> dict | None:
        """Reset options the experiment imposes on every policy (``None``: the policy's own)."""
        return None

    def start(self, info: dict) -> bool:
        """After ``env.reset`` (``info``: robot 0's); whether the episode is already over."""
        return False

    def step(self, info: dict) -> bool:
        """After every step; whether the episode is over."""
        return False

    def metrics(self, info: dict) -> dict:
        """The family's columns of the episode's row (``info``: the last step's)."""
        return {}

    def ticks(self, info: dict, steps: int) -> int:
        """The clock ticks the episode lasted (``info``: the last step's; ``steps``: env steps
        taken): the bouncing robots' ``info["ticks"]``."""
        return int(info["ticks"])


class LastInfo(Episode):
    """An episode whose metrics are read from its last ``info`` alone."""

    def __init__(self, read) -> None:
        self.read = read

    def metrics(self, info: dict) -> dict:
        return self.read(info)


class Family:
    """An experiment family: recognised by the env's task (and parallel or not), with the task's
    planner, per-episode metrics, table columns and plots.

    ``table`` is the heading of the printed table its rows go to (default: the family's name;
    families with the same heading share one table, columns merged in registry order). Every
    measured column is shown as its estimate with a 95% interval and count
    (`bounce_gym_experiments.report`); ``labels`` are columns that describe the row instead (the same in
    every episode, e.g. the number of robots) and are shown as they are; ``descriptors`` are
    per-episode facts that are not measured (e.g. which target was attacked): they stay in the
    episode rows and are left out of the summary. ``record_paths``: whether the first seed's
    robot positions are recorded for `trajectory_plots` (from ``info["position"]``). ``score`` is the column
    that ranks policies (in leaderboards, performance profiles and the hindsight oracle),
    ``higher_is_better`` its direction. ``planner_attributes`` are the planner's predictions
    copied into its rows when set. ``policy_kinds`` are the kinds of policy of a
    configuration's ``policies`` (`bounce_gym_experiments.config`) the family runs; `policies` builds
    them (``rl``: the runner loads the trained models).

    A family owns the checks of the keys it reads (`validate`): which ``policies`` it runs
    (and their default, all of ``policy_kinds``), whether it takes ``planner_kwargs``
    (``takes_planner_kwargs``; then the default is ``{}``), ``adversaries`` (``adversary_kinds``;
    none by default) and ``visibility`` (``takes_visibility``; none by default). `claims`
    recognises its experiments from the configuration alone (the env id, its registered or
    overridden ``task``), before any env is built.
    """

    name = "family"
    task = "free"
    parallel = False
    table: str | None = None
    columns: tuple[str, ...] = ("experiment", "policy", "episodes", "seeds", "return", "ticks")
    labels: frozenset[str] = frozenset()
    descriptors: frozenset[str] = frozenset()
    record_paths = True
    score = "return"
    higher_is_better = True
    planner_attributes: tuple[str, ...] = ()
    policy_kinds: tuple[str, ...] = POLICY_KINDS
    adversary_kinds: tuple[str, ...] = ()
    takes_planner_kwargs = False
    takes_visibility = False

    @property
    def heading(self) -> str:
        """The heading of the table the family's rows go to."""
        return self.name if self.table is None else self.table

    def rank(self, row: dict) -> tuple:
        """How good one episode is, for comparing episodes of the same seed: the score (in its
        direction), then fewer ticks."""
        score = float(row[self.score])
        return (score if self.higher_is_better else -score, -row["ticks"])

    def claims(self, experiment: Mapping) -> bool:
        """Whether an experiment (checked by `bounce_gym_experiments.config.Experiment`) is one
        of this family's: default, its env is parallel (PettingZoo) or not as the family, and
        runs the family's task (`env_task`). Families are asked in the registry's order, so a
        family claims what the ones before it left (e.g. the safe-plan scenarios)."""
        return (is_pettingzoo_id(experiment["env"]) == self.parallel
                and env_task(experiment) == self.task)

    def validate(self, experiment: dict) -> None:
        """Check the keys of an experiment that this family reads, and fill in their defaults
        (in place); a mistake raises `ConfigError` naming the key within the experiment
        (``policies: ...``). Default: ``policies`` among `policy_kinds` (default: all of them),
        `adversaries` among ``adversary_kinds`` (only if there are any; default: all but
        ``rl``), ``planner_kwargs`` only if the family ``takes_planner_kwargs``, no
        ``visibility``."""
        experiment.setdefault("policies", list(self.policy_kinds))
        self.check_kinds("policies", experiment["policies"], self.policy_kinds)
        if not self.adversary_kinds and "adversaries" in experiment:
            raise ConfigError(f"adversaries: {self.name} experiments have no adversaries")
        if self.adversary_kinds:
            experiment.setdefault("adversaries",
                                  [k for k in self.adversary_kinds if k != "rl"])
            self.check_kinds("adversaries", experiment["adversaries"], self.adversary_kinds)
        if self.takes_planner_kwargs:
            experiment.setdefault("planner_kwargs", {})
        elif "planner_kwargs" in experiment:
            raise ConfigError(f"planner_kwargs: {self.name} experiments take no planner options")
        if "visibility" in experiment and not self.takes_visibility:
            raise ConfigError("visibility: only for single-robot experiments" if self.parallel
                              else f"visibility: {self.name} experiments have no safe-plan "
                                   "scenario")

    def check_kinds(self, key: str, given: list, kinds: tuple[str, ...]) -> None:
        """``given`` (the list of ``key``) is a non-empty list of ``kinds``."""
        unknown = [k for k in given if k not in kinds]
        if unknown:
            raise ConfigError(f"{key}: unknown {unknown}; {self.name} experiments run "
                              f"{list(kinds)}")
        if not given:
            raise ConfigError(f"{key}: expected a non-empty list of {list(kinds)}")

    def world_name(self, experiment: Mapping) -> str:
        """The world an experiment runs on: its ``env_kwargs.world`` (a map file by its file
        name) or the one its env id registers."""
        world = experiment["env_kwargs"].get("world",
                                             registered_kwargs(experiment["env"]).get("world", "?"))
        return Path(world).name if isinstance(world, str) else getattr(world, "name", str(world))

    def prepare(self, env, experiment: Mapping) -> object:
        """Per-experiment set-up on a fresh env, handed to `planner` and `episode`."""
        return None

    def world(self, env) -> object:
        """What the experiment's plots draw the robots in: the env's world."""
        return env.unwrapped.options.world

    def policies(self, kind: str, env, experiment: Mapping, setup: object) -> list[Policy]:
        """The policies of one kind (not ``rl``) for a bouncing robot or team: ``planner`` the
        family's (`planner`), ``random`` a random angle of Φ at every bump, ``fixed`` one policy
        per angle of Φ (discrete actions only)."""
        options = env.unwrapped.options
        discrete = options.action_type == "discrete"
        if is_parallel_env(env) and not discrete:
            raise ConfigError("env_kwargs.action_type: multi-robot experiments choose angles by "
                              "index; use 'discrete'")
        if kind == "planner":
            planner = self.planner(env, experiment, setup)
            return [] if planner is None else [planner]
        if kind == "random":
            return [RandomAnglePolicy()]
        if kind == "fixed" and discrete:
            n = min(len(phi) for phi in options.angles)
            return [FixedAnglePolicy(i, math.degrees(options.angles[0][i])) for i in range(n)]
        return []

    def planner(self, env, experiment: Mapping, setup: object) -> Policy | None:
        """The task's analytic planner (``None``: none applies to this env)."""
        raise ConfigError(f"policies: no reference planner for task {self.task!r}")

    def trained_policies(self, folder: Path, env, label: str, experiment: Mapping,
                         setup: object) -> list[tuple[Policy, str]]:
        """Every trusted model of ``folder`` as a policy for ``env`` (none if there are none),
        with the group it is aggregated into; ``label`` prefixes the names (``""`` or
        ``"<folder>/"``). Gymnasium env: `baselines.rl.policies.SB3Policy`; parallel env: one
        `baselines.rl.policies.SharedSB3Policy` for every robot; a JAX learner's model
        (``jax_ppo``, ``jax_dqn``): `baselines.rl.jaxrl.policy.JaxPolicy`; a multi-robot
        learner's (``ippo``, ``mappo``): `baselines.rl.marl.policy.TeamPolicy`, its rows named
        by what it plays (``rl mappo (shared, id)``, ``rl mappo (shared, id) seed0``). Each model plays twice: its
        sampled actions (``rl <algo>_seed<N>``, group ``rl <algo>``) and its greedy ones (the
        same names with `baselines.rl.policies.GREEDY_SUFFIX`), two groups of their own; with the
        experiment's ``greedy: false``, its sampled actions only. On an
        env whose observation holds the pose (``env.unwrapped.observes_pose``: v1's
        ``achieved_goal``, ``privileged=True``) the models are `POSE_OBSERVED` and their names
        say so."""
        from baselines.rl.model_files import (
            JAX_ALGOS,
            MARL_ALGOS,
            MODEL_NAME,
            model_files,
            run_name,
        )
        from baselines.rl.policies import GREEDY_SUFFIX, SB3Policy, SharedSB3Policy

        sb3 = SharedSB3Policy if is_parallel_env(env) else SB3Policy
        information = POSE_OBSERVED if getattr(env.unwrapped, "observes_pose", False) \
            else CONTACT_AND_CLOCK
        options = env.unwrapped.options
        here = motion_model_of(options.backend, options.physics) \
            if hasattr(options, "physics") else None  # the drifters' flows have none
        out = []
        left_out = unplayable(folder)
        for path in (p for p in model_files(folder) if p not in left_out):
            name = MODEL_NAME.fullmatch(path.name)
            trained = trained_motion_model(path)
            elsewhere = f" (trained on {trained})" \
                if None not in (here, trained) and trained != here else ""
            group = labelled(f"rl {label}{run_name(name['algo'], name['variant'])}",
                             information) + elsewhere
            kind = _jax_policy() if name["algo"] in JAX_ALGOS else _team_policy() \
                if name["algo"] in MARL_ALGOS else sb3
            for deterministic in (False, True)[:1 + experiment["greedy"]]:
                suffix = GREEDY_SUFFIX if deterministic else ""
                policy = kind(path, env, deterministic)
                policy.information = information
                played, seed = f"rl {label}{path.stem}", f"seed{name['seed']}"
                if name["algo"] in MARL_ALGOS:  # e.g. rl mappo (shared, id)
                    group = labelled(f"rl {label}{policy.described}", information) + elsewhere
                    played = f"rl {label}{policy.described} {seed}"
                policy.name = labelled(played, information) + elsewhere + suffix
                out.append((policy, group + suffix))
        return out

    def episode(self, env, policy: Policy, setup: object) -> Episode:
        return Episode()

    def row_metrics(self, episode: Episode, info: dict, policy: Policy) -> dict:
        """The episode's metrics, then the planner's predictions."""
        out = episode.metrics(info)
        for key in self.planner_attributes:
            value = getattr(policy, key, None)
            if value is not None:
                out[key] = value
        return out

    def collect(self, data: dict, env, policy: Policy, setup: object) -> None:
        """Plot data after a first-seed episode (``data`` holds world, paths, family)."""

    def drain(self, setup: object) -> object:
        """What the episodes run so far have filed with ``setup`` for the plots (e.g. every
        episode's coverage curve), taken out of it: a unit of an evaluation sweep
        (`bounce_gym_experiments.sweep`) runs on its own copy of the setup and hands this back, and
        `absorb` files it with the experiment's setup. Default: nothing is filed."""
        return None

    def absorb(self, setup: object, drained: object) -> None:
        """File what `drain` took from a copy of ``setup`` with ``setup``."""

    def plots(self, folder: Path, name: str, data: dict) -> list[Path]:
        """The family's plots of one experiment."""
        return []

    def trajectory_plots(self, folder: Path, name: str, data: dict) -> list[Path]:
        """The first seed's trajectories of every policy in the world (``data["paths"]``)."""
        from bounce_gym_experiments.plots.trajectories import plot_trajectories

        return plot_trajectories(folder, name, data)

    def summary_plots(self, folder: Path, plots: Mapping, summary: list[dict]) -> list[Path]:
        """Plots across the family's experiments (called once per family that ran)."""
        return []


def env_task(experiment: Mapping) -> object:
    """The task an experiment's env runs: its ``env_kwargs.task`` or the one its env id
    registers (``None``: none registered)."""
    return experiment["env_kwargs"].get("task", registered_kwargs(experiment["env"]).get("task"))


class SingleRobotFamily(Family):
    """A Gymnasium (one robot) task whose metrics are read from the episode's last ``info``
    (`metrics`) and whose planner chooses angles of Φ by index: on an env with continuous actions
    there is no planner to run."""

    def planner(self, env, experiment, setup):
        if env.unwrapped.options.action_type != "discrete":
            return None
        return self.make_planner(env)

    def make_planner(self, env) -> Policy:
        return super().planner(env, {}, None)

    def episode(self, env, policy, setup):
        return LastInfo(self.metrics)

    def metrics(self, info: dict) -> dict:
        return {}


def unplayable(folder: Path) -> list[Path]:
    """The model files of ``folder`` whose learner's extra is not installed: the JAX learners'
    where JAX is not (`trained_policies` leaves them out; the runner says so in a note)."""
    from baselines.rl.model_files import JAX_ALGOS, MODEL_NAME, model_files

    if all(installed(module) for module in JAX_MODULES):
        return []
    return [p for p in model_files(folder) if MODEL_NAME.fullmatch(p.name)["algo"] in JAX_ALGOS]


#: what a JAX learner's model needs to play (the `jax` extra)
JAX_MODULES = ("jax", "optax")


def _jax_policy():
    """`baselines.rl.jaxrl.policy.JaxPolicy`, imported only for a JAX learner's model (it needs
    JAX: without it, a `ConfigError` naming the extra)."""
    require("models: a jax_ppo or jax_dqn model", *JAX_MODULES)
    from baselines.rl.jaxrl.policy import JaxPolicy

    return JaxPolicy


def _team_policy():
    """`baselines.rl.marl.policy.TeamPolicy`, imported only for a multi-robot learner's model
    (it needs torch: without it, a `ConfigError` naming the extra)."""
    require("models: an ippo or mappo model", "torch")
    from baselines.rl.marl.policy import TeamPolicy

    return TeamPolicy


def motion_model_of(backend: str, physics: str | None) -> str:
    """A motion model's name in row names: ``cell``, ``kinematic``, ``pymunk ideal`` or
    ``pymunk dynamic`` (``physics`` None: the backend's default)."""
    if backend != "pymunk":
        return backend
    return f"pymunk {physics or 'dynamic'}"


def trained_motion_model(path: Path) -> str | None:
    """The motion model a model file was trained on (`motion_model_of`), read from the training
    configuration its metadata records (the env id's registered arguments under its
    ``env_kwargs``); None where the file records no configuration (a model saved by hand)."""
    import gymnasium

    from baselines.rl.model_files import read_model

    config = read_model(path).metadata.get("config")
    if not isinstance(config, Mapping) or not isinstance(config.get("env"), str):
        return None
    given = dict(config.get("env_kwargs") or {})
    try:
        return motion_model_of(str(env_option(config["env"], given, "backend")),
                               env_option(config["env"], given, "physics"))
    except (gymnasium.error.Error, KeyError):  # an id this version does not register
        return None


def env_option(env_id: str, env_kwargs: Mapping, name: str) -> object:
    """The value of a bouncing env's option ``name`` (`EnvOptions`) for ``env_id`` made with
    ``env_kwargs``: given, else registered by the id, else the option's default."""
    from bounce_gym.envs.options import EnvOptions

    if name in env_kwargs:
        return env_kwargs[name]
    return registered_kwargs(env_id).get(name, EnvOptions.model_fields[name].default)
