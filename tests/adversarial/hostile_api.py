"""The hostile-input suite's Python API cases (`test_hostile_inputs`): bad actions given to
``step`` of every env form, bad env arguments given to ``gym.make`` and ``pettingzoo.make``,
and malformed files and configurations given to the package's loaders and validators.

An `ApiCase` prepares what it needs (an env, reset; a file in the case folder) and returns the
one call to measure, which must raise ``error`` (a `bounce_gym.errors.BounceGymError`) with a
one-line message containing ``expect``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from hostile_cases import Sandbox, evaluation, training
from hostile_files import flow_file

from bounce_gym.errors import ActionError, BounceGymError, ConfigError, FlowFileError


@dataclass(frozen=True)
class ApiCase:
    """A call that must raise ``error`` with a message containing ``expect``, with ``env`` set
    as `hostile_cases.Case` sets it."""

    cls: str
    name: str
    build: Callable[[Sandbox], Callable[[], object]]
    error: type[BounceGymError] = BounceGymError
    expect: str = ""
    env: tuple[tuple[str, str | None], ...] = ()

    @property
    def id(self) -> str:
        return f"{self.cls}:{self.name}"


# -- actions ---------------------------------------------------------------------------------
def _gym(env_id: str, **kwargs):
    import gymnasium as gym

    import bounce_gym  # noqa: F401  (registers the environments)

    env = gym.make(env_id, **kwargs)
    env.reset(seed=0)
    return env


def _vector(env_id: str):
    import gymnasium as gym

    import bounce_gym  # noqa: F401

    env = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    env.reset(seed=0)
    return env


def _petting(kind: str, env_id: str):
    import pettingzoo

    import bounce_gym  # noqa: F401

    env = pettingzoo.make(kind, env_id)
    env.reset(seed=0)
    return env


#: bad actions, by name, for every env
ACTIONS = {"NaN": math.nan, "inf": math.inf, "a string": "x", "None": None,
           "a list of three": [0, 1, 2], "10**30": 10**30, "-1": -1, "bytes": b"1",
           "complex": 1j, "a mapping": {"a": 1}}
#: the single-robot ids (each made with gym.make)
GYM_IDS = ("bounce_gym/Bounce-v0", "bounce_gym/BounceNavigation-v0",
           "bounce_gym/BounceCoverage-v0", "bounce_gym/BounceLocalization-v0",
           "bounce_gym/Drifter-v0")
PETTING_IDS = ("bounce_gym/MultiBounce-v0", "bounce_gym/MultiDrifter-v0",
               "bounce_gym/Patrol-v0")


def _step(make: Callable[[], object], action: object, per_agent: bool = False):
    def build(box: Sandbox) -> Callable[[], object]:
        env = make()
        if per_agent:
            return lambda: env.step(dict.fromkeys(env.agents, action))
        return lambda: env.step(action)
    return build


def _actions() -> list[ApiCase]:
    out = []
    short = ("NaN", "a string", "None", "a list of three", "10**30")
    for env_id in GYM_IDS:
        for name, action in ACTIONS.items():
            out.append(ApiCase("actions", f"{env_id} {name}",
                               _step(lambda env_id=env_id: _gym(env_id), action), ActionError))
    for env_id in ("bounce_gym/Bounce-v0", "bounce_gym/BounceNavigation-v0"):
        for name, action in {**{k: ACTIONS[k] for k in short},
                             "one action for two envs": np.zeros(1),
                             "NaN in an array": np.array([np.nan, 0.0]),
                             "strings in an array": np.array(["a", "b"])}.items():
            out.append(ApiCase("actions", f"vector {env_id} {name}",
                               _step(lambda env_id=env_id: _vector(env_id), action),
                               ActionError))
    for env_id in PETTING_IDS:
        for name in short:
            out.append(ApiCase("actions", f"AEC {env_id} {name}", _step(
                lambda env_id=env_id: _petting("aec", env_id), ACTIONS[name]), ActionError))
            out.append(ApiCase("actions", f"parallel {env_id} {name}", _step(
                lambda env_id=env_id: _petting("parallel", env_id), ACTIONS[name],
                per_agent=True), ActionError))
        for name, action in (("not a mapping", 3), ("None for all", None),
                             ("an unknown agent", {"nobody": 0})):
            out.append(ApiCase("actions", f"parallel {env_id} {name}", _step(
                lambda env_id=env_id: _petting("parallel", env_id), action), ActionError))
    return out


# -- env arguments ---------------------------------------------------------------------------
def _make(kind: str, env_id: str, **kwargs):
    def build(box: Sandbox) -> Callable[[], object]:
        import gymnasium as gym
        import pettingzoo

        import bounce_gym  # noqa: F401

        if kind == "gym":
            return lambda: gym.make(env_id, **kwargs)
        return lambda: pettingzoo.make(kind, env_id, **kwargs)
    return build


def _env_arguments() -> list[ApiCase]:
    junk = {"an unknown argument": {"colour": 1},
            "NaN angles": {"angles": [math.nan]},
            "angles a string": {"angles": "x"},
            "history -1": {"history": -1},
            "history 10**12": {"history": 10**12},
            "an unknown world": {"world": "atlantis"},
            "world a number": {"world": 3},
            "backend unknown": {"backend": "quantum"},
            "task unknown": {"task": "fly"},
            "noise unknown": {"noise": {"type": "x"}},
            "robot_radius NaN": {"robot_radius": math.nan},
            # lengths beyond the world's own (issue 36, item 6): accepted, hung or a RuntimeError
            "step_length 1e12": {"step_length": 1e12},
            "step_length 1e-9": {"step_length": 1e-9},
            "cell backend step_length 1e-3": {"backend": "cell", "step_length": 1e-3},
            "robot_radius 1e-12 on pymunk": {"backend": "pymunk", "robot_radius": 1e-12},
            "world_scale 1e12": {"backend": "pymunk", "physics_params": {"world_scale": 1e12}},
            "world_scale 1e-5": {"backend": "pymunk", "robot_radius": 0.3,
                                 "physics_params": {"world_scale": 1e-5}}}
    drifter = {"an unknown argument": {"colour": 1},
               "step_seconds 1e300": {"backend": "continuous", "step_seconds": 1e300},
               "diffusivity 1e300": {"backend": "continuous", "diffusivity": 1e300},
               "flow unknown": {"flow": "atlantis"},
               "flow a number": {"flow": 3},
               "max_values zero": {"flow_kwargs": {"max_values": 0}}}
    patrol = {"an unknown argument": {"colour": 1},
              "cell_size NaN": {"cell_size": math.nan},
              "a 600 x 450 grid": {"world": "heptagon"},
              "cell_size 1e-6": {"cell_size": 1e-6},
              "sensor_range 1e9": {"sensor_range": 1e9},
              "n_patrollers a string": {"n_patrollers": "2"},
              "attack_time zero": {"attack_time": 0}}
    out = []
    for env_id in ("bounce_gym/Bounce-v0", "bounce_gym/BounceNavigation-v0"):
        for name, kwargs in junk.items():
            if name == "robot_radius NaN":
                continue
            out.append(ApiCase("env arguments", f"{env_id} {name}",
                               _make("gym", env_id, **kwargs), ConfigError))
    for name, kwargs in junk.items():
        out.append(ApiCase("env arguments", f"MultiBounce {name}",
                           _make("parallel", "bounce_gym/MultiBounce-v0", **kwargs),
                           ConfigError))
    for name, kwargs in drifter.items():
        out.append(ApiCase("env arguments", f"Drifter {name}",
                           _make("gym", "bounce_gym/Drifter-v0", **kwargs), ConfigError))
        out.append(ApiCase("env arguments", f"MultiDrifter {name}",
                           _make("aec", "bounce_gym/MultiDrifter-v0", **kwargs), ConfigError))
    for name, kwargs in patrol.items():
        out.append(ApiCase("env arguments", f"Patrol {name}",
                           _make("parallel", "bounce_gym/Patrol-v0", **kwargs), ConfigError))
    return out


# -- loaders and validators ------------------------------------------------------------------
def _file(name: str, content: str | bytes, call: Callable[[Path], object]):
    def build(box: Sandbox) -> Callable[[], object]:
        box.write(name, content)
        return lambda: call(box.here / name)
    return build


def _with_flow(call: Callable[[Path], object], **options):
    def build(box: Sandbox) -> Callable[[], object]:
        path = flow_file(box.here / "f.nc", **options)
        return lambda: call(path)
    return build


def _value(call: Callable[[], object]):
    return lambda box: call


def _load_map(path: Path):
    from bounce_gym.worlds.io import load

    return load(path)


def _load_flow(path: Path, **options):
    from bounce_gym.flows.netcdf import load_flow

    return load_flow(path, **options)


def _validate(config: object):
    from bounce_gym_experiments.config import validate_config

    return lambda: validate_config(config)


def _validate_training(config: object):
    from baselines.rl.train_config import validate_train_config

    return lambda: validate_train_config(config)


def _read_model(path: Path):
    from baselines.rl.model_files import read_model

    return read_model(path)


def _parse(data: bytes, fmt: str = "yaml"):
    from bounce_gym.documents import parse_document

    return lambda: parse_document("doc", data, fmt=fmt)


def _loaders() -> list[ApiCase]:
    grid = 'name: bomb\ngrid:\n- &r "' + "." * 20_000 + '"\n' + "- *r\n" * 20_000
    c = "loaders"
    return [
        ApiCase(c, "map: a bow tie", _file("m.json", '{"name": "x", "outer": [[0, 0], [1, 1], '
                                                     '[1, 0], [0, 1]]}', _load_map),
                expect="invalid polygon"),
        ApiCase(c, "map: aliased rows", _file("m.yaml", grid, _load_map), expect="m.yaml"),
        ApiCase(c, "map: a NUL in the path", _value(lambda: _load_map(Path("m\0.json"))),
                expect="m"),
        ApiCase(c, "map: a huge number", _file("m.json", '{"name": "x", "outer": [[1' + "0" * 5000
                                                         + ', 0], [1, 0], [0, 1]]}', _load_map),
                expect="m.json"),
        ApiCase(c, "flow: a NUL in the path", _value(lambda: _load_flow(Path("f\0.nc"))),
                FlowFileError),
        ApiCase(c, "flow: max_values zero", _with_flow(lambda p: _load_flow(p, max_values=0)),
                ConfigError, "max_values"),
        ApiCase(c, "flow: a mapping to nothing", _with_flow(lambda p: _load_flow(
            p, mapping={"u": "nothing"})), FlowFileError),
        ApiCase(c, "flow: a mapping of numbers", _with_flow(lambda p: _load_flow(
            p, mapping={"u": 3})), FlowFileError),
        ApiCase(c, "flow: an unknown mapping key", _with_flow(lambda p: _load_flow(
            p, mapping={"w": "u"})), FlowFileError),
        ApiCase(c, "flow: a billion cells", _with_flow(_load_flow, declared=(10_000, 100_000)),
                FlowFileError),
        ApiCase(c, "flow: a cap of 5000 digits", _with_flow(_load_flow), ConfigError,
                "BOUNCE_GYM_MAX_FLOW_VALUES: expected a positive integer",
                env=(("BOUNCE_GYM_MAX_FLOW_VALUES", "9" * 5000),)),
        ApiCase(c, "flow: a cap of zero", _with_flow(_load_flow), ConfigError,
                "BOUNCE_GYM_MAX_FLOW_VALUES", env=(("BOUNCE_GYM_MAX_FLOW_VALUES", "0"),)),
        ApiCase(c, "evaluation: models with a NUL", _value(_validate(evaluation(
            models="a\0b"))), ConfigError, "config.models"),
        ApiCase(c, "evaluation: output with a NUL", _value(_validate(evaluation(
            output="a\0b"))), ConfigError, "config.output"),
        ApiCase(c, "evaluation: not a mapping", _value(_validate([1])), ConfigError),
        ApiCase(c, "training: models with a NUL", _value(_validate_training(training(
            models="a\0b"))), ConfigError, "config.models"),
        ApiCase(c, "training: hyperparams_file with a NUL", _value(_validate_training(training(
            hyperparams_file="a\0b.yaml"))), ConfigError, "config.hyperparams_file"),
        ApiCase(c, "training: not a mapping", _value(_validate_training(None)), ConfigError),
        ApiCase(c, "model: a NUL in the path", _value(lambda: _read_model(
            Path("m/ppo_seed0\0.zip"))), ConfigError),
        ApiCase(c, "model: another name", _file("x.zip", b"PK", _read_model), ConfigError,
                "expected a name"),
        ApiCase(c, "document: a JSON integer of 5000 digits", _value(_parse(
            b"[1" + b"0" * 5000 + b"]", "json")), ConfigError),
        ApiCase(c, "document: a YAML integer of 5000 digits", _value(_parse(
            b"[1" + b"0" * 5000 + b"]")), ConfigError),
        ApiCase(c, "document: JSON of a lone surrogate", _value(_parse(b'["\\ud800"]', "json")),
                ConfigError, "control character U+D800"),
        ApiCase(c, "document: JSON nested 100000 deep", _value(_parse(
            b"[" * 100_000 + b"]" * 100_000, "json")), ConfigError, "nest"),
        ApiCase(c, "document: JSON duplicate keys", _value(_parse(b'{"a": 1, "a": 2}', "json")),
                ConfigError, "duplicate key"),
    ]


def cases() -> list[ApiCase]:
    """Every case of this module."""
    return [*_actions(), *_env_arguments(), *_loaders()]
