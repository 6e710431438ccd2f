"""The hostile-input suite's files (`test_hostile_inputs`): malformed map files, NetCDF flow
files and model files given to ``bounce-gym evaluate`` and ``train``, unit files planted in
an evaluation's store, and monitor files given to ``bounce-gym curves``, by class
(`hostile_cases.Case`).

Model cases start from a model this package trained (`Sandbox.trained`, a session fixture's),
taken apart and put together again with a payload where the attack needs one: a pickle whose
``__reduce__`` creates `Sandbox.marker`. The JAX learners' cases (when JAX is installed) start
from a model file put together here (`jax_model`): a small jax_ppo network's weights as an
``.npz`` beside its training configuration.
"""

from __future__ import annotations

import base64
import bz2
import functools
import importlib.util
import io
import json
import os
import pickle
import shutil
import struct
import warnings
import zipfile
import zlib
from pathlib import Path

import hostile_cases
import numpy as np
from hostile_cases import NAV, Case, Sandbox, evaluation, experiment, training

BOUNCE = "bounce_gym/Bounce-v0"
#: the classes whose cases start from a trained model (`Sandbox.trained`)
MODEL_CLASSES = ("models", "loads")


class Payload:
    """Unpickled, it creates ``marker`` (the proof that a file ran code)."""

    def __init__(self, marker: Path) -> None:
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


class ShellPayload(Payload):
    """Unpickled, it runs ``touch marker`` in a shell."""

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


# -- map files -------------------------------------------------------------------------------
def _map_case(name: str, file_name: str, content, expect: str) -> Case:
    """An evaluation of a free bouncing robot on the map file ``file_name`` (``content``: text,
    bytes, a mapping written as JSON, or made from the sandbox)."""
    def build(box: Sandbox) -> list[str]:
        text = content(box) if callable(content) else content
        if text is not None:
            box.write(file_name, json.dumps(text) if isinstance(text, dict) else text)
        exp = experiment(env=BOUNCE, env_kwargs={"world": file_name, "backend": "cell"})
        box.yaml("c.yaml", evaluation(exp))
        return ["evaluate", "c.yaml", "--no-progress"]
    return Case("maps", name, build, expect)


SQUARE = [[0, 0], [4, 0], [4, 4], [0, 4]]


def _maps() -> list[Case]:
    ring = "a list of at least 3 vertices"
    pair = "vertex 0 must be a pair of numbers [x, y]"
    bomb_rows = "grid:\n- &r \"" + "." * 20_000 + "\"\n" + "- *r\n" * 20_000
    cases = [
        ("JSON cut short", "m.json", '{"name": "x", "outer": [[0, 0], [1, 0]', "not valid JSON"),
        ("JSON not a mapping", "m.json", "[1, 2]", "expected a mapping"),
        ("JSON empty", "m.json", "", "not valid JSON"),
        ("YAML empty", "m.yaml", "", "got an empty file"),
        ("two vertices", "m.json", {"name": "x", "outer": [[0, 0], [1, 0]]}, ring),
        ("bow tie", "m.json", {"name": "x", "outer": [[0, 0], [1, 1], [1, 0], [0, 1]]},
         "invalid polygon"),
        ("all on a line", "m.json", {"name": "x", "outer": [[0, 0], [1, 0], [2, 0]]},
         "invalid polygon"),
        ("repeated vertex", "m.json", {"name": "x", "outer": [[0, 0], [0, 0], [0, 0]]},
         "invalid polygon"),
        ("NaN in JSON", "m.json", '{"name": "x", "outer": [[NaN, 0], [1, 0], [0, 1]]}',
         "NaN is not a JSON number"),
        ("Infinity in JSON", "m.json", '{"name": "x", "outer": [[Infinity, 0], [1, 0], [0, 1]]}',
         "Infinity is not a JSON number"),
        ("1e999 in JSON", "m.json", '{"name": "x", "outer": [[1e999, 0], [1, 0], [0, 1]]}',
         "the number 1e999 is too large; numbers must be finite"),
        ("NaN in YAML", "m.yaml", "name: x\nouter: [[.nan, 0], [1, 0], [0, 1]]\n",
         "vertex 0 is not finite"),
        ("coordinates as strings", "m.json", {"name": "x", "outer": [["0", "0"], [1, 0],
                                                                      [0, 1]]}, pair),
        ("coordinates as bools", "m.json", {"name": "x", "outer": [[True, 0], [1, 0], [0, 1]]},
         pair),
        ("three coordinates", "m.json", {"name": "x", "outer": [[0, 0, 0], [1, 0, 0],
                                                                 [0, 1, 0]]}, pair),
        ("huge coordinate", "m.json", {"name": "x", "outer": [[0, 0], [10**400, 0], [0, 1]]},
         "is too large; integers lie between"),
        ("hole outside", "m.json", {"name": "x", "outer": SQUARE,
                                    "holes": [[[10, 10], [11, 10], [11, 11]]]},
         "invalid polygon"),
        ("holes overlapping", "m.json", {"name": "x", "outer": SQUARE, "holes": [
            [[1, 1], [2, 1], [2, 2], [1, 2]], [[1.5, 1.5], [2.5, 1.5], [2.5, 2.5]]]},
         "invalid polygon"),
        ("hole a number", "m.json", {"name": "x", "outer": SQUARE, "holes": 3},
         "'holes' must be a list of rings"),
        ("outer and grid", "m.json", {"name": "x", "outer": SQUARE, "grid": ["."]},
         "map has both of 'outer' and 'grid'"),
        ("neither", "m.json", {"name": "x"}, "map has neither of 'outer' and 'grid'"),
        ("unknown key", "m.json", {"name": "x", "outer": SQUARE, "colour": 1},
         "unknown key(s) 'colour'"),
        ("no name", "m.json", {"outer": SQUARE}, "missing required key 'name'"),
        ("name a number", "m.json", {"name": 3, "outer": SQUARE}, "'name' must be a non-empty"),
        ("duplicate key", "m.json", '{"name": "x", "name": "y", "outer": []}',
         "duplicate key 'name'"),
        ("deep nesting", "m.json", '{"name": "x", "outer": ' + "[" * 100 + "]" * 100 + "}",
         "nest 101 deep"),
        ("grid ragged", "m.json", {"name": "x", "grid": ["...", ".."]}, "m.json: invalid"),
        ("grid bad character", "m.json", {"name": "x", "grid": ["..x"]}, "m.json: invalid"),
        ("grid all blocked", "m.json", {"name": "x", "grid": ["###"]}, "m.json: invalid"),
        ("grid two rooms", "m.json", {"name": "x", "grid": [".#."]}, "m.json: invalid"),
        ("grid diagonal pinch", "m.json", {"name": "x", "grid": [".#", "#."]},
         "m.json: invalid"),
        ("grid empty", "m.json", {"name": "x", "grid": []}, "'grid' must be a non-empty list"),
        ("grid of numbers", "m.json", {"name": "x", "grid": [1, 2]},
         "'grid' must be a non-empty list"),
        ("cell_size zero", "m.json", {"name": "x", "grid": ["."], "cell_size": 0},
         "'cell_size' must be a finite number > 0"),
        ("cell_size NaN", "m.yaml", "name: x\ngrid: ['.']\ncell_size: .nan\n",
         "'cell_size' must be a finite number > 0"),
        ("grid of aliased rows", "m.yaml", "name: bomb\n" + bomb_rows, "more than 134217728 characters of strings"),
        ("grid 129 MiB", "m.json", lambda box: _sparse(box, "m.json", 129 << 20),
         "m.json: 135266304 bytes"),
        ("not UTF-8", "m.json", b'{"name": "\xff"}', "not UTF-8 text"),
        ("unknown suffix", "m.txt", "name: x", "unknown map file suffix '.txt'"),
        ("payload tag", "m.yaml", lambda box: "name: !!python/object/apply:os.system "
                                              f"['{box.touch_payload()}']\nouter: []\n",
         "could not determine a constructor"),
    ]
    out = [_map_case(name, file_name, content, expect)
           for name, file_name, content, expect in cases]
    return out


def _sparse(box: Sandbox, name: str, size: int) -> None:
    """A file of ``size`` bytes that takes no room (a hole); returns nothing more to write."""
    path = box.here / name
    with open(path, "wb") as fh:
        fh.truncate(size)
    return None


# -- NetCDF flow files -----------------------------------------------------------------------
def flow_file(path: Path, *, nx: int = 4, ny: int = 3, units: str = "m s-1",
              lon: np.ndarray | None = None, fmt: str = "NETCDF4", u: bool = True,
              u_dtype: object = "f4", speed: float = 0.1, attrs: dict | None = None,
              declared: tuple[int, int] | None = None) -> Path:
    """A small flow file (one layer, ``ny`` x ``nx`` cells on longitude/latitude when ``lon`` is
    given, else on x/y in metres, every velocity ``speed``: NaN is land), or one that only
    declares ``declared`` = (ny, nx) cells."""
    import netCDF4

    ny, nx = declared or (ny, nx)
    with netCDF4.Dataset(path, "w", format=fmt) as nc:
        xname, yname = ("lon", "lat") if lon is not None else ("x", "y")
        nc.createDimension("depth", 1)
        nc.createDimension(yname, ny)
        nc.createDimension(xname, nx)
        for name, size, unit in ((xname, nx, "degrees_east" if lon is not None else "m"),
                                 (yname, ny, "degrees_north" if lon is not None else "m")):
            var = nc.createVariable(name, "f8", (name,))
            var.units = unit
            if declared is None:
                var[:] = lon if name == "lon" else np.arange(size, dtype=float)
        depth = nc.createVariable("depth", "f8", ("depth",))
        depth.units, depth.positive = "m", "down"
        depth[:] = [0.0]
        names = ("u", "v") if u else ("v",)
        for name in names:
            var = nc.createVariable(name, u_dtype, ("depth", yname, xname),
                                    **({"chunksizes": (1, 1, nx)} if declared else {}))
            var.units = units
            if declared is None and u_dtype is not str:
                var[:] = np.full((1, ny, nx), speed)
        for key, value in (attrs or {}).items():
            nc.setncattr(key, value)
    return path


def _flow_case(name: str, make, expect: str, *, multi: bool = False) -> Case:
    """An evaluation of a drifter (or a fleet) on the flow file ``f.nc`` that ``make(path)``
    writes."""
    def build(box: Sandbox) -> list[str]:
        path = box.here / "f.nc"
        make(path)
        env = "bounce_gym/MultiDrifter-v0" if multi else "bounce_gym/Drifter-v0"
        exp = experiment(env=env, env_kwargs={"flow": "f.nc"}, max_steps=None,
                         horizon_reason=None, policies=["random"])
        box.yaml("c.yaml", evaluation(exp))
        return ["evaluate", "c.yaml", "--no-progress"]
    return Case("flows", name, build, expect)


def _classic_header(path: Path, dims: int) -> None:
    """A classic NetCDF header that declares ``dims`` dimensions and holds none."""
    path.write_bytes(b"CDF\x01" + (0).to_bytes(4, "big") + (10).to_bytes(4, "big")
                     + dims.to_bytes(4, "big"))


def _truncated(path: Path) -> None:
    flow_file(path, nx=40, ny=30, fmt="NETCDF3_CLASSIC")
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _flows() -> list[Case]:
    unreadable = "not a readable NetCDF file"
    cases = [
        ("text", lambda p: p.write_text("not a flow\n"), unreadable),
        ("empty", lambda p: p.write_bytes(b""), "not a readable NetCDF file"),
        ("HDF5 signature only", lambda p: p.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 100),
         "not a readable NetCDF file"),
        ("classic magic and garbage", lambda p: p.write_bytes(b"CDF\x01" + b"\xff" * 64),
         "corrupt NetCDF header"),
        ("classic header of 2**31 dimensions", lambda p: _classic_header(p, 2**31 - 1),
         "corrupt NetCDF header (it counts 2,147,483,647"),
        ("classic file cut in half", _truncated, "truncated NetCDF file"),
        ("a billion cells declared", lambda p: flow_file(p, declared=(10_000, 100_000)),
         "declares 1,000,000,000 values"),
        ("10**8 cells declared", lambda p: flow_file(p, declared=(10_000, 10_000)), "declares 100,000,000 values"),
        # under the cap, but a file of a few KB (chunks never written read back as the fill
        # value) that would load into 1.5 GB: issue 36, item 6
        ("4·10**7 cells in a few KB", lambda p: flow_file(p, declared=(4_000, 10_000)),
         "declares 40,000,000 values in a file of"),
        ("furlongs per fortnight", lambda p: flow_file(p, units="furlongs/fortnight"),
         "wrong units 'furlongs/fortnight'"),
        ("no units", lambda p: flow_file(p, units=""), "wrong units ''"),
        ("longitudes of 1000 degrees", lambda p: flow_file(
            p, lon=np.array([1000.0, 1000.1, 1000.2, 1000.3])), "longitudes must lie in [-360, 360]"),
        ("longitudes spanning 720 degrees", lambda p: flow_file(
            p, lon=np.array([-360.0, -100.0, 100.0, 360.0])), "span at most 360 degrees"),
        ("longitudes NaN", lambda p: flow_file(p, lon=np.array([0.0, np.nan, 1.0, 2.0])),
         "not monotonic"),
        ("no u", lambda p: flow_file(p, u=False), "u: missing"),
        ("u of strings", lambda p: flow_file(p, u_dtype=str), "expected real numbers in m/s"),
        ("all land", lambda p: flow_file(p, speed=np.nan), "has no water cell"),
        ("infinite velocities", lambda p: flow_file(p, speed=np.inf), "infinite velocity"),
        ("huge attribute", lambda p: flow_file(p, attrs={"title": "x" * (1 << 21)}), "global attribute 'title' has 2,097,152 values"),
        ("a folder", lambda p: p.mkdir(), "f.nc: no such file"),
        ("a link to a device", lambda p: p.symlink_to("/dev/zero"), "f.nc: no such file"),
    ]
    out = [_flow_case(name, make, expect) for name, make, expect in cases]
    out.append(_flow_case("a fleet on a billion cells",
                          lambda p: flow_file(p, declared=(10_000, 100_000)), "declares 1,000,000,000 values",
                          multi=True))
    out.append(_flow_case("a fleet on furlongs", lambda p: flow_file(p, units="furlongs"),
                          "wrong units 'furlongs'", multi=True))
    return out


# -- model files -----------------------------------------------------------------------------
def entries(path: Path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as archive:
        return {name: archive.read(name) for name in archive.namelist()}


def zipped(items: dict[str, bytes]) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, content in items.items():
            archive.writestr(name, content)
    return out.getvalue()


def _pickled(payload: Payload) -> str:
    return base64.b64encode(pickle.dumps(payload)).decode()


def _planted(box: Sandbox, *, extra: bool = False) -> dict[str, bytes]:
    """The trained model's entries with every pickled value of ``data`` a payload (and, with
    ``extra``, one more pickled key the template does not save)."""
    items = entries(box.trained)
    data = json.loads(items["data"])
    for value in data.values():
        if isinstance(value, dict) and ":serialized:" in value:
            value[":serialized:"] = _pickled(ShellPayload(box.marker))
    if extra:
        data["evil"] = {":type:": "<class 'x'>", ":serialized:": _pickled(Payload(box.marker))}
    items["data"] = json.dumps(data).encode()
    return items


def _torch_payload(box: Sandbox) -> bytes:
    import torch

    out = io.BytesIO()
    torch.save({"weight": Payload(box.marker)}, out)
    return out.getvalue()


def _with(**changes):
    """The trained model's entries with ``changes`` (entry name -> bytes, a function of the
    sandbox, or None to leave the entry out)."""
    def make(box: Sandbox) -> bytes:
        items = entries(box.trained)
        for name, value in changes.items():
            name = name.replace("__", ".")
            if value is None:
                items.pop(name, None)
            else:
                items[name] = value(box) if callable(value) else value
        return zipped(items)
    return make


def _metadata(**config):
    def change(box: Sandbox) -> bytes:
        meta = json.loads(entries(box.trained)["bounce_gym.json"])
        meta["config"].update(config)
        return json.dumps(meta).encode()
    return change


def _model_case(name: str, content, expect: str, *, manifest=None, exp: dict | None = None,
                file_name: str = "ppo_seed0.zip", status: int = 2) -> Case:
    """An evaluation of the rl models in ``models/m`` holding ``content`` (bytes, or made from
    the sandbox) as ``file_name``, with ``manifest`` (text, True: listing the file's sha256, or
    None: none); with ``status`` 0, a file that loads as data (class ``loads``)."""
    def build(box: Sandbox) -> list[str]:
        folder = box.here / "models" / "m"
        folder.mkdir(parents=True, exist_ok=True)
        data = content(box) if callable(content) else content
        if data is not None:
            (folder / file_name).write_bytes(data)
        if manifest is True:
            from bounce_gym.trust import digest

            (folder / "manifest.json").write_text(json.dumps({file_name: [digest(data)]}))
        elif manifest is not None:
            (folder / "manifest.json").write_text(manifest)
        config = evaluation(exp or experiment(policies=["rl"], rl_models="m"))
        box.yaml("c.yaml", config)
        return ["evaluate", "c.yaml", "--no-progress"]
    return Case("models" if status else "loads", name, build, expect, status=status)


def _sparse_model(box: Sandbox) -> None:
    _sparse(box, "models/m/ppo_seed0.zip", (1 << 30) + 1)


def _models() -> list[Case]:
    unreadable = "not a readable Stable-Baselines3 model file"
    bomb = b"{" + b" " * (20 << 20) + b"}"
    cases = [
        ("zip header only", b"PK\x03\x04", unreadable, None),
        ("text", b"not a model\n", unreadable, None),
        ("empty", b"", unreadable, None),
        ("no data entry", zipped({"policy.pth": b"x"}), "it has no 'data' entry", None),
        ("data not JSON", _with(data=b"\x80\x04K\x01."), "its entry 'data': not UTF-8 text",
         None),
        ("data a list", _with(data=b"[1]"), "its entry 'data' is not a JSON object", None),
        ("data of a DQN", _with(data=b'{"policy_class": {"__module__": '
                                     b'"stable_baselines3.dqn.policies"}}'),
         "its name says ppo, but it holds a dqn policy", None),
        ("data deeply nested", _with(data=b"[" * 100_000 + b"]" * 100_000),
         "its entry 'data': lists and mappings nest 100000 deep", None),
        ("data a bomb", _with(data=bomb), "its entry 'data' holds 20971522 bytes", None),
        ("listed, with planted pickles and a key of its own",
         lambda box: zipped(_planted(box, extra=True)), "evil", True),
        ("pickle as policy weights", _with(policy__pth=lambda box: pickle.dumps(
            Payload(box.marker))), "(UnpicklingError: ", True),
        ("torch-saved payload as weights", _with(policy__pth=_torch_payload), "Unsupported global: GLOBAL io.open",
         True),
        ("payload as torch variables", _with(pytorch_variables__pth=_torch_payload),
         "Unsupported global: GLOBAL io.open", True),
        ("optimizer weights a bomb", _with(policy__optimizer__pth=b"\0" * (80 << 20)),
         "its entry 'policy.optimizer.pth' holds 83886080 bytes", None),
        ("no metadata", _with(bounce_gym__json=None), "carries no training configuration", None),
        ("metadata not JSON", _with(bounce_gym__json=b"{"), "its entry 'bounce_gym.json': not "
                                                            "valid JSON", None),
        ("metadata trains gamma 5", _with(bounce_gym__json=_metadata(
            hyperparams={"gamma": 5})), "config.hyperparams.gamma: expected a number in (0, 1]", None),
        ("metadata of another algorithm", _with(bounce_gym__json=_metadata(algo="dqn")),
         "its name says ppo, but its configuration says algo 'dqn'", None),
        ("metadata a payload name", _with(bounce_gym__json=_metadata(
            name="../../ESCAPED")), "config.name: expected the name of a folder", None),
        ("changed since the manifest", lambda box: box.trained.read_bytes() + b"\0",
         "has changed since it was saved", json.dumps({"ppo_seed0.zip": ["0" * 64]})),
        ("manifest not JSON", lambda box: box.trained.read_bytes(), "model manifest", "{"),
        ("manifest deeply nested", lambda box: box.trained.read_bytes(), "model manifest",
         "[" * 100_000 + "]" * 100_000),
        ("manifest a list", lambda box: box.trained.read_bytes(), "model manifest", "[]"),
        ("manifest 20 MiB", lambda box: box.trained.read_bytes(), "model manifest",
         " " * (20 << 20)),
    ]
    out = [_model_case(name, content, expect, manifest=manifest)
           for name, content, expect, manifest in cases]
    out.append(_model_case("larger than 1 GiB", lambda box: _sparse_model(box),
                           "holds more than the 1073741824 bytes"))
    out.append(_model_case("trained on another observation", lambda box:
                           box.trained.read_bytes(), "but this env has Box(dtype=float32, shape=[27])",
                           exp=experiment(env_kwargs={**NAV, "history": 9}, policies=["rl"],
                                          rl_models="m")))
    out.append(_model_case("spaces described in many lines", _with(data=_spaces_in_lines),
                           "trained for observations Box(dtype=float32 x y, shape=[17])"))
    out.append(_model_case("listed, with every pickled value a payload", lambda box: zipped(
        _planted(box)), "", manifest=True, status=0))
    out.append(_model_case("entries named to escape", _with(**{
        "../../ESCAPED": b"x", "../../../ESCAPED": b"x"}), "", status=0))
    out.append(_resume_case("unsigned", b"0" * 64))
    out.append(_resume_case("signed in a foreign script", "\u0663".encode() * 64))
    out.append(_model_case("data a bzip2 bomb declaring 2 bytes", _bzip2_data,
                           "its entry 'data' is compressed with zip method 12"))
    out.append(_model_case("data a deflate bomb declaring its JSON and its CRC", _deflate_data,
                           "its entry 'data' holds more or fewer than the"))
    if importlib.util.find_spec("jax") is not None:
        out += _jax_models()
    return out


# -- bzip2: zipfile inflates a whole chunk of it at once, past the entry's declared size -------
#: bytes of zeros a bzip2 bomb inflates to
BOMB_BYTES = 320 << 20


@functools.cache
def deflated_zeros(size: int = BOMB_BYTES, prefix: bytes = b"") -> bytes:
    """``prefix`` and ``size`` zero bytes as a raw deflate stream (about a thousandth of it;
    made once)."""
    packer = zlib.compressobj(9, zlib.DEFLATED, -15)
    chunk = bytes(16 << 20)
    out = [packer.compress(prefix)]
    out += [packer.compress(chunk[:min(len(chunk), size - k)]) for k in range(0, size, len(chunk))]
    return b"".join(out) + packer.flush()


@functools.cache
def bzip2_zeros(size: int = BOMB_BYTES) -> bytes:
    """``size`` zero bytes, compressed with bzip2 (a few hundred bytes; made once)."""
    packer = bz2.BZ2Compressor(9)
    chunk = bytes(16 << 20)
    out = [packer.compress(chunk[:min(len(chunk), size - k)]) for k in range(0, size, len(chunk))]
    return b"".join(out) + packer.flush()


def with_raw_entry(items: dict[str, bytes], name: str, raw: bytes, method: int,
                   declared: int, crc: int | None = None) -> bytes:
    """A zip of ``items`` and the entry ``name`` whose compressed bytes are ``raw`` (already
    compressed with zip method ``method``), declaring ``declared`` bytes uncompressed (and the
    CRC ``crc``, if given): written stored, then its central directory record says otherwise
    (what `zipfile` reads)."""
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for key, content in items.items():
            archive.writestr(key, content)
        archive.writestr(zipfile.ZipInfo(name), raw, compress_type=zipfile.ZIP_STORED)
    data = bytearray(out.getvalue())
    at = data.rfind(b"PK\x01\x02")  # the central directory record of the last entry
    assert data[at + 46:at + 46 + len(name)] == name.encode()
    struct.pack_into("<H", data, at + 10, method)
    struct.pack_into("<I", data, at + 24, declared)
    if crc is not None:
        struct.pack_into("<I", data, at + 16, crc)
    return bytes(data)


def _bzip2_data(box: Sandbox) -> bytes:
    items = entries(box.trained)
    items.pop("data")
    return with_raw_entry(items, "data", bzip2_zeros(), zipfile.ZIP_BZIP2, 2)


def _deflate_data(box: Sandbox) -> bytes:
    """The trained model whose ``data`` declares (size and CRC) just its JSON, and whose stream
    inflates 320 MiB of zeros past it (`zipfile`'s ``read``, as SB3's load reads ``data``,
    inflates all of it before cutting it to the declared size)."""
    items = entries(box.trained)
    data = items.pop("data")
    return with_raw_entry(items, "data", deflated_zeros(prefix=data), zipfile.ZIP_DEFLATED,
                          len(data), zlib.crc32(data))


# -- the JAX learners' model files -----------------------------------------------------------
#: the hidden layer of the JAX cases' network
JAX_HIDDEN = 16


def jax_shapes() -> dict[str, tuple[int, ...]]:
    """The arrays of a jax_ppo network for the navigation env of `hostile_cases.NAV`."""
    import gymnasium as gym

    from baselines.rl.jaxrl.networks import layer_shapes, observation_size
    from baselines.rl.jaxrl.ppo import actor_critic_sizes

    env = gym.make(hostile_cases.NAVIGATION, **NAV)
    sizes = actor_critic_sizes(observation_size(env.observation_space),
                               int(env.action_space.n), {"pi": [JAX_HIDDEN], "vf": [JAX_HIDDEN]})
    return {name: shape for net, s in sizes.items()
            for name, shape in layer_shapes(net, s).items()}


def npy(shape: tuple[int, ...], data: bytes | None = None, descr: str = "<f4") -> bytes:
    """An ``.npy`` file: a header declaring ``shape`` of ``descr``, then ``data`` (default:
    the zeros it declares)."""
    out = io.BytesIO()
    np.lib.format.write_array_header_1_0(out, {"descr": descr, "fortran_order": False,
                                               "shape": shape})
    if data is None:
        data = bytes(4 * int(np.prod(shape)))
    return out.getvalue() + data


def jax_npz(**members: bytes | None) -> bytes:
    """The ``.npz`` of the network's weights (zeros), with ``members`` (array name with ``__``
    for ``.`` -> the member's bytes, or None to leave it out) in place of the arrays'."""
    arrays = {name: npy(shape) for name, shape in jax_shapes().items()}
    arrays.update({name.replace("__", "."): value for name, value in members.items()})
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, content in arrays.items():
            if content is not None:
                archive.writestr(f"{name}.npy", content)
    return out.getvalue()


def jax_model(weights: bytes) -> bytes:
    """A jax_ppo model file (as `baselines.rl.jaxrl.weights` writes one) holding ``weights`` as
    its ``weights.npz``, for `hostile_cases.NAV`'s env."""
    from baselines.rl.train_config import validate_train_config

    config = validate_train_config(training(
        name="m", algo="jax_ppo", models=None, n_envs=None,
        hyperparams={"policy_kwargs": {"net_arch": [JAX_HIDDEN]}}))
    return zipped({"weights.npz": weights,
                   "bounce_gym.json": json.dumps({"config": config,
                                                  "jax": {"num_timesteps": 64}}).encode()})


def _streamed_member(shape: tuple[int, ...], zeros: int) -> bytes:
    """An ``.npz`` whose ``pi.0.w`` declares ``shape`` and holds ``zeros`` zero bytes, deflated
    (written in pieces: never whole in memory)."""
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, shape_k in jax_shapes().items():
            if name != "pi.0.w":
                archive.writestr(f"{name}.npy", npy(shape_k))
                continue
            with archive.open(f"{name}.npy", "w", force_zip64=True) as member:
                member.write(npy(shape, b""))
                chunk = bytes(16 << 20)
                for k in range(0, zeros, len(chunk)):
                    member.write(chunk[:min(len(chunk), zeros - k)])
    return out.getvalue()


def _lying_member(method: int, stream: bytes) -> bytes:
    """A model whose ``pi.0.w`` member is ``stream`` (compressed with zip ``method``: a bomb),
    declaring just the size the network needs."""
    arrays = {f"{name}.npy": npy(shape) for name, shape in jax_shapes().items()}
    size = len(arrays.pop("pi.0.w.npy"))
    return jax_model(with_raw_entry(arrays, "pi.0.w.npy", stream, method, size))


def _lying_weights(box: Sandbox) -> bytes:
    """A model whose ``weights.npz`` entry declares 1,000 bytes and inflates to 320 MiB."""
    from baselines.rl.train_config import validate_train_config

    config = validate_train_config(training(
        name="m", algo="jax_ppo", models=None, n_envs=None,
        hyperparams={"policy_kwargs": {"net_arch": [JAX_HIDDEN]}}))
    metadata = json.dumps({"config": config, "jax": {"num_timesteps": 64}}).encode()
    return with_raw_entry({"bounce_gym.json": metadata}, "weights.npz", deflated_zeros(),
                          zipfile.ZIP_DEFLATED, 1000)


def _jax_models() -> list[Case]:
    """Model cases of a JAX learner: its weights are checked against the network its
    configuration describes before anything is inflated past it."""
    right = (17, JAX_HIDDEN)  # the first layer: 17 observations (4 pairs and the goal) -> hidden
    name = "jax_ppo_seed0.zip"
    cases = [
        ("a member declaring 10**12 floats, holding none",
         lambda box: jax_model(jax_npz(pi__0__w=npy((10**6, 10**6), b""))),
         f"its weights 'pi.0.w' are float32[1000000, 1000000], the network needs "
         f"float32{list(right)}"),
        ("a member of 384 MiB of zeros, declared so",
         lambda box: jax_model(_streamed_member((3 << 25,), 3 << 27)),
         "its weights 'pi.0.w' take 402653312 bytes uncompressed, more than"),
        ("a member of the right header and 384 MiB more",
         lambda box: jax_model(_streamed_member(right, 3 << 27)),
         "its weights 'pi.0.w' take 402653312 bytes uncompressed, more than"),
        ("an entry of 16 MiB of zeros", lambda box: jax_model(bytes(16 << 20)),
         "its entry 'weights.npz' holds 16777216 bytes, more than the"),
        ("a member a bzip2 bomb declaring the right size", lambda box: _lying_member(
            zipfile.ZIP_BZIP2, bzip2_zeros()),
         "its weights' member 'pi.0.w.npy' is compressed with zip method 12"),
        ("a member a deflate bomb declaring the right size", lambda box: _lying_member(
            zipfile.ZIP_DEFLATED, deflated_zeros(prefix=npy(right, b""))),
         "its weights cannot be read (BadZipFile: Bad CRC-32 for file 'pi.0.w.npy')"),
        ("the entry a deflate bomb declaring 1,000 bytes", _lying_weights,
         "its weights cannot be read (BadZipFile: "),
        ("a header declaring 4 GiB of itself", lambda box: jax_model(jax_npz(
            pi__0__w=b"\x93NUMPY\x02\x00\xff\xff\xff\xff" + b" " * 100)),
         "its weights 'pi.0.w' have an .npy header of 4294967295 bytes, not at most 10000"),
        ("a member cut short", lambda box: jax_model(jax_npz(
            pi__0__w=npy(right, bytes(100)))), "its weights 'pi.0.w' take 228 bytes "
         "uncompressed, but a float32[17, 16] array with its .npy header takes 1216"),
        ("a member of float64", lambda box: jax_model(jax_npz(
            pi__0__w=npy(right, descr="<f8"))), "its weights 'pi.0.w' are float64[17, 16]"),
        ("a member of pickled objects", lambda box: jax_model(jax_npz(
            pi__0__w=npy(right, pickle.dumps(Payload(box.marker)), descr="|O"))),
         "its weights 'pi.0.w' are object[17, 16]"),
        ("a member missing", lambda box: jax_model(jax_npz(pi__0__b=None)),
         "holds weights ['pi.0.w', 'pi.1.b'"),
        ("a member twice", lambda box: jax_model(_twice("pi.0.b.npy")),
         "holds weights ['pi.0.b', 'pi.0.b', 'pi.0.w'"),
        ("a header of 60,000 bytes", lambda box: jax_model(jax_npz(
            pi__0__w=b"\x93NUMPY\x01\x00\x60\xea" + b" " * 60_000)),
         "its weights 'pi.0.w' take 60010 bytes uncompressed, more than"),
        ("a header of 9,000 bytes", lambda box: jax_model(jax_npz(
            pi__0__w=b"\x93NUMPY\x01\x00\x28\x23" + b" " * 9000)),
         "its weights cannot be read (ValueError: "),
        ("weights not a zip", lambda box: jax_model(b"not a zip"),
         "its weights cannot be read (BadZipFile: "),
    ]
    return [_model_case(f"JAX: {label}", content, expect, file_name=name)
            for label, content, expect in cases]


def _twice(member: str) -> bytes:
    """The network's ``.npz`` with the member ``member`` written a second time."""
    out = io.BytesIO(jax_npz())
    with zipfile.ZipFile(out, "a") as archive, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile's warning of a duplicate name
        archive.writestr(member, archive.read(member))
    return out.getvalue()


def _spaces_in_lines(box: Sandbox) -> bytes:
    data = json.loads(entries(box.trained)["data"])
    data["observation_space"]["dtype"] = "float32\nx\ny"
    return json.dumps(data).encode()


def _resume_case(name: str, signature: bytes) -> Case:
    """``train --resume`` from a checkpoint whose resume state this user's runs did not sign
    (a payload in its place, with ``signature``)."""
    def build(box: Sandbox) -> list[str]:
        from baselines.rl.model_files import RESUME_ENTRY, SIGNATURE_ENTRY

        checkpoints = box.here / "out/models/nav/checkpoints"
        checkpoints.mkdir(parents=True)
        source = sorted(box.trained.parent.glob("checkpoints/*.zip"))[-1]
        items = entries(source)
        items[RESUME_ENTRY] = pickle.dumps(Payload(box.marker))
        items[SIGNATURE_ENTRY] = signature
        (checkpoints / source.name).write_bytes(zipped(items))
        box.yaml("t.yaml", training(total_timesteps=128, hyperparams={
            "n_steps": 32, "batch_size": 32, "n_epochs": 1, "learning_rate": "lin_0.001",
            "policy_kwargs": {"activation_fn": "relu", "net_arch": [16]}}))
        return ["train", "t.yaml", "--resume", "--no-progress"]
    return Case("models", f"resume from a checkpoint {name}", build,
                "its resume state was not written by this user's runs")


# -- unit files ------------------------------------------------------------------------------
def store(box: Sandbox) -> Path:
    """The units folder of the case's evaluation ``c.yaml`` (written here), created."""
    from bounce_gym_experiments.config import load_config, validate_config
    from bounce_gym_experiments.sweep import store_folder

    box.yaml("c.yaml", evaluation())
    folder = store_folder(validate_config(load_config(box.here / "c.yaml")))
    folder.mkdir(parents=True)
    return folder


def _signed_elsewhere(box: Sandbox, folder: Path, key: str, home: str) -> None:
    """A payload signed by the store of another user (``home``) or for another unit."""
    from bounce_gym.trust import HOME_VARIABLE
    from bounce_gym_experiments.executors import UnitStore

    saved = os.environ.get(HOME_VARIABLE)
    os.environ[HOME_VARIABLE] = str(box.here / home)
    try:
        UnitStore(folder).save(key, Payload(box.marker))
    finally:
        os.environ[HOME_VARIABLE] = saved
    shutil.rmtree(box.here / home)


def _unit_case(name: str, plant) -> Case:
    """An evaluation whose one unit ``0-0-0`` finds ``plant(box, folder, unit)`` planted."""
    def build(box: Sandbox) -> list[str]:
        folder = store(box)
        plant(box, folder, folder / "0-0-0.unit")
        return ["evaluate", "c.yaml", "--no-progress"]
    return Case("units", name, build, "not taken as a unit result", status=0)


def _other_user(box: Sandbox, folder: Path, unit: Path) -> None:
    _signed_elsewhere(box, folder, "0-0-0", "another-user")


def _other_unit(box: Sandbox, folder: Path, unit: Path) -> None:
    from bounce_gym_experiments.executors import UnitStore

    UnitStore(folder).save("0-0-1", Payload(box.marker))
    (folder / "0-0-1.unit").rename(unit)


def _other_sweep(box: Sandbox, folder: Path, unit: Path) -> None:
    from bounce_gym_experiments.executors import UnitStore

    other = folder.with_name("f" * 16)
    UnitStore(other).save("0-0-0", Payload(box.marker))
    (other / "0-0-0.unit").rename(unit)
    other.rmdir()


def _cut_short(box: Sandbox, folder: Path, unit: Path) -> None:
    from bounce_gym_experiments.executors import UnitStore

    UnitStore(folder).save("0-0-0", Payload(box.marker))
    unit.write_bytes(unit.read_bytes()[:-3])


def _linked(box: Sandbox, folder: Path, unit: Path) -> None:
    target = box.here / "elsewhere.unit"
    target.write_bytes(pickle.dumps(Payload(box.marker)))
    unit.symlink_to(target)


def _units() -> list[Case]:
    plain = pickle.dumps(Payload)
    cases = [
        ("an unsigned pickle", lambda box, f, u: u.write_bytes(pickle.dumps(
            ShellPayload(box.marker)))),
        ("a forged signature line", lambda box, f, u: u.write_bytes(
            b"bounce_gym-unit " + b"0" * 64 + b"\n" + pickle.dumps(Payload(box.marker)))),
        ("a signature line without a signature", lambda box, f, u: u.write_bytes(
            b"bounce_gym-unit\n" + pickle.dumps(Payload(box.marker)))),
        ("a signature of another length", lambda box, f, u: u.write_bytes(
            b"bounce_gym-unit " + b"\xff" * 10 + b"\n" + plain)),
        ("signed by another user", _other_user),
        ("signed for another unit", _other_unit),
        ("signed for another sweep", _other_sweep),
        ("signed and cut short", _cut_short),
        ("empty", lambda box, f, u: u.write_bytes(b"")),
        ("one newline", lambda box, f, u: u.write_bytes(b"\n")),
        ("a megabyte of junk", lambda box, f, u: u.write_bytes(os.urandom(1 << 20))),
        ("a folder", lambda box, f, u: (u / "inside").mkdir(parents=True)),
        ("an empty folder", lambda box, f, u: u.mkdir()),
        ("a link to a payload", _linked),
        ("a dangling link", lambda box, f, u: u.symlink_to(box.here / "nowhere")),
        ("a pipe", lambda box, f, u: os.mkfifo(u)),
    ]
    return [_unit_case(name, plant) for name, plant in cases]


# -- monitor files -----------------------------------------------------------------------------
MONITOR_HEAD = '#{"t_start": 0.0, "env_id": "x"}\nr,l,t,is_success\n'
#: the rows of a monitor file before the hostile one
MONITOR_ROWS = "-1.0,10,0.1,True\n" * 5


def _monitor_case(name: str, content, expect: str) -> Case:
    """``bounce-gym curves out`` of a folder holding ``content`` (text, or made from the
    sandbox) as ``ppo_seed0.monitor.csv``."""
    def build(box: Sandbox) -> list[str]:
        text = content(box) if callable(content) else content
        if text is not None:
            box.write("out/ppo_seed0.monitor.csv", text)
        return ["curves", "out"]
    return Case("monitors", name, build, expect)


def _monitor_link(target: str):
    """A monitor file that is a link to ``target`` (in the case folder, or absolute), which
    holds a valid monitor file if its name ends in ``.csv``."""
    def plant(box: Sandbox) -> None:
        if target.endswith(".csv"):
            box.write(target, MONITOR_HEAD + MONITOR_ROWS)
        (box.here / "out").mkdir()
        (box.here / "out/ppo_seed0.monitor.csv").symlink_to(box.here / target)
    return plant


def _monitor_sparse(box: Sandbox) -> None:
    (box.here / "out").mkdir()
    _sparse(box, "out/ppo_seed0.monitor.csv", (1 << 30) + 1)


def _monitors() -> list[Case]:
    def row(r="-1.0", l="10", t="0.2", success="True") -> str:  # noqa: E741
        return MONITOR_HEAD + MONITOR_ROWS + f"{r},{l},{t},{success}\n"
    number = "not a number in [-1e+12, 1e+12]"
    length = "not an integer in [1, 1e+09]"
    cases = [
        ("r nan", row(r="nan"), f"line 8: column r holds 'nan', {number}"),
        ("r 1e999", row(r="1e999"), f"line 8: column r holds '1e999', {number}"),
        ("r -inf", row(r="-inf"), f"column r holds '-inf', {number}"),
        ("r 1e13", row(r="1e13"), f"column r holds '1e13', {number}"),
        ("r a word", row(r="many"), f"column r holds 'many', {number}"),
        ("l 1e32", row(l="1e32"), f"line 8: column l holds '1e32', {length}"),
        ("l 2.5", row(l="2.5"), f"column l holds '2.5', {length}"),
        ("l 0", row(l="0"), f"column l holds '0', {length}"),
        ("l negative", row(l="-3"), f"column l holds '-3', {length}"),
        ("t nan", row(t="nan"), f"column t holds 'nan', {number}"),
        ("is_success 7", row(success="7"), "column is_success holds '7', not a number in [0, 1]"),
        ("a row of five values", row(success="True,1"), "line 8 holds 5 values, its header 4"),
        ("a row of three values", row(success="").replace(",\n", "\n"),
         "line 8 holds 3 values, its header 4"),
        ("nine columns", '#{"t_start": 0}\nr,l,t,a,b,c,d,e,f\n',
         "expected at most 8 columns, none twice, got 9"),
        ("a column twice", '#{"t_start": 0}\nr,l,t,r\n', "none twice, got 4"),
        ("no l column", '#{"t_start": 0}\nr,t\n', "expected the columns r, l, t"),
        ("a line of 1 MiB", MONITOR_HEAD + "1" * (1 << 20) + "\n",
         "line 3 is longer than the 65536 bytes a line may hold"),
        ("a partial line of 1 MiB", MONITOR_HEAD + "1" * (1 << 20),
         "line 3 is longer than the 65536 bytes a line may hold"),
        ("a quoted value across lines", MONITOR_HEAD + '"-1.0\n' + "1\n" * 10 + '",10,0.1,1\n',
         "a quoted value spans lines"),
        ("not UTF-8", MONITOR_HEAD.encode() + b"\xff,1,1,1\n", "not UTF-8 text (byte 50)"),
        ("first line not JSON", "#{\nr,l,t\n", "its first line: not valid JSON"),
        ("no first line", "r,l,t\n-1,1,1\n", "expected a first line '#{...}'"),
        ("a link to a valid one", _monitor_link("elsewhere.csv"),
         "ppo_seed0.monitor.csv: is a symbolic link"),
        ("a dangling link", _monitor_link("nowhere"), "ppo_seed0.monitor.csv: is a symbolic link"),
        ("a link to a device", _monitor_link("/dev/zero"),
         "ppo_seed0.monitor.csv: is a symbolic link"),
        ("larger than 1 GiB", _monitor_sparse, "1073741825 bytes, more than the 1073741824"),
    ]
    return [_monitor_case(name, content, expect) for name, content, expect in cases]


def cases() -> list[Case]:
    """Every case of this module."""
    return [*_maps(), *_flows(), *_models(), *_units(), *_monitors()]
