"""Map files (bounce_gym.worlds.io): schema, round trips, error messages, atomic saving."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
import yaml

from bounce_gym.errors import InvalidWorldError, MapFormatError
from bounce_gym.worlds import World, from_dict, load, parse_ascii, save, to_ascii, world_from_grid
from bounce_gym.worlds import io as map_io

SUFFIXES = [".json", ".yaml", ".yml"]

GRID_ROWS = [
    "......",
    ".##...",
    ".##..#",
    "......",
]


@pytest.fixture
def polygon_world() -> World:
    # Non-round floats check that coordinates survive the text format bit for bit.
    outer = [(0.0, 0.0), (10.1, 0.0), (10.1, 7.3), (1 / 3, 7.3)]
    hole = [(2.0, 2.0), (2.0, 4.0), (4.0 + 1e-7, 4.0), (4.0, 2.0)]  # clockwise
    return World(outer, [hole, [(6, 1), (8, 1), (7, 2.5)]], name="room with holes")


@pytest.fixture
def grid_world() -> World:
    return world_from_grid(parse_ascii(GRID_ROWS), 1.0, name="tiny grid")


def _only_file(directory, name):
    assert sorted(p.name for p in directory.iterdir()) == [name]


# -- round trips ------------------------------------------------------------------------------
@pytest.mark.parametrize("suffix", SUFFIXES)
def test_polygon_round_trip(tmp_path, polygon_world, suffix):
    path = save(polygon_world, tmp_path / f"map{suffix}")
    loaded = load(path)
    assert loaded == polygon_world
    assert loaded.name == "room with holes"
    assert len(loaded.holes) == 2
    _only_file(tmp_path, f"map{suffix}")


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_grid_round_trip(tmp_path, grid_world, suffix):
    path = save(grid_world, tmp_path / f"grid{suffix}", grid=1.0, description="a test grid")
    raw = map_io.load_dict(path)
    assert raw["grid"] == GRID_ROWS  # top row first, as drawn
    assert raw["cell_size"] == 1.0
    assert raw["description"] == "a test grid"
    assert "outer" not in raw
    assert load(path) == grid_world
    assert load(path).name == "tiny grid"


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_grid_round_trip_other_cell_size(tmp_path, suffix):
    world = world_from_grid(parse_ascii(GRID_ROWS), 0.25, name="small cells")
    path = save(world, tmp_path / f"g{suffix}", grid=0.25)
    assert map_io.load_dict(path)["cell_size"] == 0.25
    loaded = load(path)
    assert loaded == world
    assert loaded.bounds == (0.0, 0.0, 1.5, 1.0)


def test_grid_given_as_array_or_true(tmp_path, grid_world):
    free = parse_ascii(GRID_ROWS)
    by_array = map_io.to_dict(grid_world, grid=free)
    by_true = map_io.to_dict(grid_world, grid=True)
    assert by_array == by_true
    assert by_array["grid"] == GRID_ROWS


def test_grid_form_must_describe_the_world(tmp_path, polygon_world, grid_world):
    with pytest.raises(MapFormatError, match="grid"):
        save(polygon_world, tmp_path / "x.json", grid=1.0)
    other = parse_ascii(GRID_ROWS)
    other[0, 0] = False
    with pytest.raises(MapFormatError, match="grid"):
        save(grid_world, tmp_path / "y.yaml", grid=other)
    assert list(tmp_path.iterdir()) == []


def test_from_dict_inverts_to_dict(polygon_world, grid_world):
    assert from_dict(map_io.to_dict(polygon_world)) == polygon_world
    assert from_dict(map_io.to_dict(grid_world, grid=1.0)) == grid_world
    assert from_dict(polygon_world.to_dict()) == polygon_world  # World's own polygon form


def test_files_are_readable(tmp_path, polygon_world):
    text = save(polygon_world, tmp_path / "m.json").read_text()
    assert "\n    [0.0, 0.0],\n" in text  # one vertex per line
    assert json.loads(text)["name"] == "room with holes"
    ytext = save(polygon_world, tmp_path / "m.yaml").read_text()
    assert ytext.startswith("name: room with holes\n")
    assert "- [0.0, 0.0]" in ytext


def test_description_with_brackets_survives_json(tmp_path, grid_world):
    desc = 'tricky "text" [\n  1,\n  2\n] and [ 3, 4 ]'
    path = save(grid_world, tmp_path / "d.json", grid=1.0, description=desc)
    assert map_io.load_dict(path)["description"] == desc


def test_optional_keys_default(tmp_path):
    assert from_dict({"name": "t", "outer": [[0, 0], [1, 0], [0, 1]]}).holes == ()
    world = from_dict({"name": "g", "grid": ["..", ".."]})
    assert world.bounds == (0.0, 0.0, 2.0, 2.0)


def test_closing_vertex_and_orientation_are_normalised():
    cw_closed = [[0, 0], [0, 2], [2, 2], [2, 0], [0, 0]]
    world = from_dict({"name": "sq", "outer": cw_closed})
    assert len(world.outer) == 4
    assert world.polygon.equals(World([(0, 0), (2, 0), (2, 2), (0, 2)]).polygon)
    assert world.outer.tolist() == [[2, 0], [2, 2], [0, 2], [0, 0]]  # reversed to CCW


# -- malformed maps ---------------------------------------------------------------------------
SQUARE = [[0, 0], [4, 0], [4, 4], [0, 4]]
HOLE = [[1, 1], [2, 1], [2, 2], [1, 2]]

MALFORMED = [
    # (id, dict, text expected in the message: the field)
    ("missing-name", {"outer": SQUARE}, "'name'"),
    ("name-not-str", {"name": 3, "outer": SQUARE}, "'name'"),
    ("name-empty", {"name": " ", "outer": SQUARE}, "'name'"),
    ("unknown-key", {"name": "m", "outer": SQUARE, "colour": "red"}, "'colour'"),
    ("neither-form", {"name": "m"}, "'outer' and 'grid'"),
    ("both-forms", {"name": "m", "outer": SQUARE, "grid": [".."]}, "'outer' and 'grid'"),
    ("description-type", {"name": "m", "outer": SQUARE, "description": 5}, "'description'"),
    ("outer-not-list", {"name": "m", "outer": "square"}, "'outer'"),
    ("outer-too-short", {"name": "m", "outer": [[0, 0], [1, 1]]}, "'outer'"),
    ("vertex-length", {"name": "m", "outer": [[0, 0], [1, 0, 0], [0, 1]]}, "'outer' vertex 1"),
    ("vertex-string", {"name": "m", "outer": [[0, 0], [1, "0"], [0, 1]]}, "'outer' vertex 1"),
    ("vertex-bool", {"name": "m", "outer": [[0, 0], [True, 0], [0, 1]]}, "'outer' vertex 1"),
    ("holes-not-list", {"name": "m", "outer": SQUARE, "holes": 7}, "'holes'"),
    ("hole-vertex", {"name": "m", "outer": SQUARE, "holes": [[[1, 1], [2], [1, 2]]]},
     "'holes[0]' vertex 1"),
    ("hole-flat", {"name": "m", "outer": SQUARE, "holes": HOLE}, "'holes[0]'"),
    ("cell-size-with-outer", {"name": "m", "outer": SQUARE, "cell_size": 1}, "'cell_size'"),
    ("holes-with-grid", {"name": "m", "grid": [".."], "holes": []}, "'holes'"),
    ("grid-not-list", {"name": "m", "grid": "...."}, "'grid'"),
    ("grid-empty", {"name": "m", "grid": []}, "'grid'"),
    ("grid-not-strings", {"name": "m", "grid": [[1, 0], [0, 1]]}, "'grid'"),
    ("grid-bad-char", {"name": "m", "grid": ["..", ".x"]}, "grid"),
    ("grid-ragged", {"name": "m", "grid": ["..", "..."]}, "grid"),
    ("grid-disconnected", {"name": "m", "grid": [".#.", ".#."]}, "grid"),
    ("grid-pinch", {"name": "m", "grid": [".#", "#."]}, "grid"),
    ("grid-all-blocked", {"name": "m", "grid": ["##"]}, "grid"),
    ("cell-size-negative", {"name": "m", "grid": [".."], "cell_size": -1}, "'cell_size'"),
    ("cell-size-string", {"name": "m", "grid": [".."], "cell_size": "1"}, "'cell_size'"),
    ("cell-size-bool", {"name": "m", "grid": [".."], "cell_size": True}, "'cell_size'"),
    ("cell-size-nan", {"name": "m", "grid": [".."], "cell_size": float("nan")}, "'cell_size'"),
    ("outer-self-intersects", {"name": "m", "outer": [[0, 0], [2, 2], [2, 0], [0, 2]]},
     "outer ring"),
    ("hole-outside", {"name": "m", "outer": SQUARE, "holes": [[[5, 5], [6, 5], [6, 6]]]},
     "hole 0"),
]


@pytest.mark.parametrize(("case", "field"), [(c[1], c[2]) for c in MALFORMED],
                         ids=[c[0] for c in MALFORMED])
def test_malformed_dict_names_the_field(case, field):
    with pytest.raises(MapFormatError) as info:
        from_dict(case)
    assert field in str(info.value)
    assert isinstance(info.value, InvalidWorldError)  # MapFormatError is an InvalidWorldError


def _has_nan(case: dict) -> bool:
    return any(isinstance(v, float) and np.isnan(v) for v in case.values())


FILE_CASES = [
    pytest.param(suffix, c[1], c[2], id=f"{c[0]}{suffix}")
    for c in MALFORMED
    for suffix in (".json", ".yaml")
    if not (suffix == ".json" and _has_nan(c[1]))  # JSON has no NaN (see test_unreadable_files)
]


@pytest.mark.parametrize(("suffix", "case", "field"), FILE_CASES)
def test_malformed_file_names_file_and_field(tmp_path, suffix, case, field):
    path = tmp_path / f"bad{suffix}"
    text = json.dumps(case) if suffix == ".json" else yaml.safe_dump(case)
    path.write_text(text)
    with pytest.raises(MapFormatError) as info:
        load(path)
    assert str(path) in str(info.value)
    assert field in str(info.value)


def test_unknown_key_message_lists_allowed_keys():
    with pytest.raises(MapFormatError) as info:
        from_dict({"name": "m", "outer": SQUARE, "hole": []})
    msg = str(info.value)
    for key in ("name", "description", "outer", "holes", "grid", "cell_size"):
        assert repr(key) in msg


@pytest.mark.parametrize(
    ("name", "text", "expected"),
    [
        ("syntax.json", '{"name": "m", "outer": [[0, 0], [1, 0], [0, 1]]', "not valid JSON"),
        ("syntax.yaml", "name: m\nouter: [[0, 0], [1, 0]\n", "not valid YAML"),
        ("empty.yaml", "", "empty file"),
        ("list.json", "[1, 2, 3]", "mapping"),
        ("scalar.yml", "just text\n", "mapping"),
        ("dup.json", '{"name": "a", "name": "b", "outer": [[0, 0], [1, 0], [0, 1]]}',
         "duplicate key 'name'"),
        ("dup.yaml", "name: a\nname: b\nouter: [[0, 0], [1, 0], [0, 1]]\n", "duplicate key 'name'"),
        ("nan.json", '{"name": "m", "outer": [[0, 0], [NaN, 0], [0, 1]]}', "NaN"),
        ("comment.yaml", "name: m\ngrid:\n- #..\n- ...\n", "'grid'"),  # unquoted '#' row
    ],
)
def test_unreadable_files(tmp_path, name, text, expected):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(MapFormatError) as info:
        load(path)
    assert str(path) in str(info.value)
    assert expected in str(info.value)


def test_not_utf8(tmp_path):
    path = tmp_path / "latin1.yaml"
    path.write_bytes("name: caf\xe9\nouter: [[0, 0], [1, 0], [0, 1]]\n".encode("latin-1"))
    with pytest.raises(MapFormatError, match="UTF-8"):
        load(path)


@pytest.mark.parametrize("name", ["map.txt", "map", "map.json.bak", "map.toml"])
def test_unknown_suffix(tmp_path, polygon_world, name):
    path = tmp_path / name
    path.write_text("{}")
    with pytest.raises(MapFormatError) as info:
        load(path)
    for allowed in SUFFIXES:
        assert allowed in str(info.value)
    with pytest.raises(MapFormatError, match="suffix"):
        save(polygon_world, tmp_path / ("new_" + name))
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_suffix_is_case_insensitive(tmp_path, polygon_world):
    assert load(save(polygon_world, tmp_path / "MAP.YAML")) == polygon_world


def test_missing_file_is_a_map_format_error(tmp_path):
    with pytest.raises(MapFormatError, match=r"^file '.*nope.yaml' does not exist$"):
        load(tmp_path / "nope.yaml")


def test_bad_save_arguments(tmp_path, polygon_world):
    with pytest.raises(MapFormatError, match="world"):
        save(polygon_world.to_dict(), tmp_path / "a.json")
    with pytest.raises(MapFormatError, match="cell_size"):
        save(polygon_world, tmp_path / "a.json", grid=-1.0)
    with pytest.raises(MapFormatError, match="grid"):
        save(polygon_world, tmp_path / "a.json", grid="yes")
    with pytest.raises(MapFormatError, match="description"):
        save(polygon_world, tmp_path / "a.json", description=3)
    assert list(tmp_path.iterdir()) == []


# -- atomic saving ----------------------------------------------------------------------------
def test_save_overwrites_and_leaves_no_temp_files(tmp_path, polygon_world, grid_world):
    path = tmp_path / "m.yaml"
    save(polygon_world, path)
    save(grid_world, path, grid=1.0)
    assert load(path) == grid_world
    _only_file(tmp_path, "m.yaml")


def test_failed_write_keeps_old_file_and_cleans_up(tmp_path, polygon_world, grid_world,
                                                   monkeypatch):
    path = save(polygon_world, tmp_path / "m.json")
    before = path.read_bytes()

    def broken_replace(src, dst):
        raise OSError("disk on fire")

    monkeypatch.setattr(map_io.os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk on fire"):
        save(grid_world, path, grid=1.0)
    assert path.read_bytes() == before
    _only_file(tmp_path, "m.json")


def test_saved_file_mode_follows_umask(tmp_path, polygon_world):
    reference = tmp_path / "ref.txt"
    reference.write_text("x")
    path = save(polygon_world, tmp_path / "m.json")
    assert (path.stat().st_mode & 0o777) == (reference.stat().st_mode & 0o777)


def test_save_returns_path_and_accepts_strings(tmp_path, polygon_world):
    out = save(polygon_world, os.fspath(tmp_path / "s.yml"))
    assert out == tmp_path / "s.yml"
    assert load(os.fspath(out)) == polygon_world


def test_to_ascii_matches_file_rows(grid_world):
    assert to_ascii(grid_world.occupancy(1.0)) == GRID_ROWS


# -- size and nesting limits ------------------------------------------------------------------
@pytest.mark.timeout(30)  # a hang guard only
@pytest.mark.parametrize("suffix, text", [
    (".json", "[" * 100_000 + "]" * 100_000),
    (".yaml", "[" * 100_000 + "]" * 100_000),
    (".yaml", "".join("  " * k + "-\n" for k in range(10_000))),  # block style, by indentation
])
def test_deep_nesting_is_a_map_format_error(tmp_path, suffix, text):
    # used to end in RecursionError
    path = tmp_path / f"deep{suffix}"
    path.write_text(text)
    with pytest.raises(MapFormatError, match="nest .* deep; at most 32 are allowed"):
        load(path)


def test_nesting_within_the_limit_reaches_the_schema_check(tmp_path):
    path = tmp_path / "nested.json"
    path.write_text("[" * 32 + "]" * 32)
    with pytest.raises(MapFormatError, match="expected a mapping"):
        load(path)


def test_too_large_a_file_is_a_map_format_error(tmp_path, monkeypatch):
    monkeypatch.setattr(map_io, "MAX_FILE_BYTES", 100)
    path = tmp_path / "big.json"
    path.write_text(json.dumps({"name": "x", "outer": [[0, 0], [1, 0], [0, 1]] * 10}))
    with pytest.raises(MapFormatError, match=r"bytes; at most 100 are allowed"):
        load(path)


def test_too_many_vertices_is_a_map_format_error(monkeypatch):
    monkeypatch.setattr(map_io, "MAX_VERTICES", 5)
    ring = [[np.cos(a), np.sin(a)] for a in np.linspace(0, 6, 6)]
    with pytest.raises(MapFormatError, match=r"'outer' must be .* at most 5, got 6 vertices"):
        from_dict({"name": "x", "outer": ring})


@pytest.mark.timeout(30)  # a hang guard only: the aliases are never expanded
def test_an_alias_bomb_is_a_map_format_error(tmp_path):
    lines = ["name: bomb", "outer: [[0, 0], [1, 0], [0, 1]]", "description:",
             "- &a [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"- &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 10)}]" for i in range(9)]
    path = tmp_path / "bomb.yaml"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(MapFormatError, match=rf"^{path}: more than {2**25} nodes with its "
                                             "aliases expanded"):
        load(path)


@pytest.mark.parametrize(("name", "text", "expected"), [
    ("nul.json", '{"name": "a\\u0000", "outer": [[0, 0], [1, 0], [0, 1]]}',
     "control character U+0000"),
    ("esc.yaml", 'name: "\\e[31mred"\nouter: [[0, 0], [1, 0], [0, 1]]\n',
     "control character U+001B"),
    ("key.yaml", "name: m\n1: 2\nouter: [[0, 0], [1, 0], [0, 1]]\n",
     "found a key that is not a string: 1"),
    ("recursive.yaml", "name: m\nouter: &o [[0, 0], [1, 0], *o]\n",
     "the alias *o at line 2, column 28 names no anchor before it, or a node that contains it"),
])
def test_hostile_text_in_a_map_is_a_map_format_error(tmp_path, name, text, expected):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(MapFormatError) as info:
        load(path)
    assert str(info.value).startswith(f"{path}: ") and expected in str(info.value)
