"""bounce_gym.model_cache: models kept as data, rebuilt (None) when a file is not usable, built
once when several processes ask at once."""

import multiprocessing
import os
import time
import warnings

import numpy as np
import pytest

from bounce_gym import model_cache
from bounce_gym.errors import ConfigError


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
    monkeypatch.delenv(model_cache.CACHE_VARIABLE, raising=False)
    monkeypatch.setenv("BOUNCE_GYM_HOME", str(tmp_path))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert model_cache.cache_folder("x") == tmp_path / "cache" / "x"


def test_the_cache_variable_names_the_folder_and_must_be_absolute(monkeypatch, tmp_path):
    monkeypatch.setenv("BOUNCE_GYM_HOME", str(tmp_path / "home"))
    monkeypatch.setenv(model_cache.CACHE_VARIABLE, str(tmp_path / "shared"))
    assert model_cache.cache_folder("x") == tmp_path / "shared" / "x"
    for bad, message in [("relative/cache", "absolute"), ("~nosuchuser-xyz/c", "no such user")]:
        monkeypatch.setenv(model_cache.CACHE_VARIABLE, bad)
        with pytest.raises(ConfigError, match=message):
            model_cache.cache_folder("x")


def _build_once(path, log, ready):
    """`model_cache.cached` of one model in a process of its own: each build is a line in
    ``log`` (it takes 0.3 s, so that the other process asks while it runs)."""
    ready.wait()

    def load():
        found = model_cache.load_cached(path, 1, "k")
        return None if found is None else found[1]["a"]

    def build():
        with open(log, "a") as fh:
            fh.write(f"{os.getpid()}\n")
        time.sleep(0.3)
        model_cache.store(path, {"format": 1, "fingerprint": "k"}, {"a": np.arange(4)})
        return np.arange(4)

    assert np.array_equal(model_cache.cached(path, load, build), np.arange(4))


def test_processes_asking_for_the_same_model_at_once_build_it_once(tmp_path):
    path, log = tmp_path / "models" / "k.npz", tmp_path / "builds.txt"
    spawn = multiprocessing.get_context("spawn")
    ready = spawn.Event()
    workers = [spawn.Process(target=_build_once, args=(path, log, ready)) for _ in range(3)]
    for worker in workers:
        worker.start()
    ready.set()
    for worker in workers:
        worker.join(60)
    assert [worker.exitcode for worker in workers] == [0, 0, 0]
    assert len(log.read_text().split()) == 1


def test_a_model_that_is_there_is_read_from_a_read_only_folder(tmp_path):
    path = tmp_path / "ro" / "k.npz"
    model_cache.store(path, {"format": 1, "fingerprint": "k"}, {"a": np.arange(2)})
    path.parent.chmod(0o500)
    try:
        found = model_cache.cached(path, lambda: model_cache.load_cached(path, 1, "k"),
                                   lambda: pytest.fail("built although stored"))
    finally:
        path.parent.chmod(0o700)
    assert np.array_equal(found[1]["a"], np.arange(2))
    assert sorted(p.name for p in path.parent.iterdir()) == ["k.npz"]  # no lock file either
