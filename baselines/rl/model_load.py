"""Loading a Stable-Baselines3 model file as data: nothing in it is unpickled.

SB3 keeps an algorithm's attributes in the zip's ``data`` entry as JSON, and those JSON cannot
hold — the spaces, the policy class, the schedules (``lr_schedule``, ``clip_range``,
``exploration_schedule``, …), ``policy_kwargs`` naming an activation, the last observations —
as base64 cloudpickle (``{":serialized:": ...}``), which ``load`` unpickles unless the key is
given in ``custom_objects``. `load_model_file` gives every key: it builds a fresh model of the
algorithm (a *template*) on an env that has only the spaces the model must fit, from the
training configuration the file carries as JSON (`baselines.rl.model_files.METADATA_ENTRY`,
checked by `baselines.rl.train_config` like a new one), and hands SB3 the template's attribute
for each key of ``data`` — except the step counters (`COUNTERS`), which SB3 takes from the file
when they are plain numbers. A key the template would not save is refused: nothing is left for
SB3 to unpickle. The weights (``*.pth`` entries, only those the template saves and no larger
than its own allow, `WEIGHTS_FACTOR`) are read with ``torch.load(weights_only=True)``, which
builds tensors and plain containers only and refuses any other global.
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import os
import pickle
import re
import warnings
import zipfile
from collections.abc import Iterator

from baselines.rl.model_files import DATA_ENTRY, METADATA_ENTRY, ZIP_ERRORS, ModelFile, read_entry
from baselines.rl.train_config import (
    algo_class,
    algo_kwargs,
    check_hyperparams,
    policy_name,
    validate_train_config,
)
from baselines.rl.wrappers import Feed
from bounce_gym.errors import ConfigError

#: Attributes SB3 saves as JSON numbers that count what the run did: kept from the file when
#: they have the template's type (a resumed run restores them anyway, `baselines.rl.resume`).
COUNTERS = ("num_timesteps", "_episode_num", "_n_updates", "_n_calls", "exploration_rate",
            "_current_progress_remaining")
#: A weights entry may hold this many times the bytes of the template's largest one (an
#: optimiser keeps two moments per weight), plus `WEIGHTS_SLACK`.
WEIGHTS_FACTOR = 4
WEIGHTS_SLACK = 1 << 20
#: The zip entry of the torch variables that are not state dicts.
VARIABLES_ENTRY = "pytorch_variables.pth"
#: The fields of a space's JSON description that say which space it is.
_SPACE_FIELDS = ("dtype", "_shape", "n", "start", "nvec")
#: What SB3's load raises for weights that do not fit the model or are not weights at all.
_LOAD_ERRORS = (*ZIP_ERRORS, pickle.UnpicklingError, ValueError, KeyError, IndexError,
                TypeError, AttributeError, AssertionError)


def load_model_file(trained: ModelFile, observation_space, action_space, **load_kwargs):
    """The SB3 model of ``trained`` for an env with these spaces (``load_kwargs`` go to SB3's
    ``load``, e.g. the env to resume training on); a `ConfigError` naming the file for a
    file that does not fit them or is not a model this package saved."""
    acting = load_kwargs.get("env") is None
    template = _template(trained, observation_space, action_space, acting)
    saved, weights = _saved(template)
    _check_spaces(trained, saved)
    _check_weights(trained, weights)
    custom_objects = _custom_objects(trained, template, saved)
    try:
        with _torch_quiet():
            return type(template).load(io.BytesIO(trained.data), device="cpu",
                                       custom_objects=custom_objects, **load_kwargs)
    except _LOAD_ERRORS as exc:
        raise ConfigError(f"model {trained.path}: its weights do not fit the {trained.algo} model "
                          f"its configuration describes ({_reason(exc)})") from None


def _config(trained: ModelFile) -> dict:
    """The validated training configuration the file carries."""
    saved = trained.metadata.get("config")
    if not isinstance(saved, dict):
        raise ConfigError(f"model {trained.path}: carries no training configuration in its "
                          f"{METADATA_ENTRY}, from which the objects it holds pickled would be "
                          "rebuilt; only models saved by baselines.rl.train load")
    # the saved configuration is complete: its defaults of None are left out to be filled in
    # again, and the hyperparameter file it names was merged into it already
    config = {k: v for k, v in saved.items() if v is not None and k != "hyperparams_file"}
    if config.get("algo") != trained.algo:
        raise ConfigError(f"model {trained.path}: its name says {trained.algo}, but its "
                          f"configuration says algo {config.get('algo')!r}")
    try:
        config = validate_train_config(config)
        check_hyperparams(algo_class(trained.algo), config["hyperparams"])
    except ConfigError as exc:
        raise ConfigError(f"model {trained.path}: the training configuration it carries is not "
                          f"valid ({exc})") from None
    return config


def _template(trained: ModelFile, observation_space, action_space, acting: bool):
    """A fresh model of the file's configuration, for an env with these spaces; ``acting``: for
    a model loaded to act (`_acting_kwargs`)."""
    config = _config(trained)
    env = Feed(copy.deepcopy(observation_space), copy.deepcopy(action_space))
    kwargs = algo_kwargs(config["hyperparams"])
    if acting:
        kwargs = _acting_kwargs(kwargs, trained.algo)
    try:
        with warnings.catch_warnings():  # e.g. a mini-batch that does not divide one env's steps
            warnings.simplefilter("ignore")
            return algo_class(trained.algo)(
                policy_name(trained.algo, observation_space), env, seed=config["seeds"][0],
                device="cpu", verbose=0, **kwargs)
    except (AssertionError, TypeError, ValueError, KeyError) as exc:
        raise ConfigError(f"model {trained.path}: no {trained.algo} model for observations "
                          f"{observation_space} and actions {action_space} can be built from its "
                          f"configuration ({_reason(exc)})") from None


#: the SB3 algorithms whose policies are actor-critics (SB3 initialises their weights
#: orthogonally unless ``policy_kwargs.ortho_init`` is False)
ACTOR_CRITIC = ("ppo", "recurrentppo")


def _acting_kwargs(kwargs: dict, algo: str) -> dict:
    """The template's arguments for a model loaded to act, which neither trains nor fills a
    buffer: SB3's plain replay buffer (hindsight relabelling needs the env it relabels with, and
    the model has none) and, for the actor-critic algorithms, no orthogonal initialisation of
    weights that the file's replace (the template's arguments become the loaded model's, so
    neither is built twice; a quarter to half a second per model)."""
    kwargs = dict(kwargs)
    if "replay_buffer_class" in kwargs:
        kwargs.update(replay_buffer_class=None, replay_buffer_kwargs={})
    if algo in ACTOR_CRITIC:
        kwargs["policy_kwargs"] = {**(kwargs.get("policy_kwargs") or {}), "ortho_init": False}
    return kwargs


def _saved(template) -> tuple[dict, dict[str, int]]:
    """What SB3 writes for the template: its ``data`` (JSON) and the size of each ``.pth``."""
    buffer = io.BytesIO()
    template.save(buffer)
    with zipfile.ZipFile(buffer) as archive:
        sizes = {info.filename: info.file_size for info in archive.infolist()}
        return json.loads(archive.read(DATA_ENTRY)), {
            name: size for name, size in sizes.items() if _is_weights(name)}


def _is_weights(name: str) -> bool:
    """Whether SB3's load reads the entry ``name`` with ``torch.load``."""
    return os.path.splitext(name)[1] == ".pth"


def _serialized(value: object) -> bool:
    return isinstance(value, dict) and ":serialized:" in value


def _custom_objects(trained: ModelFile, template, saved: dict) -> dict:
    """For every key of the file's ``data``, the template's attribute (`COUNTERS` of the right
    type aside): SB3 then unpickles nothing."""
    custom = {}
    for key, value in trained.sb3_data.items():
        if key not in saved:
            what = "a pickled" if _serialized(value) else "an"
            raise ConfigError(f"model {trained.path}: its {DATA_ENTRY!r} holds {what} entry "
                              f"{key!r}, which a {trained.algo} model does not save and this "
                              "package cannot rebuild")
        fresh = getattr(template, key)
        if key in COUNTERS and not _serialized(value) and type(value) is type(fresh):
            continue
        custom[key] = fresh
    return custom


def _describe(space: object) -> str:
    """A space's JSON description in a few words, e.g. ``Box(dtype=float32, shape=[17])``."""
    if not isinstance(space, dict):
        return "(no space)"
    kind = re.fullmatch(r"<class '(?:\w+\.)*(\w+)'>", str(space.get(":type:")))
    fields = ", ".join(f"{name.strip('_')}={_shown(space[name])}" for name in _SPACE_FIELDS
                       if name in space)
    return f"{kind.group(1) if kind else '?'}({fields})"


def _shown(value: object) -> str:
    """A value of a file's JSON in one short line (a file may put anything there)."""
    text = " ".join(str(value).split())
    return text if len(text) <= 40 else f"{text[:37]}..."


def _check_spaces(trained: ModelFile, saved: dict) -> None:
    """The file's spaces are of the kind, shape and type of the template's (their JSON
    descriptions; the spaces themselves are the template's)."""
    keys = ("observation_space", "action_space")
    theirs = [trained.sb3_data.get(key) for key in keys]
    if [_describe(space) for space in theirs] != [_describe(saved[key]) for key in keys]:
        raise ConfigError(
            f"model {trained.path}: trained for observations {_describe(theirs[0])} and actions "
            f"{_describe(theirs[1])}, but this env has {_describe(saved[keys[0]])} and "
            f"{_describe(saved[keys[1]])} (train with the same env_kwargs)")


def _check_weights(trained: ModelFile, weights: dict[str, int]) -> None:
    """Only the weights entries the template has, each within the size its own allow, and no
    torch variables (none of `baselines.rl.model_files.ALGOS` has any)."""
    limit = WEIGHTS_FACTOR * max(weights.values()) + WEIGHTS_SLACK
    for name, size in trained.sizes.items():
        if _is_weights(name) and name not in weights:
            raise ConfigError(f"model {trained.path}: holds weights {name!r}, which a "
                              f"{trained.algo} model does not have (it has {sorted(weights)})")
        if _is_weights(name) and size > limit:
            raise ConfigError(f"model {trained.path}: its entry {name!r} holds {size} bytes, more "
                              f"than the {limit} the weights of its model may")
    if VARIABLES_ENTRY in trained.sizes:
        variables = _variables(trained)
        if not isinstance(variables, dict) or variables:
            raise ConfigError(f"model {trained.path}: its {VARIABLES_ENTRY!r} holds torch "
                              f"variables, and a {trained.algo} model has none")


def _variables(trained: ModelFile) -> object:
    """The file's torch variables, read as weights only (SB3 would set each one it names)."""
    import torch

    try:
        with zipfile.ZipFile(io.BytesIO(trained.data)) as archive, _torch_quiet():
            variables = read_entry(archive, VARIABLES_ENTRY)
            return torch.load(io.BytesIO(variables), map_location="cpu", weights_only=True)
    except _LOAD_ERRORS as exc:
        raise ConfigError(f"model {trained.path}: its {VARIABLES_ENTRY!r} cannot be read as "
                          f"torch weights ({_reason(exc)})") from None


@contextlib.contextmanager
def _torch_quiet() -> Iterator[None]:
    """torch's warnings about what it reads (e.g. "Detected pickle protocol 4" in a weights
    entry that is a plain pickle) not shown: a file it refuses is one line, a `ConfigError`."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=UserWarning, module="torch")
        yield


def _reason(exc: BaseException) -> str:
    """The exception's type and the gist of its message, on one line: of torch's refusal to
    unpickle, the reason only (not its advice to load without ``weights_only``)."""
    text = str(exc)
    refusal = re.search(r"WeightsUnpickler error:\s*(.+?)(?:\. Please|\n\n|$)", text, re.S)
    gist = " ".join((refusal.group(1) if refusal else text).split())
    return f"{type(exc).__name__}: {gist if len(gist) <= 300 else gist[:299] + '…'}"
