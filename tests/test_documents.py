"""The one reader of YAML and JSON documents (`bounce_gym.documents`): every hostile document is
one line of the caller's error class, found before anything large or deep is built."""

import json

import pytest

from bounce_gym.documents import Limits, parse_document, read_document
from bounce_gym.errors import ConfigError, MapFormatError

#: ten levels of ten aliases each: 10**10 nodes once expanded, a few hundred bytes as written
LAUGHS = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 10)}]\n"
    for i in range(9))


def _yaml(text: str, **limits) -> object:
    return parse_document("t.yaml", text.encode(), limits=Limits(**limits))


def _json(text: str, **limits) -> object:
    return parse_document("t.json", text.encode(), fmt="json", limits=Limits(**limits))


def test_plain_documents_read_as_plain_data():
    assert _yaml("name: x\nseeds: [1, 2]\nkw: {a: 0.5, b: null}\n") == \
        {"name": "x", "seeds": [1, 2], "kw": {"a": 0.5, "b": None}}
    assert _json('{"a": [1, 2.5, true, null, "\\u00e9\\ud83d\\ude00"]}') == \
        {"a": [1, 2.5, True, None, "é😀"]}
    assert _yaml("\ufeffa: 1\n") == {"a": 1}  # a byte-order mark is dropped
    assert _yaml("") is None


@pytest.mark.parametrize(("text", "message"), [
    ("name: [unclosed", "t.yaml: not valid YAML: while parsing a flow sequence, did not find "
                        "expected ',' or ']' at line 2, column 1"),
    ("a: 1\n---\nb: 2\n", "t.yaml: not valid YAML: expected a single document in the stream, "
                          "but found another document at line 2, column 1"),
    ("a: 1\na: 2\n", "t.yaml: not valid YAML: found duplicate key 'a' at line 2, column 1"),
    ("1: x\n", "t.yaml: not valid YAML: found a key that is not a string: 1 at line 1, column 1"),
    ("on: x\n", "t.yaml: not valid YAML: found a key that is not a string: True (YAML reads yes, "
                "no, on and off as booleans: quote the key) at line 1, column 1"),
    ("a: !!python/object/apply:os.system [ls]\n",
     "t.yaml: not valid YAML: could not determine a constructor for the tag "
     "'tag:yaml.org,2002:python/object/apply:os.system' at line 1, column 4"),
    ('name: "a\\0b"\n', "t.yaml: control character U+0000 in the string 'a\\x00b' at line 1, "
                        "column 7; strings may not hold control characters"),
    ('name: "a\\x1bb"\n', "t.yaml: control character U+001B in the string"),
    ('name: "\\N"\n', "t.yaml: control character U+0085 in the string"),
    ("name: a\x00b\n", "t.yaml: not valid YAML: control characters are not allowed: U+0000 at "
                       "character 7"),
    ("name: a\x7fb\n", "t.yaml: not valid YAML: control characters are not allowed: U+007F"),
    ("a: &a [1, *a]\n", "t.yaml: the alias *a at line 1, column 11 names no anchor before it, "
                        "or a node that contains it"),
    ("a: *nowhere\n", "t.yaml: the alias *nowhere at line 1, column 4 names no anchor before it"),
])
def test_a_bad_yaml_document_is_one_line_naming_the_file(text, message):
    with pytest.raises(ConfigError) as info:
        _yaml(text)
    assert str(info.value).startswith(message) and "\n" not in str(info.value)


@pytest.mark.parametrize(("text", "message"), [
    ('{"a": 1', "t.json: not valid JSON: Expecting ',' delimiter at line 1, column 8"),
    ('{"a": 1, "a": 2}', "t.json: duplicate key 'a'"),
    ('{"a": NaN}', "t.json: NaN is not a JSON number; numbers must be finite"),
    ('{"a": -Infinity}', "t.json: -Infinity is not a JSON number"),
    ('{"a\\u0000": 1}', "t.json: control character U+0000 in the string 'a\\x00'"),
    ('["\\ud800"]', "t.json: control character U+D800 in the string"),
    ('[{"a": ["\\u009f"]}]', "t.json: control character U+009F"),
])
def test_a_bad_json_document_is_one_line_naming_the_file(text, message):
    with pytest.raises(ConfigError) as info:
        _json(text)
    assert str(info.value).startswith(message) and "\n" not in str(info.value)


@pytest.mark.timeout(60)  # a hang guard only
@pytest.mark.parametrize(("fmt", "text"), [
    ("yaml", "a: " + "[" * 5000 + "]" * 5000),  # used to end in RecursionError
    ("yaml", "".join("  " * k + "-\n" for k in range(3000))),  # block style, by indentation
    ("yaml", "a: " + "{b: " * 5000 + "1" + "}" * 5000),
    ("json", "[" * 100_000 + "]" * 100_000),
])
def test_deep_nesting_is_refused_before_it_is_built(fmt, text):
    with pytest.raises(ConfigError, match=r"lists and mappings nest .* deep; at most 32 are "
                                          "allowed"):
        parse_document("deep", text.encode(), fmt=fmt, limits=Limits(bytes=2**24))


def test_nesting_up_to_the_limit_is_read():
    nested: list = []
    for _ in range(30):
        nested = [nested]
    assert _yaml("a: " + "[" * 31 + "]" * 31) == {"a": nested}  # with the mapping, 32 deep
    assert _json("[" * 32 + "]" * 32, depth=32) is not None
    with pytest.raises(ConfigError, match="nest 3 deep; at most 2"):
        _json("[[[]]]", depth=2)


@pytest.mark.timeout(30)  # a hang guard only: the bomb is never expanded
def test_an_alias_bomb_is_refused_without_being_expanded():
    with pytest.raises(ConfigError, match=r"^t.yaml: more than 120000 nodes with its aliases "
                                          r"expanded at line \d+, column \d+; at most 120000 "
                                          r"are allowed$"):
        _yaml(LAUGHS)
    # the same under a key of a configuration, and as a merged mapping
    with pytest.raises(ConfigError, match="nodes with its aliases expanded"):
        _yaml("experiments:\n- name: x\n  env_kwargs:\n" +
              "".join(f"    {line}\n" for line in LAUGHS.splitlines()))
    with pytest.raises(ConfigError, match="at most 50 are allowed"):
        _yaml("a: &a {x: 1, y: 2, z: 3}\n" + "".join(f"k{i}: {{<<: *a}}\n" for i in range(20)),
              nodes=50)


def test_aliases_within_the_limit_are_read_and_counted_expanded():
    text = "a: &a [1, 2, 3]\nb: [*a, *a]\n"  # mapping 1, keys 2, list 4, b's list 1 + 2 x 4
    assert _yaml(text, nodes=16) == {"a": [1, 2, 3], "b": [[1, 2, 3], [1, 2, 3]]}
    with pytest.raises(ConfigError, match="more than 15 nodes"):
        _yaml(text, nodes=15)


def test_merged_keys_may_be_overridden_but_not_repeated():
    assert _yaml("base: &b {x: 1, y: 2}\nd:\n  <<: *b\n  x: 3\n")["d"] == {"x": 3, "y": 2}
    with pytest.raises(ConfigError, match="found duplicate key 'x'"):
        _yaml("base: &b {x: 1}\nd:\n  <<: *b\n  x: 3\n  x: 4\n")


def test_size_utf8_and_files(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text("a: " + "x" * 200, encoding="utf-8")
    with pytest.raises(ConfigError, match=rf"^config: {path}: 203 bytes; at most 100 are "
                                          "allowed$"):
        read_document(path, "config", limits=Limits(bytes=100))
    with pytest.raises(ConfigError, match="more than 100 bytes"):
        parse_document("b", b"x" * 101, limits=Limits(bytes=100))
    path.write_bytes("name: caf\xe9\n".encode("latin-1"))
    with pytest.raises(ConfigError, match=rf"^config: {path}: not UTF-8 text: byte 0xe9 at "
                                          "offset 9$"):
        read_document(path, "config")
    with pytest.raises(ConfigError, match=r"^config: file '.*none.yaml' does not exist$"):
        read_document(tmp_path / "none.yaml", "config")
    with pytest.raises(ConfigError, match=r"^config: file '.*' is not a file$"):
        read_document(tmp_path, "config")
    (tmp_path / "m.json").write_text(json.dumps({"a": [1]}), encoding="utf-8")
    assert read_document(tmp_path / "m.json", fmt="json") == {"a": [1]}


def test_the_callers_error_class_is_raised(tmp_path):
    path = tmp_path / "map.yaml"
    path.write_text(LAUGHS, encoding="utf-8")
    with pytest.raises(MapFormatError, match=rf"^{path}: more than 120000 nodes"):
        read_document(path, error=MapFormatError)
    with pytest.raises(ValueError, match="fmt: expected one of"):
        parse_document("x", b"", fmt="toml")


def test_an_aliased_string_counts_its_characters_each_time():
    # one aliased row used to make a 120 KB map file into a 20,000 x 20,000 grid (18 s, 3.5 GB)
    text = "row: &r '" + "." * 1000 + "'\ngrid: [" + ", ".join(["*r"] * 9) + "]\n"
    # the row, 1,000 characters, ten times, and the keys' 7
    assert len(_yaml(text, bytes=10_007)["grid"]) == 9
    with pytest.raises(ConfigError, match=r"^t.yaml: more than 10006 characters of strings "
                                          r"with its aliases expanded at line 2, column \d+"):
        _yaml(text, bytes=10_006)


@pytest.mark.parametrize(("text", "fmt"), [
    ("a: 1" + "0" * 5000, "yaml"),  # Python refuses to convert more than 4,300 digits
    ("a: 0x" + "f" * 90, "yaml"),  # short as written, 10**108 in value
    ("a: 1" + ":59" * 60, "yaml"),  # sexagesimal
    ("[1" + "0" * 100 + "]", "json"),
])
def test_integers_have_at_most_100_digits(text, fmt):
    with pytest.raises(ConfigError, match=r"is too large; integers lie between -10\*\*100 and "
                                          r"10\*\*100"):
        parse_document("t", text.encode(), fmt=fmt)
    assert _yaml("a: " + "9" * 100) == {"a": 10**100 - 1}
    assert _yaml("a: [0, 007, 0x10, -12, 1_000]") == {"a": [0, 7, 16, -12, 1000]}


def test_a_json_number_beyond_a_float_is_refused():
    with pytest.raises(ConfigError, match="the number -1e999 is too large; numbers must be "
                                          "finite"):
        _json("[-1e999]")
    assert _json("[1e308, 1.5]") == [1e308, 1.5]
