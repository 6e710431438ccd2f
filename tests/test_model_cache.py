"""bounce_gym.model_cache: models kept as data, rebuilt (None) when a file is not usable."""

import warnings

import numpy as np
import pytest

from bounce_gym import model_cache


def test_round_trip_and_missing_file(tmp_path):
    path = tmp_path / "m" / "k.npz"
    assert model_cache.load_cached(path, 1, "k") is None  # missing: no warning
    model_cache.store(path, {"format": 1, "fingerprint": "k", "n": 3}, {"a": np.arange(3)})
    header, arrays = model_cache.load_cached(path, 1, "k")
    assert header == {"format": 1, "fingerprint": "k", "n": 3}
    assert list(arrays) == ["a"] and np.array_equal(arrays["a"], np.arange(3))
    assert [p.name for p in path.parent.iterdir()] == ["k.npz"]  # no temporary left


@pytest.mark.parametrize("fmt, key", [(2, "k"), (1, "other")])
def test_other_format_or_fingerprint_is_not_used(tmp_path, fmt, key):
    path = tmp_path / "k.npz"
    model_cache.store(path, {"format": 1, "fingerprint": "k"}, {"a": np.zeros(2)})
    with pytest.warns(UserWarning, match="does not match"):
        assert model_cache.load_cached(path, fmt, key) is None


@pytest.mark.parametrize("content", [
    b"", b"PK\x03\x04 broken", "header-less", "pickled", "bad-header"])
def test_damaged_files_are_not_used(tmp_path, content):
    path = tmp_path / "k.npz"
    if content == "header-less":
        np.savez(path, a=np.zeros(2))
    elif content == "pickled":
        np.savez(path, header=np.array([{"format": 1}], dtype=object))
    elif content == "bad-header":
        np.savez(path, header=np.frombuffer(b'{"format": 1, "fingerprint": "k"', np.uint8))
    else:
        path.write_bytes(content)
    with pytest.warns(UserWarning, match="unusable"):
        assert model_cache.load_cached(path, 1, "k") is None


def test_an_array_may_not_shadow_the_header(tmp_path):
    with pytest.raises(ValueError, match="header"):
        model_cache.store(tmp_path / "k.npz", {}, {"header": np.zeros(1)})


def test_home_cache_folder_is_under_the_package_home(monkeypatch, tmp_path):
    monkeypatch.setenv("BOUNCE_GYM_HOME", str(tmp_path))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert model_cache.cache_folder("x") == tmp_path / "cache" / "x"
