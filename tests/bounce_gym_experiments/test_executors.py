"""The shared executor layer (`bounce_gym_experiments.executors`): the unit store, retries, failures that
leave the other units running, and a worker that dies, on the in-process executor and the local
process pool (the Ray executor: test_ray_executor.py)."""

import os
import pickle
from pathlib import Path

import pytest
import sweep_units

from bounce_gym.errors import ConfigError, MissingExtraError
from bounce_gym_experiments.executors import (
    InProcessExecutor,
    PoolExecutor,
    Unit,
    UnitFailure,
    UnitStore,
    check_ray_cluster,
    executor_settings,
    init_ray,
    make_executor,
    ray_endpoint,
)

LOCAL = [pytest.param(1, id="in-process"), pytest.param(2, id="pool")]


def _squares(n: int) -> list[Unit]:
    return [Unit(f"sq{k}", sweep_units.square, (k,)) for k in range(n)]


def test_the_store_keeps_results_atomically_one_signed_file_per_unit(tmp_path):
    store = UnitStore(tmp_path / "units")
    with pytest.raises(FileNotFoundError):
        store.load("a")
    store.save("a", {"rows": [1, 2]})
    assert store.load("a") == {"rows": [1, 2]} and store.stored(["a", "b"]) == {"a": {"rows": [1, 2]}}
    assert [p.name for p in (tmp_path / "units").iterdir()] == ["a.unit"]
    head, _, data = (tmp_path / "units/a.unit").read_bytes().partition(b"\n")
    assert head.startswith(b"bounce_gym-unit ") and len(head.split()[1]) == 64
    assert pickle.loads(data) == {"rows": [1, 2]}


class _Plant:
    """Unpickled, it creates ``marker``: what a planted unit file could run."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (Path(self.marker),))


def _forged(store, marker):
    """Unit files that must not be unpickled: a plain pickle, one signed with another key, one
    cut short, one signed for another key of the store, a link to a good one, a pipe."""
    payload = pickle.dumps(_Plant(marker))
    good = (store.folder / "good.unit").read_bytes()
    head = good.partition(b"\n")[0]
    return {
        "plain pickle": payload,
        "other key": b"bounce_gym-unit " + b"0" * 64 + b"\n" + payload,
        "no newline": b"bounce_gym-unit " + head.split()[1],
        "cut short": good[:-5],
        "signed for another unit": good,
        "payload swapped": head + b"\n" + payload,
    }


def test_unit_files_the_user_did_not_sign_are_never_unpickled(tmp_path, capsys):
    store = UnitStore(tmp_path / "units")
    store.save("good", _Plant(tmp_path / "signed-ran"))
    store.load("good")
    assert (tmp_path / "signed-ran").exists()  # the control: a signed file is unpickled
    marker = tmp_path / "planted-ran"
    forged = _forged(store, marker)
    keys = [f"k{n}" for n in range(len(forged))]
    for key, data in zip(keys, forged.values(), strict=True):
        (tmp_path / "units" / f"{key}.unit").write_bytes(data)
    os.symlink(tmp_path / "units/good.unit", tmp_path / "units/link.unit")
    os.mkfifo(tmp_path / "units/pipe.unit")
    assert store.stored([*keys, "link", "pipe", "missing"]) == {}
    assert not marker.exists()
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == len(keys) + 2
    assert all(line.startswith("warning: ") and line.endswith("running the unit again")
               for line in lines)
    assert "symbolic link" in lines[-2] and "not a regular file" in lines[-1]


def test_a_signed_unit_file_this_code_cannot_unpickle_is_a_warning_too(tmp_path, capsys):
    from bounce_gym.trust import sign

    store = UnitStore(tmp_path / "units")
    data = b"cno_such_module_here\nThing\n."  # a pickle of a class that is gone
    (tmp_path / "units").mkdir()
    (tmp_path / "units/a.unit").write_bytes(
        b"bounce_gym-unit " + sign(data, "unit units/a").encode() + b"\n" + data)
    assert store.stored(["a"]) == {}
    assert "cannot be unpickled (ModuleNotFoundError" in capsys.readouterr().err


def test_a_unit_file_signed_by_another_user_runs_again(tmp_path, monkeypatch, capsys):
    from bounce_gym.trust import HOME_VARIABLE

    calls = tmp_path / "calls"
    units = [Unit(u.key, sweep_units.count_calls, (calls, u.fn, *u.args)) for u in _squares(3)]
    monkeypatch.setenv(HOME_VARIABLE, str(tmp_path / "someone-else"))
    make_executor(workers=1).run(units, UnitStore(tmp_path / "units"), progress=False)
    monkeypatch.undo()
    results, _ = make_executor(workers=1).run(units, UnitStore(tmp_path / "units"),
                                              progress=False)
    assert results == {"sq0": 0, "sq1": 1, "sq2": 4}
    assert len(list(calls.iterdir())) == 6  # every unit ran again under this user's key
    assert capsys.readouterr().err.count("does not match your key") == 3


def test_the_store_needs_the_users_key_before_any_unit_runs(tmp_path, monkeypatch):
    from bounce_gym.trust import HOME_VARIABLE

    (tmp_path / "home").write_text("a file, not a folder")
    monkeypatch.setenv(HOME_VARIABLE, str(tmp_path / "home"))
    with pytest.raises(ConfigError, match=HOME_VARIABLE):
        UnitStore(tmp_path / "units")


@pytest.mark.parametrize("key", ["", "a/b", "../x", ".hidden", "a b", "-x"])
def test_a_unit_key_must_be_a_plain_file_name(key):
    with pytest.raises(ValueError, match="unit key"):
        Unit(key, sweep_units.square, (1,))


def test_unit_keys_must_be_unique(tmp_path):
    units = [Unit("a", sweep_units.square, (1,)), Unit("a", sweep_units.square, (2,))]
    with pytest.raises(ValueError, match="repeated: \\['a'\\]"):
        make_executor(workers=1).run(units, UnitStore(tmp_path), progress=False)


@pytest.mark.parametrize("workers", LOCAL)
def test_every_unit_runs_once_and_is_stored(tmp_path, workers):
    store = UnitStore(tmp_path / "units")
    results, failures = make_executor(workers=workers).run(_squares(5), store, progress=False)
    assert results == {f"sq{k}": k * k for k in range(5)} and failures == []
    assert all(store.load(f"sq{k}") == k * k for k in range(5))


def test_the_pool_runs_units_in_other_processes(tmp_path):
    import os

    units = [Unit(f"p{k}", sweep_units.pid_of, (k,)) for k in range(4)]
    results, _ = make_executor(workers=2).run(units, UnitStore(tmp_path), progress=False)
    assert os.getpid() not in results.values()


@pytest.mark.parametrize("workers", LOCAL)
def test_a_restarted_sweep_skips_stored_units(tmp_path, workers):
    store, calls = UnitStore(tmp_path / "units"), tmp_path / "calls"
    store.save("sq1", 1)
    store.save("sq3", 9)
    units = [Unit(u.key, sweep_units.count_calls, (calls, u.fn, *u.args)) for u in _squares(5)]
    results, failures = make_executor(workers=workers).run(units, store, progress=False)
    assert results == {f"sq{k}": k * k for k in range(5)} and failures == []
    assert len(list(calls.iterdir())) == 3


@pytest.mark.parametrize("workers", LOCAL)
def test_a_unit_failing_for_good_is_reported_while_the_others_complete(tmp_path, workers):
    units = [*_squares(3), Unit("bad", sweep_units.fail, (7,))]
    store = UnitStore(tmp_path / "units")
    results, failures = make_executor(workers=workers, retries=2).run(units, store,
                                                                      progress=False)
    assert results == {"sq0": 0, "sq1": 1, "sq2": 4}
    assert failures == [UnitFailure("bad", "ValueError: unit 7 cannot be done", 3)]
    assert store.stored(["bad"]) == {}


@pytest.mark.parametrize("workers", LOCAL)
def test_a_unit_that_raises_once_is_retried(tmp_path, workers):
    units = [*_squares(2), Unit("x", sweep_units.raise_once, (tmp_path / "m", sweep_units.square,
                                                             6))]
    results, failures = make_executor(workers=workers, retries=1).run(
        units, UnitStore(tmp_path / "units"), progress=False)
    assert results == {"sq0": 0, "sq1": 1, "x": 36} and failures == []


def test_no_retries_means_one_attempt(tmp_path):
    units = [Unit("x", sweep_units.raise_once, (tmp_path / "m", sweep_units.square, 6))]
    _, failures = make_executor(workers=1, retries=0).run(units, UnitStore(tmp_path / "u"),
                                                          progress=False)
    assert failures == [UnitFailure("x", "RuntimeError: injected failure", 1)]


def test_a_pool_worker_that_dies_is_replaced_and_its_unit_retried(tmp_path):
    units = [*_squares(4), Unit("x", sweep_units.die_once, (tmp_path / "m", sweep_units.square,
                                                           5)), *_squares(8)[4:]]
    results, failures = make_executor(workers=2, retries=2).run(
        units, UnitStore(tmp_path / "units"), progress=False)
    assert failures == []
    assert results == {**{f"sq{k}": k * k for k in range(8)}, "x": 25}


@pytest.mark.slow  # three pools die and restart: ~45 s on two cores
def test_a_pool_worker_that_always_dies_fails_for_good(tmp_path):
    units = [Unit("x", sweep_units.die, (5,)), *_squares(5)]
    results, failures = make_executor(workers=2, retries=2).run(
        units, UnitStore(tmp_path / "units"), progress=False)
    assert failures == [UnitFailure("x", "worker died", 3)]
    assert results == {f"sq{k}": k * k for k in range(5)}


def test_the_progress_bar_counts_stored_units_from_the_start(tmp_path, capsys):
    store = UnitStore(tmp_path)
    store.save("sq0", 0)
    make_executor(workers=1).run(_squares(2), store, desc="squares")
    err = capsys.readouterr().err
    assert "squares:  50%" in err and "squares: 100%" in err and "2/2" in err


def test_make_executor_picks_the_executor_and_checks_its_arguments():
    assert isinstance(make_executor(workers=1), InProcessExecutor)
    pool = make_executor("local", workers=3, retries=0)
    assert isinstance(pool, PoolExecutor) and (pool.workers, pool.retries) == (3, 0)
    assert make_executor().workers >= 1


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "dask"}, r"executor.kind: expected one of \('local', 'ray'\), got 'dask'"),
        ({"workers": 0}, r"executor.workers: expected an integer in \[1, 1024\], got 0"),
        ({"workers": True}, r"executor.workers: expected an integer in \[1, 1024\], got True"),
        ({"workers": 10**6}, r"executor.workers: expected an integer in \[1, 1024\]"),
        ({"retries": -1}, r"executor.retries: expected an integer in \[0, 100\], got -1"),
        ({"retries": 10**9}, r"executor.retries: expected an integer in \[0, 100\]"),
        ({"address": "localhost:6379"}, "executor.address: only for the ray executor"),
        ({"kind": "ray", "address": " "}, "executor.address: expected a Ray address"),
    ],
)
def test_bad_executor_arguments_raise(kwargs, message):
    with pytest.raises(ConfigError, match=message):
        make_executor(**kwargs)


def test_a_missing_ray_names_the_extra(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(MissingExtraError, match=r"^executor: ray needs the 'distributed' extra: "
                                                r"pip install 'bounce-gym\[distributed\]'$"):
        make_executor("ray")


def test_an_executor_block_is_completed_with_the_defaults():
    assert executor_settings({}) == {"kind": "local", "workers": None, "address": None,
                                     "retries": 2}
    assert executor_settings({"kind": "ray", "address": "auto", "workers": 4})["workers"] == 4


@pytest.mark.parametrize(
    ("block", "names", "message"),
    [
        ([], None, "config.executor: expected a mapping"),
        ({"cores": 2}, None, r"config.executor: unknown keys \['cores'\]"),
        ({"workers": "2"}, None, "config.executor.workers: expected an integer in .*, got '2'"),
        ({"retries": None}, None, r"config.executor.retries: expected an integer in \[0, 100\]"),
        ({"workers": 0}, {"workers": "--workers"}, r"^--workers: expected an integer in \[1,"),
        ({"address": "h:1"}, {"address": "--address", "kind": "--executor"},
         r"^--address: only for the ray executor \(--executor: ray\)"),
    ],
)
def test_bad_executor_blocks_name_the_field(block, names, message):
    with pytest.raises(ConfigError, match=message):
        executor_settings(block, "config.executor", names)


@pytest.mark.parametrize(("address", "endpoint"), [
    ("auto", None), ("head:6379", ("head", 6379)),
    ("ray://10.0.0.1:10001", ("10.0.0.1", 10001)), ("[::1]:6379", ("::1", 6379)),
    ("node-1.example.org:1", ("node-1.example.org", 1)), ("h:65535", ("h", 65535)),
])
def test_ray_addresses(address, endpoint):
    assert ray_endpoint("--address", address) == endpoint


@pytest.mark.parametrize("address", [
    "256.1.1.1:1", "ray://256.1.1.1:1", "1.2.3:6379", "h:0", "h:65536", "h:-1", "h:６３７９",
    "h",
    ":6379", "-h:1", "h_1:1", "[::g]:1", "::1:6379", "local", "ray://", "http://h:1", "h:1/x",
    "a" * 64 + ":1", 6379, None,
])
def test_what_is_no_ray_address(address):
    with pytest.raises(ConfigError, match=r"^--address: expected a Ray address \(auto, "
                                          r"host:port or ray://host:port"):
        ray_endpoint("--address", address)


def _server(answer: bytes | None):
    """A TCP server on a free local port that sends ``answer`` to each connection (None:
    nothing, ever); returns its port."""
    import socket
    import threading

    server = socket.create_server(("127.0.0.1", 0))
    held = []

    def serve() -> None:
        while True:
            connection, _ = server.accept()
            held.append(connection)
            if answer is not None:
                connection.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    return server.getsockname()[1]


@pytest.mark.timeout(30)  # a hang guard only
def test_only_an_answering_ray_cluster_passes_the_check(monkeypatch, tmp_path):
    import bounce_gym_experiments.executors

    monkeypatch.setattr(bounce_gym_experiments.executors, "CONNECT_TIMEOUT", 0.5)
    settings = bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])  # an HTTP/2 server's first frame
    check_ray_cluster("--address", f"127.0.0.1:{_server(settings)}")
    port = _server(b"HTTP/1.1 400 Bad Request\r\n\r\n")
    with pytest.raises(ConfigError, match=rf"^--address: '127.0.0.1:{port}' is not a Ray "
                                          "cluster: it does not answer as Ray's gRPC servers do$"):
        check_ray_cluster("--address", f"127.0.0.1:{port}")
    port = _server(None)
    with pytest.raises(ConfigError, match=rf"^--address: no Ray cluster answers at "
                                          rf"'ray://127.0.0.1:{port}' within 0.5 s$"):
        check_ray_cluster("--address", f"ray://127.0.0.1:{port}")
    monkeypatch.setenv("RAY_ADDRESS", "auto")  # as good as unset
    monkeypatch.setenv("RAY_TMPDIR", str(tmp_path))
    with pytest.raises(ConfigError, match=rf"^x: auto: no running Ray cluster found \(RAY_ADDRESS "
                                          rf"names none and {tmp_path}/ray/ray_current_cluster "
                                          r"does not exist\)"):
        check_ray_cluster("x", "auto")
    (tmp_path / "ray").mkdir()
    (tmp_path / "ray" / "ray_current_cluster").write_text(f"127.0.0.1:{_server(settings)}\n")
    check_ray_cluster("x", "auto")
    monkeypatch.setenv("RAY_ADDRESS", "256.0.0.1:1")
    with pytest.raises(ConfigError, match=r"^x \(auto, from RAY_ADDRESS\): expected a Ray addr"):
        check_ray_cluster("x", "auto")


@pytest.mark.timeout(60)  # a hang guard only: ray.init used to retry for minutes
def test_ray_is_not_asked_to_connect_where_no_cluster_answers(monkeypatch):
    ray = pytest.importorskip("ray")
    calls = []
    monkeypatch.setattr(ray, "init", lambda *args, **kwargs: calls.append(kwargs))
    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    port = _server(b"SSH-2.0-OpenSSH\r\n")
    with pytest.raises(ConfigError, match=f"^executor.address: '127.0.0.1:{port}' is not a Ray"):
        init_ray("executor.address", f"127.0.0.1:{port}", None)
    assert calls == []

    def refuse(**kwargs):
        raise ConnectionError("Could not find any running Ray instance.\nPlease ...")

    monkeypatch.setattr(ray, "init", refuse)
    with pytest.raises(ConfigError, match=r"^executor.address: cannot start or reach a local Ray "
                                          r"instance: Could not find any running Ray instance.$"):
        init_ray("executor.address", None, 2)
