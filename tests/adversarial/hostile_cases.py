"""The catalogue of the hostile-input suite (`test_hostile_inputs`): malformed configurations and
flags given to the ``bounce-gym`` command, by class.

A `Case` writes its files into a fresh case folder (`Sandbox`), which is the working folder of
the command, and gives the command's arguments. The command must refuse it in one line that
contains ``expect``, changing nothing outside ``writes`` (a path under the case folder: the
output folder it names). Payloads that would run code try to create `Sandbox.marker`.

The files, maps, flow files, model files and unit files of the other classes are built in
`hostile_files`; what goes through the Python API (actions, env arguments, loaders) is in
`hostile_api`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import yaml

NAVIGATION = "bounce_gym/BounceNavigation-v0"
NAV = {"world": "square", "backend": "cell", "angles": [90, 135]}


@dataclass
class Sandbox:
    """A case's folder ``here`` (the command's working folder, two levels below the snapshot's
    root, so that ``../..`` stays inside it) and the ``marker`` a payload would create."""

    here: Path
    marker: Path
    trained: Path | None = None  #: a model this package trained (for the model cases)

    def write(self, name: str, content: str | bytes) -> str:
        """Write ``content`` to ``name`` in the case folder; returns ``name``."""
        path = self.here / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, str):
            content = content.encode("utf-8")
        path.write_bytes(content)
        return name

    def yaml(self, name: str, data: object) -> str:
        return self.write(name, yaml.safe_dump(data, sort_keys=False))

    def touch_payload(self) -> str:
        """A shell command that creates the marker."""
        return f"touch {self.marker}"


@dataclass(frozen=True)
class Case:
    """One malformed input given to the command: ``build(sandbox)`` writes its files and returns
    the arguments. The command must end with exit status ``status``: 2, an error line that
    contains ``expect``; 0, after warning lines that do. Only ``writes`` may change; ``env``
    sets (or, with None, removes) environment variables for the run (``{here}`` in a value is
    the case folder)."""

    cls: str
    name: str
    build: Callable[[Sandbox], list[str]]
    expect: str
    writes: str = "out"
    env: tuple[tuple[str, str | None], ...] = field(default=())
    status: int = 2

    @property
    def id(self) -> str:
        return f"{self.cls}:{self.name}"


def experiment(**overrides) -> dict:
    """A small navigation experiment (5 steps of one seed, random policy); an override of None
    leaves the key out."""
    exp = {"name": "a", "env": NAVIGATION, "env_kwargs": dict(NAV), "seeds": [10_000],
           "max_steps": 5, "horizon_reason": "a quick test", "policies": ["random"],
           **overrides}
    return {k: v for k, v in exp.items() if v is not None}


def evaluation(*experiments: dict, **top) -> dict:
    """A configuration writing into ``out/runs`` (models read from ``models``), in this
    process (one worker), of ``experiments`` (default: one `experiment`)."""
    config = {"name": "run", "output": "out/runs", "models": "models",
              "executor": {"workers": 1}, "experiments": list(experiments) or [experiment()],
              **top}
    return {k: v for k, v in config.items() if v is not None}


def evaluate_yaml(text_or_config: str | bytes | dict | Callable[[Sandbox], str | bytes],
                  *flags: str, name: str = "c.yaml") -> Callable[[Sandbox], list[str]]:
    """A builder: the configuration (text, bytes, a mapping, or made from the sandbox) in
    ``name``, evaluated with ``flags``."""
    def build(box: Sandbox) -> list[str]:
        content = text_or_config(box) if callable(text_or_config) else text_or_config
        if isinstance(content, dict):
            box.yaml(name, content)
        else:
            box.write(name, content)
        return ["evaluate", name, "--no-progress", *flags]
    return build


def eval_case(cls: str, name: str, content, expect: str, *flags: str, **options) -> Case:
    return Case(cls, name, evaluate_yaml(content, *flags), expect, **options)


def laughs(levels: int, indent: str = "    ") -> str:
    """A "billion laughs" of YAML aliases, ``levels`` deep, ten-fold at each level, as the lines
    of a block mapping at ``indent``."""
    lines = [f"{indent}l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for k in range(1, levels + 1):
        lines.append(f"{indent}l{k}: &l{k} [" + ", ".join([f"*l{k - 1}"] * 10) + "]")
    return "\n".join(lines) + "\n"


def _nav_yaml(extra: str = "", seeds: str = "[10000]") -> str:
    return ("experiments:\n- name: a\n  env: bounce_gym/BounceNavigation-v0\n"
            f"  seeds: {seeds}\n  max_steps: 5\n  horizon_reason: q\n  policies: [random]\n"
            + extra)


# -- evaluation configurations: the text -----------------------------------------------------
def _yaml_text() -> list[Case]:
    c = "eval-yaml"
    bad_yaml = "config: c.yaml: not valid YAML"
    cases = [
        ("unclosed flow", "experiments: [unclosed\n", bad_yaml),
        ("unterminated string", 'name: "open\nexperiments: []\n', bad_yaml),
        ("tab indentation", "experiments:\n\t- name: a\n", bad_yaml),
        ("key after scalar", "name: a: b\n", bad_yaml),
        ("bad indentation", "name: x\n  experiments: []\n", bad_yaml),
        ("stray bracket", "experiments: ]\n", bad_yaml),
        ("two documents", "name: a\n---\nname: b\n", bad_yaml),
        ("empty file", "", "config: expected a mapping, got NoneType"),
        ("only a comment", "# nothing\n", "config: expected a mapping, got NoneType"),
        ("explicit null", "~\n", "config: expected a mapping, got NoneType"),
        ("top-level scalar", "hello\n", "config: expected a mapping, got str"),
        ("top-level list", "- name: a\n", "config: expected a mapping, got list"),
        ("top-level number", "12\n", "config: expected a mapping, got int"),
        ("latin-1", "name: caf\xe9\n".encode("latin-1"), "not UTF-8 text: byte 0xe9"),
        ("utf-16 with BOM", "name: x\n".encode("utf-16"), "not UTF-8 text: byte 0xff"),
        ("utf-32", "name: x\n".encode("utf-32-le"), "U+0000"),
        ("lone continuation byte", b"name: \x80\n", "not UTF-8 text: byte 0x80"),
        ("overlong encoding", b"name: \xc0\xaf\n", "not UTF-8 text: byte 0xc0"),
        ("encoded surrogate", b"name: \xed\xa0\x80\n", "not UTF-8 text: byte 0xed"),
        ("BOM then a mistake", "\ufeffname: x\n", "config: missing key 'experiments'"),
        ("two BOMs", "\ufeff\ufeffname: x\n", "config: missing key 'experiments'"),
        ("raw NUL", b"name: a\x00b\n", "control characters are not allowed: U+0000"),
        ("escaped NUL", _nav_yaml().replace("name: a", 'name: "a\\0b"'),
         "control character U+0000"),
        ("escaped NUL in a key", 'experiments: []\n"a\\0": 1\n', "control character U+0000"),
        ("escaped bell", 'name: "\\a"\nexperiments: []\n', "control character U+0007"),
        ("escaped DEL", 'name: "\\x7f"\nexperiments: []\n', "control character U+007F"),
        ("C1 control", 'name: "\\x9b"\nexperiments: []\n', "control character U+009B"),
        ("escaped ESC in env id", _nav_yaml().replace(
            "env: bounce_gym/BounceNavigation-v0", 'env: "bounce_gym/\\e[2J"'),
         "control character U+001B"),
        ("lone surrogate", 'name: "\\ud800"\nexperiments: []\n', "invalid Unicode character escape"),
        ("raw vertical tab", "name: a\x0bb\nexperiments: []\n",
         "control characters are not allowed: U+000B"),
        ("5000 deep flow", "experiments: " + "[" * 5000 + "]" * 5000,
         "nest more than 32 deep"),
        ("1500 deep block", "name: x\nexperiments:\n"
         + "".join("  " * k + "-\n" for k in range(1, 1500)), "nest more than 32 deep"),
        ("deep mappings", "experiments: " + "{a: " * 200 + "1" + "}" * 200,
         "nest more than 32 deep"),
        ("deep under env_kwargs", _nav_yaml("  env_kwargs: " + "[" * 40 + "]" * 40 + "\n"),
         "nest more than 32 deep"),
        ("5 MiB", "name: " + "x" * 5 * 2**20, "bytes; at most 4194304 are allowed"),
        ("laughs at the top", f"name: x\nlaughs:\n{laughs(7, '  ')}",
         "more than 120000 nodes with its aliases expanded"),
        ("laughs under env_kwargs", _nav_yaml(f"  env_kwargs:\n    x:\n{laughs(6, '      ')}"),
         "more than 120000 nodes"),
        ("laughs under visibility", _nav_yaml(f"  visibility:\n    x:\n{laughs(6, '      ')}"),
         "more than 120000 nodes"),
        ("laughs under the executor", "executor:\n  x:\n" + laughs(6, "    ") + _nav_yaml(),
         "more than 120000 nodes"),
        ("laughs as seeds", _nav_yaml(seeds="*l5") .replace(
            "experiments:", "x:\n" + laughs(5, "  ") + "experiments:"),
         "more than 120000 nodes"),
        ("laughs of long strings", "x:\n  s0: &s0 '" + "x" * 100_000 + "'\n  s1: &s1 ["
         + ", ".join(["*s0"] * 100) + "]\n  s2: [" + ", ".join(["*s1"] * 100) + "]\n"
         + _nav_yaml(), "more than 4194304 characters of strings"),
        ("self alias", "experiments: &e [*e]\n", "names no anchor before it"),
        ("unknown alias", "experiments: *nowhere\n", "names no anchor before it"),
        ("merge of itself", "a: &a {<<: *a}\nexperiments: []\n", "names no anchor before it"),
        ("duplicate top key", "experiments: []\nexperiments: []\n", "found duplicate key"),
        ("duplicate nested key", _nav_yaml("  policies: [planner]\n"),
         "found duplicate key 'policies'"),
        ("boolean key", "yes: 1\nexperiments: []\n", "found a key that is not a string: True"),
        ("integer key", "1: 1\nexperiments: []\n", "found a key that is not a string: 1"),
        ("null key", "~: 1\nexperiments: []\n", "found a key that is not a string: None"),
        ("list key", "? [a, b]\n: 1\nexperiments: []\n", "config: c.yaml: not valid YAML"),
        ("integer of 5000 digits", _nav_yaml(seeds="[1" + "0" * 5000 + "]"), "is too large; integers lie between"),
        ("hex integer of 5000 digits", _nav_yaml(seeds="[0x" + "f" * 5000 + "]"),
         "is too large; integers lie between"),
        ("sexagesimal integer", _nav_yaml(seeds="[" + ":59" * 3000 + "]").replace(
            "[:", "[1:"), "is too large; integers lie between"),
        ("float of 5000 digits", _nav_yaml("  max_steps: 1." + "1" * 5000 + "\n").replace(
            "  max_steps: 5\n", ""), "max_steps: expected int, got float"),
        ("timestamp name", "name: 2001-12-14\nexperiments: []\n",
         "config.name: expected str, got date"),
        ("binary name", "name: !!binary aGVsbG8=\nexperiments: []\n",
         "config.name: expected str, got bytes"),
        ("set of experiments", "experiments: !!set {a, b}\n",
         "config.experiments: expected list, got set"),
        ("omap output", "output: !!omap [a: 1]\nexperiments: []\n",
         "config.output: expected str, got list"),
        ("local tag", "name: !mine x\nexperiments: []\n", "could not determine a constructor"),
    ]
    out = [eval_case(c, name, text, expect) for name, text, expect in cases]
    payloads = [
        ("os.system", "!!python/object/apply:os.system ['{cmd}']"),
        ("subprocess", "!!python/object/apply:subprocess.call [[sh, -c, '{cmd}']]"),
        ("object new", "!!python/object/new:subprocess.Popen [[sh, -c, '{cmd}']]"),
        ("python name", "!!python/name:os.system"),
        ("python module", "!!python/module:os"),
        ("python object", "!!python/object:os.PathLike {{}}"),
        ("tag in a list", "[1, !!python/object/apply:os.system ['{cmd}']]"),
        ("tag under env_kwargs", None),
        ("tag as a key", "{{? !!python/object/apply:os.system ['{cmd}'] : 1}}"),
        ("verbatim tag", "!<tag:yaml.org,2002:python/object/apply:os.system> ['{cmd}']"),
        ("percent-encoded tag", "!!python/object/apply:os%2Esystem ['{cmd}']"),
        ("tag directive", None),
    ]
    for name, template in payloads:
        def text(box: Sandbox, template=template, name=name) -> str:
            cmd = box.touch_payload()
            if name == "tag under env_kwargs":
                return _nav_yaml("  env_kwargs: {world: !!python/object/apply:os.system "
                                 f"['{cmd}']}}\n")
            if name == "tag directive":
                return (f"%TAG !p! tag:yaml.org,2002:python/object/apply:\n---\n"
                        f"name: !p!os.system ['{cmd}']\nexperiments: []\n")
            return f"name: {template.format(cmd=cmd)}\n" + _nav_yaml()
        out.append(eval_case(c, f"payload: {name}", text,
                             "could not determine a constructor for the tag"))
    return out


# -- evaluation configurations: the content --------------------------------------------------
def _config_content() -> list[Case]:
    c = "eval-config"
    x = "config.experiments[0]"
    long_name = "x" * 101
    cases = [
        ("missing experiments", {"name": "x"}, "config: missing key 'experiments'"),
        ("no experiments", evaluation(experiments=[]), "expected at least one experiment"),
        ("experiments a mapping", evaluation(experiments={"a": 1}),
         "config.experiments: expected list, got dict"),
        ("experiment a number", evaluation(experiments=[3]),
         f"{x}: expected a mapping, got int"),
        ("unknown top key", evaluation(colour=1), "config: unknown keys ['colour']"),
        ("unknown experiment key", evaluation(experiment(colour=1)),
         f"{x}: unknown keys ['colour']"),
        ("experiment without env", evaluation(experiment(env=None)),
         f"{x}: missing key 'env'"),
        ("experiment without name", evaluation(experiment(name=None)),
         f"{x}: missing key 'name'"),
        ("name a number", evaluation(name=3), "config.name: expected str, got int"),
        ("name empty", evaluation(name=""), "config.name: expected a name for the run folder"),
        ("name escapes", evaluation(name="../../ESCAPED"), "it contains '/'"),
        ("name a path", evaluation(name="a/b"), "it contains '/'"),
        ("name backslash", evaluation(name="a\\b"), "it contains '\\\\'"),
        ("name dot", evaluation(name="."), "it starts with '.'"),
        ("name dot dot", evaluation(name=".."), "it starts with '.'"),
        ("name hidden", evaluation(name=".hidden"), "it starts with '.'"),
        ("name an option", evaluation(name="-rf"), "it starts with '-'"),
        ("name padded", evaluation(name=" x "), "it starts or ends with a space"),
        ("name 101 bytes", evaluation(name=long_name), "it is 101 bytes long, at most 100"),
        ("name 120 bytes of accents", evaluation(name="é" * 60), "it is 120 bytes long"),
        ("name 10000 characters", evaluation(name="x" * 10_000), "it is 10000 bytes long"),
        ("name with a newline", evaluation(name="two\nlines"),
         "control character U+000A"),
        ("name with a right-to-left override", evaluation(name="a\u202eb"),
         "control character U+202E"),
        ("name with a zero-width space", evaluation(name="a\u200bb"),
         "control character U+200B"),
        ("name with a line separator", evaluation(name="a\u2028b"),
         "control character U+2028"),
        ("experiment name escapes", evaluation(experiment(name="../x")),
         f"{x}.name: expected a name for the plot files"),
        ("experiment name twice", evaluation(experiment(), experiment()),
         "config.experiments[1].name: 'a' is used twice"),
        ("output a file", lambda box: box.write("out", "a file") and evaluation(output="out"),
         "config.output: cannot write into 'out'"),
        ("output below a file", lambda box: box.write("out", "a file") and evaluation(
            output="out/runs"), "config.output: cannot write into 'out/runs'"),
        ("output a device", evaluation(output="/dev/null"),
         "config.output: cannot write into '/dev/null'"),
        ("output a number", evaluation(output=3), "config.output: expected str, got int"),
        ("models a number", evaluation(models=[]), "config.models: expected str, got list"),
        ("leaderboard a string", evaluation(leaderboard="yes"),
         "config.leaderboard: expected bool, got str"),
        ("executor a list", evaluation(executor=[1]), "config.executor: expected dict"),
        ("executor unknown key", evaluation(executor={"cores": 2}),
         "config.executor: unknown keys ['cores']"),
        ("executor kind", evaluation(executor={"kind": "slurm"}),
         "config.executor.kind: expected one of ('local', 'ray')"),
        ("executor workers huge", evaluation(executor={"workers": 10**9}),
         "config.executor.workers: expected an integer in [1, 1024]"),
        ("executor workers bool", evaluation(executor={"workers": True}),
         "config.executor.workers: expected an integer"),
        ("executor retries negative", evaluation(executor={"retries": -1}),
         "config.executor.retries: expected an integer in [0, 100]"),
        ("executor address for local", evaluation(executor={"address": "h:1"}),
         "config.executor.address: only for the ray executor"),
        ("executor address garbage", evaluation(executor={"kind": "ray", "address": "::"}),
         "config.executor.address: expected a Ray address"),
        ("unknown env id", evaluation(experiment(env="bounce_gym/Nothing-v0")),
         f"{x}.env: unknown environment id 'bounce_gym/Nothing-v0'"),
        ("a Gymnasium env of another package", evaluation(experiment(env="CartPole-v1")),
         f"{x}.env: unknown environment id 'CartPole-v1'"),
        ("env id a list", evaluation(experiment(env=["a"])), f"{x}.env: expected str"),
        ("env_kwargs a list", evaluation(experiment(env_kwargs=[1])),
         f"{x}.env_kwargs: expected dict"),
        ("unknown env argument", evaluation(experiment(env_kwargs={"colour": 1})),
         f"{x}.env_kwargs: BounceEnv() got an unexpected keyword argument 'colour'"),
        ("unknown world", evaluation(experiment(env_kwargs={"world": "atlantis"})),
         f"{x}.env_kwargs: world: unknown world 'atlantis'"),
        ("world a number", evaluation(experiment(env_kwargs={"world": 3})),
         f"{x}.env_kwargs: world: expected a zoo name"),
        ("missing map file", evaluation(experiment(env_kwargs={"world": "nowhere.json"})),
         f"{x}.env_kwargs: world: map file 'nowhere.json' does not exist"),
        ("angles a string", evaluation(experiment(env_kwargs={**NAV, "angles": "x"})),
         f"{x}.env_kwargs: angles: expected a list"),
        ("angles empty", evaluation(experiment(env_kwargs={**NAV, "angles": []})),
         f"{x}.env_kwargs: angles: the set of bounce angles is empty"),
        ("angles NaN", _nav_yaml("  env_kwargs: {world: square, angles: [.nan]}\n"),
         f"{x}.env_kwargs: angles[0]: expected a finite number, got nan"),
        ("angles inf", _nav_yaml("  env_kwargs: {world: square, angles: [.inf]}\n"),
         f"{x}.env_kwargs: angles[0]: expected a finite number, got inf"),
        ("history negative", evaluation(experiment(env_kwargs={**NAV, "history": -1})),
         f"{x}.env_kwargs: history: expected an integer in [0, 10000]"),
        ("history huge", evaluation(experiment(env_kwargs={**NAV, "history": 10**12})),
         f"{x}.env_kwargs: history: expected an integer in [0, 10000]"),
        ("step_length 1e12", evaluation(experiment(env_kwargs={**NAV, "step_length": 1e12})),
         f"{x}.env_kwargs: step_length: expected a length in [0.00141, 14.1]"),
        ("coverage cell_size 1e-3", evaluation(experiment(
            env="bounce_gym/BounceCoverage-v0", env_kwargs={"task_kwargs": {"cell_size": 1e-3}},
            max_steps=None, horizon_reason=None)),
         f"{x}.env_kwargs: task_kwargs.cell_size: expected a length in"),
        ("backend unknown", evaluation(experiment(env_kwargs={**NAV, "backend": "quantum"})),
         f"{x}.env_kwargs: backend: expected one of"),
        ("task_kwargs unknown", evaluation(experiment(env_kwargs={**NAV, "task_kwargs": {
            "colour": 1}})), f"{x}.env_kwargs: task_kwargs for 'navigation'"),
        ("noise unknown", evaluation(experiment(env_kwargs={**NAV, "noise": {"type": "x"}})),
         f"{x}.env_kwargs: noise.type: unknown noise model 'x'"),
        ("env_kwargs sets the horizon", evaluation(experiment(env_kwargs={
            "max_episode_steps": 3})), f"{x}.env_kwargs.max_episode_steps: not allowed"),
        ("robots a billion", evaluation(experiment(env="bounce_gym/MultiBounce-v0",
                                                   env_kwargs={"n_robots": 10**9})),
         f"{x}.env_kwargs: n_robots: expected an integer in [1, 10000]"),
        ("multi-robot sets max_cycles", evaluation(experiment(
            env="bounce_gym/MultiBounce-v0", env_kwargs={"max_cycles": 3})),
         f"{x}.env_kwargs.max_cycles: not allowed"),
        ("seeds: ten billion", evaluation(experiment(seeds={"start": 10_000,
                                                           "count": 10**10})),
         f"{x}.seeds.count: expected an integer in [1, 100000]"),
        ("seeds: past the largest", evaluation(experiment(seeds={"start": 2**32 - 2,
                                                                "count": 5})),
         f"{x}.seeds.count: expected an integer in [1, 2]"),
        ("seeds: start huge", evaluation(experiment(seeds={"start": 2**70, "count": 1})),
         f"{x}.seeds.start: expected an integer in [10000, 4294967295]"),
        ("seeds: start a string", evaluation(experiment(seeds={"start": "a", "count": 1})),
         f"{x}.seeds.start: expected int, got str"),
        ("seeds: count zero", evaluation(experiment(seeds={"start": 10_000, "count": 0})),
         f"{x}.seeds.count: expected an integer in [1, 100000], got 0"),
        ("seeds: count a bool", evaluation(experiment(seeds={"start": 10_000, "count": True})),
         f"{x}.seeds.count: expected an integer"),
        ("seeds: unknown key", evaluation(experiment(seeds={"start": 10_000, "count": 1,
                                                           "step": 2})),
         f"{x}.seeds: unknown keys ['step']"),
        ("seeds: count missing", evaluation(experiment(seeds={"start": 10_000})),
         f"{x}.seeds: missing key 'count'"),
        ("seeds: one duplicate among 100000", evaluation(experiment(
            seeds=[*range(10_000, 109_999), 50_000])),
         f"{x}.seeds: every seed once (an episode counts once), repeated: [50000]"),
        ("seeds: 100001", evaluation(experiment(seeds=list(range(10_000, 110_001)))),
         f"{x}.seeds: at most 100000 seeds, got 100001"),
        ("seeds: negative", evaluation(experiment(seeds=[-1])),
         f"{x}.seeds: evaluation seeds must be >= 10000"),
        ("seeds: training seeds", evaluation(experiment(seeds=[0, 1])),
         f"{x}.seeds: evaluation seeds must not overlap the training seeds [0, 9000)"),
        ("seeds: above 2**32", evaluation(experiment(seeds=[2**32])),
         f"{x}.seeds: evaluation seeds must be <= 4294967295"),
        ("seeds: a bool", evaluation(experiment(seeds=[True])),
         f"{x}.seeds: expected a non-empty list of integers"),
        ("seeds: a float", evaluation(experiment(seeds=[10_000.5])),
         f"{x}.seeds: expected a non-empty list of integers"),
        ("seeds: empty", evaluation(experiment(seeds=[])),
         f"{x}.seeds: expected a non-empty list of integers"),
        ("seeds: a string", evaluation(experiment(seeds="10000")),
         f"{x}.seeds: expected list or dict, got str"),
        ("seeds: nested", evaluation(experiment(seeds=[[10_000]])),
         f"{x}.seeds: expected a non-empty list of integers"),
        ("max_steps zero", evaluation(experiment(max_steps=0)),
         f"{x}.max_steps: expected an integer in [1, 1000000], got 0"),
        ("max_steps a billion", evaluation(experiment(max_steps=10**9)),
         f"{x}.max_steps: expected an integer in [1, 1000000]"),
        ("max_steps a bool", evaluation(experiment(max_steps=True)),
         f"{x}.max_steps: expected an integer in [1, 1000000], got True"),
        ("max_steps without a reason", evaluation(experiment(horizon_reason=None)),
         f"{x}.max_steps: 5 differs from the horizon 200"),
        ("blank horizon_reason", evaluation(experiment(horizon_reason="  ")),
         f"{x}.horizon_reason: expected a non-empty explanation"),
        ("unknown policy", evaluation(experiment(policies=["genius"])),
         f"{x}.policies: unknown ['genius']"),
        ("policies a string", evaluation(experiment(policies="random")),
         f"{x}.policies: expected list, got str"),
        ("no policies", evaluation(experiment(policies=[])),
         f"{x}.policies: expected a non-empty list"),
        ("a policy twice", evaluation(experiment(policies=["random", "random"])),
         f"{x}.policies: each policy once"),
        ("policy a mapping", evaluation(experiment(policies=[{"rl": 1}])),
         f"{x}.policies[0]: expected str, got dict"),
        ("adversaries without patrol", evaluation(experiment(adversaries=["rl"])),
         f"{x}.adversaries: navigation experiments have no adversaries"),
        ("patrol adversary unknown", evaluation(experiment(
            env="bounce_gym/Patrol-v0", env_kwargs={}, max_steps=None, horizon_reason=None,
            policies=["random"], adversaries=["god"])), f"{x}.adversaries: unknown ['god']"),
        ("patrol adversary twice", evaluation(experiment(
            env="bounce_gym/Patrol-v0", env_kwargs={}, max_steps=None, horizon_reason=None,
            policies=["random"], adversaries=["best_response"] * 2)),
         f"{x}.adversaries: each adversary once"),
        ("difficulty unknown", evaluation(experiment(difficulty="nightmare")),
         f"{x}.difficulty: expected one of ('easy', 'medium', 'hard')"),
        ("planner_kwargs on one robot", evaluation(experiment(
            env="bounce_gym/Bounce-v0", env_kwargs={}, planner_kwargs={"phi": 1})),
         f"{x}.planner_kwargs: bouncing experiments take no planner options"),
        ("navigation planner_kwargs unknown", evaluation(experiment(planner_kwargs={"phi": 1})),
         "planner_kwargs: unknown ['phi']"),
        ("visibility on several robots", evaluation(experiment(
            env="bounce_gym/MultiBounce-v0", env_kwargs={}, visibility={})),
         f"{x}.visibility: only for single-robot experiments"),
        ("rl_models escapes", evaluation(experiment(policies=["rl"], rl_models="../x")),
         f"{x}.rl_models: expected the name of a folder in models/"),
        ("rl_models absolute", evaluation(experiment(policies=["rl"], rl_models="/etc")),
         f"{x}.rl_models: expected the name of a folder in models/"),
        ("rl_models empty list", evaluation(experiment(policies=["rl"], rl_models=[])),
         f"{x}.rl_models: expected a folder name or a non-empty list"),
        ("rl_models twice", evaluation(experiment(policies=["rl"], rl_models=["m", "m"])),
         f"{x}.rl_models: a folder is named twice"),
        ("rl_models a number", evaluation(experiment(policies=["rl"], rl_models=[3])),
         f"{x}.rl_models[0]: expected a folder name or {{folder, env_kwargs}}"),
        ("rl_models entry without folder", evaluation(experiment(
            policies=["rl"], rl_models=[{"env_kwargs": {}}])),
         f"{x}.rl_models[0]: missing key 'folder'"),
        ("rl_models entry changes the world", evaluation(experiment(
            policies=["rl"], rl_models=[{"folder": "m", "env_kwargs": {"world": "x"}}])),
         f"{x}.rl_models[0].env_kwargs: only observation options"),
        ("rl_models folder hidden", evaluation(experiment(
            policies=["rl"], rl_models=[{"folder": ".m"}])),
         f"{x}.rl_models[0].folder: expected the name of a folder in models/"),
    ]
    out = [eval_case(c, name, content, expect) for name, content, expect in cases]
    out.append(eval_case(c, "units folder a planted link", _units_link, "config.output: "
                         "out/runs/run-units is a symbolic link"))
    return out


def _units_link(box: Sandbox) -> dict:
    """A valid evaluation whose units folder is a link planted to a folder elsewhere."""
    box.write("elsewhere/keep", "untouched")
    (box.here / "out/runs").mkdir(parents=True)
    (box.here / "out/runs/run-units").symlink_to(box.here / "elsewhere")
    return evaluation()


def _monitor_link(box: Sandbox) -> dict:
    """A training run whose monitor file is a link planted to a file elsewhere."""
    box.write("elsewhere", "untouched")
    (box.here / "out/models/nav").mkdir(parents=True)
    (box.here / "out/models/nav/ppo_seed0.monitor.csv").symlink_to(box.here / "elsewhere")
    return training()


# -- training configurations ------------------------------------------------------------------
def training(**overrides) -> dict:
    """A small PPO training configuration saving into ``out/models``; None leaves a key out."""
    config = {"name": "nav", "env": NAVIGATION, "env_kwargs": dict(NAV), "algo": "ppo",
              "total_timesteps": 64, "n_envs": 1, "models": "out/models",
              "hyperparams": {"n_steps": 32, "batch_size": 32}, **overrides}
    return {k: v for k, v in config.items() if v is not None}


def train_case(name: str, content, expect: str, *flags: str, files: dict | None = None,
               **options) -> Case:
    """``bounce-gym train t.yaml`` of ``content`` (a mapping or text), with ``files`` (name ->
    text, bytes or mapping) beside it."""
    def build(box: Sandbox) -> list[str]:
        for file_name, file_content in (files or {}).items():
            file_content = file_content(box) if callable(file_content) else file_content
            if isinstance(file_content, dict):
                box.yaml(file_name, file_content)
            else:
                box.write(file_name, file_content)
        text = content(box) if callable(content) else content
        if isinstance(text, dict):
            box.yaml("t.yaml", text)
        else:
            box.write("t.yaml", text)
        return ["train", "t.yaml", "--no-progress", *flags]
    return Case("training", name, build, expect, **options)


def _hp(**hyperparams) -> dict:
    return training(hyperparams={"n_steps": 32, "batch_size": 32, **hyperparams})


def _training() -> list[Case]:
    threads = 4 * (os.cpu_count() or 1)
    entry = {NAVIGATION: {"n_timesteps": 64}}
    hp_file = training(hyperparams_file="hp.yaml")
    text = ("name: nav\nenv: bounce_gym/BounceNavigation-v0\nalgo: ppo\ntotal_timesteps: 64\n"
            "models: out/models\n")
    cases = [
        train_case("gamma 5", _hp(gamma=5), "config.hyperparams.gamma: expected a number in "
                                            "(0, 1], got 5"),
        train_case("gamma zero", _hp(gamma=0), "config.hyperparams.gamma: expected a number"),
        train_case("gamma a string", _hp(gamma="0.99"), "config.hyperparams.gamma: expected a "
                                                        "number"),
        train_case("learning rate NaN", text + "hyperparams: {learning_rate: .nan}\n",
                   "config.hyperparams.learning_rate: expected a finite number, got nan"),
        train_case("learning rate inf", text + "hyperparams: {learning_rate: .inf}\n",
                   "config.hyperparams.learning_rate: expected a finite number, got inf"),
        train_case("learning rate -inf", text + "hyperparams: {learning_rate: -.inf}\n",
                   "config.hyperparams.learning_rate: expected a finite number"),
        train_case("learning rate negative", _hp(learning_rate=-1e-3),
                   "config.hyperparams.learning_rate: expected a number > 0"),
        train_case("schedule lin_x", _hp(learning_rate="lin_x"),
                   "config.hyperparams.learning_rate: expected lin_<number>, got 'lin_x'"),
        train_case("schedule lin_", _hp(learning_rate="lin_"),
                   "config.hyperparams.learning_rate: expected lin_<number>"),
        train_case("schedule lin_-1", _hp(learning_rate="lin_-1"),
                   "config.hyperparams.learning_rate: expected lin_<number>"),
        train_case("schedule lin_1e999", _hp(learning_rate="lin_1e999"),
                   "expected a finite number, got inf"),
        train_case("schedule lin_0", _hp(clip_range="lin_0"),
                   "config.hyperparams.clip_range (the start of its lin_ schedule): expected "
                   "a number > 0"),
        train_case("schedule on n_epochs", _hp(n_epochs="lin_3"),
                   "config.hyperparams.n_epochs: a lin_ schedule is allowed only for"),
        train_case("schedule of 5000 digits", _hp(learning_rate="lin_" + "9" * 5000),
                   "config.hyperparams.learning_rate"),
        train_case("torch_threads a million", training(torch_threads=1_000_000),
                   f"config.torch_threads: expected an integer in [1, {threads}]"),
        train_case("torch_threads negative", training(torch_threads=-4),
                   f"config.torch_threads: expected an integer in [1, {threads}]"),
        train_case("torch_threads zero", training(torch_threads=0),
                   "config.torch_threads: expected an integer"),
        train_case("n_envs zero", training(n_envs=0), "config.n_envs: expected an integer in "
                                                      "[1, 1024], got 0"),
        train_case("n_envs a million", training(n_envs=10**6), "config.n_envs: expected an "
                                                               "integer in [1, 1024]"),
        train_case("n_envs a float", training(n_envs=2.0), "config.n_envs: expected int, got "
                                                           "float"),
        train_case("total_timesteps zero", training(total_timesteps=0),
                   "config.total_timesteps: expected an integer in [1, 10000000000], got 0"),
        train_case("total_timesteps 10**30", training(total_timesteps=10**30),
                   "config.total_timesteps: expected an integer in [1, 10000000000]"),
        train_case("total_timesteps a string", training(total_timesteps="many"),
                   "config.total_timesteps: expected int, got str"),
        train_case("--timesteps negative", training(), "config.total_timesteps: expected an "
                                                       "integer in [1, 10000000000], got -5",
                   "--timesteps", "-5"),
        train_case("--seeds negative", training(), "config.seeds: expected a non-empty list "
                                                   "of distinct integers >= 0", "--seeds", "-1"),
        train_case("--seeds twice", training(), "config.seeds: expected a non-empty list of "
                                                "distinct integers", "--seeds", "1", "1"),
        train_case("seed into the evaluation seeds", training(seed=9_999, n_envs=2),
                   "config.seeds: seed 9999 with n_envs 2 would seed envs up to 10000"),
        train_case("seed and seeds", training(seed=0, seeds=[1]),
                   "config.seeds: give either seed"),
        train_case("seeds with a bool", training(seeds=[True]),
                   "config.seeds: expected a non-empty list of distinct integers"),
        train_case("seed a string", training(seed="0"), "config.seed: expected int, got str"),
        train_case("n_stack zero", training(n_stack=0), "config.n_stack: expected an integer "
                                                        "in [1, 100], got 0"),
        train_case("checkpoint_every negative", training(checkpoint_every=-1),
                   "config.checkpoint_every: expected an integer in [0, 10000000000]"),
        train_case("normalize clip NaN", text + "normalize: {clip_obs: .nan}\n",
                   "config.normalize.clip_obs: expected a finite number, got nan"),
        train_case("normalize unknown", training(normalize={"clip": 1}),
                   "config.normalize: unknown keys ['clip']"),
        train_case("normalize a number", training(normalize=1),
                   "config.normalize: expected bool or dict, got int"),
        train_case("unknown key", training(colour=1), "config: unknown keys ['colour']"),
        train_case("missing algo", training(algo=None), "config: missing key 'algo'"),
        train_case("algo unknown", training(algo="a2c"), "config.algo: expected one of "
                   "('ppo', 'dqn', 'recurrentppo', 'jax_ppo', 'jax_dqn', 'ippo', 'mappo')"),
        train_case("env unknown", training(env="bounce_gym/Nothing-v0"),
                   "config.env: unknown environment id"),
        train_case("env of another package", training(env="CartPole-v1"),
                   "config.env: unknown environment id 'CartPole-v1'"),
        train_case("vec_env unknown", training(vec_env="threads"),
                   "config.vec_env: expected one of ('native', 'sync', 'subproc')"),
        train_case("variant with a space", training(variant="Stack 4"),
                   "config.variant: expected lower-case letters and digits"),
        train_case("variant escapes", training(variant="../x"),
                   "config.variant: expected lower-case letters and digits"),
        train_case("name escapes", training(name="../../ESCAPED"),
                   "config.name: expected the name of a folder in models/"),
        train_case("name empty", training(name=""), "config.name: expected the name of a "
                                                    "folder in models/"),
        train_case("name 101 bytes", training(name="x" * 101), "it is 101 bytes long"),
        train_case("name with a newline", training(name="a\nb"),
                   "it contains the control character U+000A"),
        train_case("models a file", lambda box: box.write("out/f", "x") and training(
            models="out/f/m"), "config.models: cannot write into", writes="out"),
        train_case("models /dev/null", training(models="/dev/null"),
                   "config.models: cannot write into"),
        train_case("role without patrol", training(role="adversary"),
                   "config.role: only bounce_gym/Patrol-v0 has roles"),
        train_case("dqn on continuous actions", training(
            algo="dqn", env_kwargs={"world": "square", "action_type": "continuous"},
            hyperparams={}),
            "config.algo: dqn needs discrete actions"),
        train_case("unknown hyperparameter", _hp(colour=1),
                   "config.hyperparams.colour: not a hyperparameter of PPO"),
        train_case("hyperparameter device", _hp(device="cuda:99"),
                   "config.hyperparams.device: not a hyperparameter of PPO"),
        train_case("n_steps zero", _hp(n_steps=0), "config.hyperparams.n_steps: expected an "
                                                   "integer in [1, 1000000], got 0"),
        train_case("batch_size 2.5", _hp(batch_size=2.5), "config.hyperparams.batch_size: "
                                                          "expected an integer"),
        train_case("n_epochs a billion", _hp(n_epochs=10**9), "config.hyperparams.n_epochs: "
                                                              "expected an integer in [1, 1000]"),
        train_case("rollout 10**8", training(n_envs=1000, hyperparams={"n_steps": 100_000}),
                   "config.hyperparams.n_steps: n_steps x n_envs is a rollout of 100000000"),
        train_case("buffer 10**12", training(algo="dqn", hyperparams={"buffer_size": 10**12}),
                   "config.hyperparams.buffer_size: expected an integer in [1, 10000000]"),
        train_case("policy_kwargs a list", _hp(policy_kwargs=[1]),
                   "config.hyperparams.policy_kwargs: expected a mapping"),
        train_case("policy_kwargs activation eval", _hp(policy_kwargs={
            "activation_fn": "__import__('os').system('x')"}),
            "config.hyperparams.policy_kwargs.activation_fn: expected one of"),
        train_case("net_arch 10**9 wide", _hp(policy_kwargs={"net_arch": [10**9]}),
                   "config.hyperparams.policy_kwargs.net_arch[0]: expected an integer in "
                   "[1, 4096]"),
        train_case("net_arch 1000 deep", _hp(policy_kwargs={"net_arch": [8] * 1000}),
                   "config.hyperparams.policy_kwargs.net_arch: expected a list of at most 16"),
        train_case("net_arch NaN", text + "hyperparams: {policy_kwargs: {net_arch: [.nan]}}\n",
                   "config.hyperparams.policy_kwargs.net_arch[0]: expected a finite number"),
        train_case("net_arch unknown key", _hp(policy_kwargs={"net_arch": {"actor": [8]}}),
                   "config.hyperparams.policy_kwargs.net_arch: unknown keys ['actor']"),
        train_case("lstm huge", training(algo="recurrentppo", hyperparams={
            "policy_kwargs": {"lstm_hidden_size": 10**6}}),
            "config.hyperparams.policy_kwargs.lstm_hidden_size: expected an integer in"),
        train_case("unknown policy_kwargs", _hp(policy_kwargs={"colour": 1}),
                   "config.hyperparams"),
        train_case("hyperparams_file missing", hp_file, "config.hyperparams_file: file '"),
        train_case("hyperparams_file a folder", hp_file, "is not a file",
                   files={"hp.yaml/x": "a"}),
        train_case("hyperparams_file a device", training(hyperparams_file="/dev/zero"),
                   "config.hyperparams_file: file '/dev/zero' is not a file"),
        train_case("hyperparams_file a pipe", lambda box: os.mkfifo(box.here / "hp.yaml")
                   or hp_file, "config.hyperparams_file: file '"),
        train_case("hyperparams_file not UTF-8", hp_file, "not UTF-8 text",
                   files={"hp.yaml": b"\xff\xfe"}),
        train_case("hyperparams_file a bomb", hp_file, "more than 120000 nodes",
                   files={"hp.yaml": f"{NAVIGATION}:\n  x:\n{laughs(7)}"}),
        train_case("hyperparams_file too deep", hp_file, "nest more than 32 deep",
                   files={"hp.yaml": "a: " + "[" * 100 + "]" * 100}),
        train_case("hyperparams_file 5 MiB", hp_file, "bytes; at most 4194304 are allowed",
                   files={"hp.yaml": "a: " + "x" * 5 * 2**20}),
        train_case("hyperparams_file a payload", hp_file, "could not determine a constructor",
                   files={"hp.yaml": lambda box: f"{NAVIGATION}:\n  gamma: !!python/object/"
                                                 f"apply:os.system ['{box.touch_payload()}']\n"}),
        train_case("hyperparams_file a list", hp_file, "has no entry for",
                   files={"hp.yaml": "[1, 2]\n"}),
        train_case("hyperparams_file entry a number", hp_file, "is not a mapping",
                   files={"hp.yaml": {NAVIGATION: 3}}),
        train_case("hyperparams_file wrong policy", hp_file, "names policy 'CnnPolicy'",
                   files={"hp.yaml": {NAVIGATION: {"policy": "CnnPolicy"}}}),
        train_case("hyperparams_file gamma 5", hp_file, "config.hyperparams.gamma: expected a "
                   "number in (0, 1], got 5", files={"hp.yaml": {NAVIGATION: {"gamma": 5}}}),
        train_case("hyperparams_file policy_kwargs string", hp_file,
                   "config.hyperparams.policy_kwargs: expected a mapping",
                   files={"hp.yaml": {NAVIGATION: {"policy_kwargs": "dict(net_arch=[64])"}}}),
        train_case("hyperparams_file normalize string", hp_file,
                   "config.normalize: expected bool or dict, got str",
                   files={"hp.yaml": {NAVIGATION: {"normalize": "dict(norm_obs=True)"}}}),
        train_case("hyperparams_file n_timesteps float", training(
            hyperparams_file="hp.yaml", total_timesteps=None),
                   "config.total_timesteps: expected int, got float",
                   files={"hp.yaml": {NAVIGATION: {"n_timesteps": 1.5}}}),
        train_case("hyperparams_file n_envs huge", training(hyperparams_file="hp.yaml",
                                                            n_envs=None),
                   "config.n_envs: expected an integer in [1, 1024]",
                   files={"hp.yaml": {NAVIGATION: {**entry[NAVIGATION], "n_envs": 10**6}}}),
        train_case("--resume with nothing", training(), "config.resume: nothing to resume",
                   "--resume"),
        train_case("monitor file a planted link", _monitor_link, "is a symbolic link"),
    ]
    return cases


# -- tune ------------------------------------------------------------------------------------
def tune_case(name: str, space: str, expect: str, *flags: str, config: dict | None = None,
              **options) -> Case:
    def build(box: Sandbox) -> list[str]:
        box.yaml("t.yaml", config if config is not None else training())
        box.write("space.yaml", space)
        return ["tune", "t.yaml", "--space", "space.yaml", "--no-progress", *flags]
    return Case("tune", name, build, expect, **options)


def _tune() -> list[Case]:
    ok = "gamma: {uniform: [0.9, 0.99]}\n"
    bounds = "expected [low, high]"
    return [
        tune_case("randint beyond int64", "n_epochs: {randint: [0, " + "9" * 30 + "]}", bounds),
        tune_case("randint below int64", f"n_epochs: {{randint: [-{2**64}, 3]}}", bounds),
        tune_case("randint of floats", "n_epochs: {randint: [1.5, 3]}", bounds),
        tune_case("randint empty", "n_epochs: {randint: [3, 3]}", bounds),
        tune_case("randint reversed", "n_epochs: {randint: [9, 3]}", bounds),
        tune_case("randint out of range", "n_epochs: {randint: [0, 10]}",
                  "search.n_epochs.randint[0]: expected an integer in [1, 1000], got 0"),
        tune_case("randint three bounds", "n_epochs: {randint: [1, 2, 3]}", bounds),
        tune_case("uniform beyond gamma", "gamma: {uniform: [0.9, 1.5]}",
                  "search.gamma.uniform[1]: expected a number in (0, 1], got 1.5"),
        tune_case("uniform NaN", "gamma: {uniform: [.nan, 0.9]}", bounds),
        tune_case("uniform strings", "gamma: {uniform: ['0.9', '0.99']}", bounds),
        tune_case("uniform bools", "gamma: {uniform: [false, true]}", bounds),
        tune_case("loguniform from zero", "learning_rate: {loguniform: [0, 1.0e-3]}", bounds),
        tune_case("loguniform to inf", "learning_rate: {loguniform: [1.0e-5, .inf]}", bounds),
        tune_case("two distributions", "gamma: {uniform: [0.9, 0.99], choice: [0.9]}",
                  "search.gamma: expected one of"),
        tune_case("unknown distribution", "gamma: {normal: [0.9, 0.01]}",
                  "search.gamma: expected one of"),
        tune_case("distribution a number", "gamma: 0.9", "search.gamma: expected one of"),
        tune_case("empty choice", "n_steps: {choice: []}", "search.n_steps.choice: expected a "
                                                          "list of 1 to 10000 values, got 0"),
        tune_case("huge choice", "batch_size: {choice: [" + ", ".join(["64"] * 10_001) + "]}",
                  "search.batch_size.choice: expected a list of 1 to 10000 values, got 10001"),
        tune_case("choice a string", "n_steps: {choice: '64'}", "search.n_steps.choice: "
                                                               "expected a list"),
        tune_case("choice out of range", "gamma: {choice: [0.9, 2]}",
                  "search.gamma.choice[1]: expected a number in (0, 1]"),
        tune_case("choice a laugh", f"policy_kwargs:\n  choice:\n{laughs(7)}",
                  "more than 120000 nodes with its aliases expanded"),
        tune_case("choice of huge net_arch", "policy_kwargs: {choice: [{net_arch: [100000]}]}",
                  "search: trial 0"),
        tune_case("unknown hyperparameter", "colour: {choice: [1, 2]}", "search: trial 0"),
        tune_case("empty space", "{}\n", "must map hyperparameter names to distributions"),
        tune_case("space a list", "[1]\n", "must map hyperparameter names to distributions"),
        tune_case("space missing", ok, "search: file 'nowhere.yaml' does not exist",
                  "--space", "nowhere.yaml"),
        tune_case("space not UTF-8", b"gamma: \xff", "search: space.yaml: not UTF-8 text"),
        tune_case("space a payload", "gamma: !!python/object/apply:os.system ['true']",
                  "could not determine a constructor"),
        tune_case("--trials a billion", ok, "--trials: expected an integer in [1, 10000], "
                                            "got 1000000000", "--trials", "1000000000"),
        tune_case("--trials zero", ok, "--trials: expected an integer in [1, 10000], got 0",
                  "--trials", "0"),
        tune_case("--trials -1", ok, "--trials: expected an integer", "--trials", "-1"),
        tune_case("--trials many", ok, "argument --trials: invalid int value: 'many'",
                  "--trials", "many"),
        tune_case("--seed -1", ok, "--seed: expected an integer in [0, 4294967295]",
                  "--seed", "-1"),
        tune_case("--seed 2**64", ok, "--seed: expected an integer in [0, 4294967295]",
                  "--seed", str(2**64)),
        tune_case("--workers 0", ok, "--workers: expected an integer in [1, 1024], got 0",
                  "--workers", "0"),
        tune_case("--workers -1", ok, "--workers: expected an integer in [1, 1024], got -1",
                  "--workers", "-1"),
        tune_case("--workers x", ok, "argument --workers: invalid int value: 'x'",
                  "--workers", "x"),
        tune_case("--metric bogus", ok, "--metric: expected one of ['return', 'success'], got "
                                        "'bogus'", "--metric", "bogus"),
        tune_case("--scheduler bogus", ok, "--scheduler: expected one of ['fifo', 'asha']",
                  "--scheduler", "bogus"),
        tune_case("--address ray://256.1.1.1:1", ok, "--address: expected a Ray address",
                  "--address", "ray://256.1.1.1:1"),
        tune_case("bad training config", ok, "config.hyperparams.n_epochs: expected an integer",
                  config=_hp(n_epochs=10**9)),
        tune_case("training name 96 bytes", ok, "config.name: a search saves into "
                  "models/<name>-tune, so the name may have at most 95 bytes; it has 96",
                  config=training(name="n" * 96)),
        tune_case("training name 100 bytes", ok, "config.name: a search saves into "
                  "models/<name>-tune, so the name may have at most 95 bytes; it has 100",
                  config=training(name="é" * 50)),
        tune_case("training name 101 bytes", ok, "config.name: expected the name of a folder",
                  config=training(name="n" * 101)),
    ]


# -- flags -----------------------------------------------------------------------------------
def _arguments(box: Sandbox, argv: list[str]) -> list[str]:
    """``argv`` after a valid evaluation configuration ``c.yaml``, a valid training
    configuration ``t.yaml``, user folders with a short key, a key others can read, a pipe
    for a key, a folder anyone may write into, and a file to trust are written (``{c}``,
    ``{t}`` and ``{here}`` in ``argv`` name them)."""
    box.yaml("c.yaml", evaluation(executor=None))
    box.yaml("t.yaml", training())
    box.write("short-key/secret.key", b"short")
    (box.here / "short-key/secret.key").chmod(0o600)  # private: the length is what is wrong
    box.write("open-key/secret.key", os.urandom(32))  # readable by all (umask 022: 0644)
    (box.here / "open-key/secret.key").chmod(0o644)
    box.write("open-home/secret.key", os.urandom(32))
    (box.here / "open-home/secret.key").chmod(0o600)
    (box.here / "open-home").chmod(0o777)  # anyone may plant a key
    (box.here / "pipe-key").mkdir(mode=0o700)
    os.mkfifo(box.here / "pipe-key/secret.key", 0o600)  # reading it would wait for ever
    box.write("ppo_seed0.zip", b"a file to trust")
    return [arg.format(c="c.yaml", t="t.yaml", here=box.here) for arg in argv]


def _flag_case(name: str, argv: list[str], expect: str, **options) -> Case:
    return Case("flags", name, lambda box: _arguments(box, argv), expect, **options)


def _flags() -> list[Case]:
    no_ray = (("RAY_ADDRESS", None), ("RAY_TMPDIR", "{here}"))
    cases = [
        ("--workers 0", ["evaluate", "{c}", "--workers", "0"],
         "--workers: expected an integer in [1, 1024], got 0"),
        ("--workers -1", ["evaluate", "{c}", "--workers", "-1"],
         "--workers: expected an integer in [1, 1024], got '-1'"),
        ("--workers x", ["evaluate", "{c}", "--workers", "x"],
         "--workers: expected an integer in [1, 1024], got 'x'"),
        ("--workers 1e3", ["evaluate", "{c}", "--workers", "1e3"],
         "--workers: expected an integer"),
        ("--workers huge", ["evaluate", "{c}", "--workers", "9" * 5000],
         "--workers: expected an integer"),
        ("--workers Arabic digits", ["evaluate", "{c}", "--workers", "\u0663"],
         "--workers: expected an integer"),
        ("--workers empty", ["evaluate", "{c}", "--workers", ""],
         "--workers: expected an integer"),
        ("--executor slurm", ["evaluate", "{c}", "--executor", "slurm"],
         "--executor: expected one of ('local', 'ray')"),
        ("--address for local", ["evaluate", "{c}", "--address", "h:1"],
         "--address: only for the ray executor"),
        ("--address garbage:1", ["evaluate", "{c}", "--executor", "ray", "--address",
                                 "garbage:1"], "--address: cannot reach a Ray cluster at "
                                               "'garbage:1'"),
        ("--address ray://256.1.1.1:1", ["evaluate", "{c}", "--executor", "ray", "--address",
                                         "ray://256.1.1.1:1"], "--address: expected a Ray "
                                                               "address"),
        ("--address port 0", ["evaluate", "{c}", "--executor", "ray", "--address", "h:0"],
         "--address: expected a Ray address"),
        ("--address port 65536", ["evaluate", "{c}", "--executor", "ray", "--address",
                                  "h:65536"], "--address: expected a Ray address"),
        ("--address no port", ["evaluate", "{c}", "--executor", "ray", "--address", "host"],
         "--address: expected a Ray address"),
        ("--address IPv6 unbracketed", ["evaluate", "{c}", "--executor", "ray", "--address",
                                        "::1:6379"], "--address: expected a Ray address"),
        ("--address with a path", ["evaluate", "{c}", "--executor", "ray", "--address",
                                   "ray://h:1/../x"], "--address: expected a Ray address"),
        ("--address http", ["evaluate", "{c}", "--executor", "ray", "--address",
                            "http://h:1"], "--address: expected a Ray address"),
        ("--address NUL", ["evaluate", "{c}", "--executor", "ray", "--address", "h\x01:1"],
         "--address: expected a Ray address"),
        ("--address 300-character host", ["evaluate", "{c}", "--executor", "ray", "--address",
                                          "a" * 300 + ":1"], "--address: expected a Ray "
                                                             "address"),
        ("--address auto without a cluster", ["evaluate", "{c}", "--executor", "ray",
                                              "--address", "auto"],
         "--address: auto: no running Ray cluster found"),
        ("train --workers 0", ["train", "{t}", "--workers", "0"],
         "--workers: expected an integer in [1, 1024], got 0"),
        ("train --address garbage", ["train", "{t}", "--executor", "ray", "--address", "x"],
         "--address: expected a Ray address"),
        ("train --timesteps many", ["train", "{t}", "--timesteps", "many"],
         "argument --timesteps: invalid int value: 'many'"),
        ("train --seeds none", ["train", "{t}", "--seeds"],
         "argument --seeds: expected at least one argument"),
        ("train --seeds a", ["train", "{t}", "--seeds", "a"],
         "argument --seeds: invalid int value: 'a'"),
        ("abbreviated --worker", ["evaluate", "{c}", "--worker", "2"],
         "unrecognized arguments: --worker 2"),
        ("abbreviated --work=2", ["evaluate", "{c}", "--work=2"],
         "unrecognized arguments: --work=2"),
        ("abbreviated --exec", ["evaluate", "{c}", "--exec", "ray"],
         "unrecognized arguments: --exec ray"),
        ("abbreviated --no-prog", ["evaluate", "{c}", "--no-prog"],
         "unrecognized arguments: --no-prog"),
        ("abbreviated --timestep", ["train", "{t}", "--timestep", "100"],
         "unrecognized arguments: --timestep 100"),
        ("abbreviated --res", ["train", "{t}", "--res"], "unrecognized arguments: --res"),
        ("abbreviated --sched", ["tune", "{t}", "--sched", "asha"],
         "unrecognized arguments: --sched asha"),
        ("abbreviated --tri", ["tune", "{t}", "--tri", "3"], "unrecognized arguments: --tri 3"),
        ("abbreviated --win", ["curves", "out", "--win", "3"],
         "unrecognized arguments: --win 3"),
        ("unknown flag", ["evaluate", "{c}", "--colour"], "unrecognized arguments: --colour"),
        ("unknown command", ["deploy"], "argument command: invalid choice: 'deploy'"),
        ("abbreviated command", ["eval", "{c}"], "argument command: invalid choice: 'eval'"),
        ("no command", [], "the following arguments are required: command"),
        ("train without config", ["train"], "the following arguments are required: config"),
        ("config missing", ["evaluate", "nowhere.yaml"], "config: file 'nowhere.yaml' does "
                                                         "not exist"),
        ("config a folder", ["evaluate", "{here}"], "is not a file"),
        ("config a device", ["evaluate", "/dev/zero"], "config: file '/dev/zero' is not a "
                                                       "file"),
        ("config a pipe", ["evaluate", "pipe.yaml"], "config: file 'pipe.yaml' is not a file"),
        ("config name with a NUL", ["evaluate", "c\x01.yaml"], "config: file 'c\\x01.yaml' "
                                                               "does not exist"),
        ("curves --window 0", ["curves", "out", "--window", "0"],
         "window: expected an integer >= 1, got 0"),
        ("curves --window -5", ["curves", "out", "--window", "-5"],
         "window: expected an integer >= 1, got -5"),
        ("curves of nothing", ["curves", "nowhere"], "curves: 'nowhere' is not a folder"),
        ("trust a missing file", ["trust", "nowhere.zip"], "trust: file 'nowhere.zip' does "
                                                           "not exist"),
        ("trust a folder", ["trust", "{here}"], "' is not a file"),
        ("trust another name", ["trust", "{c}"], "trust: c.yaml: expected a name"),
        ("trust a device", ["trust", "/dev/zero"], "trust: file '/dev/zero' is not a file"),
    ]
    environment = [
        ("BOUNCE_GYM_MAX_TIMESTEPS x", ["train", "{t}"], "BOUNCE_GYM_MAX_TIMESTEPS: expected an "
         "integer >= 1", (("BOUNCE_GYM_MAX_TIMESTEPS", "x"),)),
        ("BOUNCE_GYM_MAX_TIMESTEPS 0", ["train", "{t}"], "BOUNCE_GYM_MAX_TIMESTEPS: expected an "
         "integer >= 1, got '0'", (("BOUNCE_GYM_MAX_TIMESTEPS", "0"),)),
        ("BOUNCE_GYM_MAX_TIMESTEPS of 5000 digits", ["train", "{t}"], "BOUNCE_GYM_MAX_TIMESTEPS:"
         " expected an integer >= 1", (("BOUNCE_GYM_MAX_TIMESTEPS", "9" * 5000),)),
        ("BOUNCE_GYM_HOME a file", ["evaluate", "{c}"], "BOUNCE_GYM_HOME: cannot read or create "
         "the key", (("BOUNCE_GYM_HOME", "{here}/c.yaml"),)),
        ("BOUNCE_GYM_HOME with a short key", ["evaluate", "{c}"], "BOUNCE_GYM_HOME: the key",
         (("BOUNCE_GYM_HOME", "{here}/short-key"),)),
        ("BOUNCE_GYM_HOME with a key others can read", ["evaluate", "{c}"],
         "can be read or written by others (mode 0644); chmod 600",
         (("BOUNCE_GYM_HOME", "{here}/open-key"),)),
        ("BOUNCE_GYM_HOME writable by all", ["evaluate", "{c}"],
         "can be written by others (mode 0777), who could plant a key",
         (("BOUNCE_GYM_HOME", "{here}/open-home"),)),
        ("BOUNCE_GYM_HOME with a pipe for a key", ["evaluate", "{c}"],
         "secret.key is not a regular file", (("BOUNCE_GYM_HOME", "{here}/pipe-key"),)),
        ("BOUNCE_GYM_HOME of an unknown user", ["evaluate", "{c}"],
         "BOUNCE_GYM_HOME: cannot expand '~nosuchuser-bounce-gym/x': no such user",
         (("BOUNCE_GYM_HOME", "~nosuchuser-bounce-gym/x"),)),
        ("trust with a key folder writable by all", ["trust", "ppo_seed0.zip"],
         "chmod go-w", (("BOUNCE_GYM_HOME", "{here}/open-home"),)),
        ("RAY_ADDRESS garbage for auto", ["evaluate", "{c}", "--executor", "ray", "--address",
                                          "auto"], "--address (auto, from RAY_ADDRESS): expected "
                                                   "a Ray address", (("RAY_ADDRESS", "::x"),)),
    ]
    out = []
    for name, argv, expect, env in environment:
        out.append(_flag_case(name, argv, expect, env=env))
    for name, argv, expect in cases:
        env = no_ray if "auto" in argv else ()
        if name == "config a pipe":
            def build(box: Sandbox, argv=argv) -> list[str]:
                os.mkfifo(box.here / "pipe.yaml")
                return argv
            out.append(Case("flags", name, build, expect))
        else:
            out.append(_flag_case(name, argv, expect, env=env))
    return out


def _wrappers() -> list[Case]:
    """The thin wrappers ``evaluate.py`` and ``train.py``, which parse as the command does."""
    cases = [
        ("evaluate.py --worker 2", ["evaluate.py", "{c}", "--worker", "2"],
         "unrecognized arguments: --worker 2"),
        ("evaluate.py --workers 0", ["evaluate.py", "{c}", "--workers", "0"],
         "--workers: expected an integer in [1, 1024], got 0"),
        ("evaluate.py of a missing file", ["evaluate.py", "nowhere.yaml"],
         "config: file 'nowhere.yaml' does not exist"),
        ("evaluate.py of a name that escapes", ["evaluate.py", "escape.yaml"],
         "config.name: expected a name for the run folder"),
        ("train.py --timestep 5", ["train.py", "{t}", "--timestep", "5"],
         "unrecognized arguments: --timestep 5"),
        ("train.py of gamma 5", ["train.py", "gamma.yaml"],
         "config.hyperparams.gamma: expected a number in (0, 1], got 5"),
        ("train.py --seeds x", ["train.py", "{t}", "--seeds", "x"],
         "argument --seeds: invalid int value: 'x'"),
        ("train.py of a YAML payload", ["train.py", "payload.yaml"],
         "could not determine a constructor"),
    ]

    def build(box: Sandbox, argv: list[str]) -> list[str]:
        box.yaml("escape.yaml", evaluation(name="../../ESCAPED"))
        box.yaml("gamma.yaml", _hp(gamma=5))
        box.write("payload.yaml",
                  f"name: !!python/object/apply:os.system ['{box.touch_payload()}']\n")
        return _arguments(box, argv)
    return [Case("wrappers", name, lambda box, argv=argv: build(box, argv), expect)
            for name, argv, expect in cases]


def cases() -> list[Case]:
    """Every command-line case of this module (a case's arguments start with ``evaluate.py``
    or ``train.py`` to run that wrapper instead of ``bounce-gym``)."""
    return [*_yaml_text(), *_config_content(), *_training(), *_tune(), *_flags(), *_wrappers()]

