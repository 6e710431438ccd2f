"""`bounce_gym.files`: names that become path components, never writing through a link planted
at a name the package writes, and folders that appear whole."""

import errno
import os
import stat

import pytest

from bounce_gym import files
from bounce_gym.errors import BounceGymError, ConfigError, OutputError
from bounce_gym.files import (
    MAX_NAME_BYTES,
    NewFolder,
    atomic_path,
    atomic_write,
    check_path_component,
    check_writable,
    locked,
    open_no_follow,
    refuse_links,
)


@pytest.mark.parametrize(("name", "why"), [
    ("../../ESCAPED", "it contains '/'"),
    ("a/b", "it contains '/'"),
    ("a\\b", "it contains '\\\\'"),
    ("..", "it starts with '.'"),
    (".", "it starts with '.'"),
    (".hidden", "it starts with '.'"),
    ("-rf", "it starts with '-'"),
    ("a\0b", "it contains the control character U+0000"),
    ("two\nlines", "it contains the control character U+000A"),
    ("tab\there", "it contains the control character U+0009"),
    ("evil\u202egnp", "it contains the control character U+202E"),
    ("", "it is empty"),
    (" padded", "it starts or ends with a space"),
    ("x" * (MAX_NAME_BYTES + 1), f"it is 101 bytes long, at most {MAX_NAME_BYTES}"),
    ("é" * 51, "it is 102 bytes long"),
    (7, "it is not a string"),
])
def test_a_name_that_is_not_one_plain_path_component_is_one_line_error(name, why):
    with pytest.raises(ConfigError) as error:
        check_path_component("config.name", name, "a name for the run folder")
    message = str(error.value)
    assert message.startswith("config.name: expected a name for the run folder (one path "
                              "component), got ")
    assert why in message
    assert "\n" not in message and len(message) < 200


@pytest.mark.parametrize("name", ["run", "navigation-lab", "coverage-10x10-m3", "tiny_lab",
                                  "a b", "x" * MAX_NAME_BYTES, "é" * 50, "v1.2"])
def test_plain_names_pass(name):
    check_path_component("config.name", name)


def test_check_writable_reports_a_nul_in_a_folder_in_one_line(tmp_path):
    with pytest.raises(ConfigError, match="config.output: .* contains a NUL character"):
        check_writable("config.output", tmp_path / "a\0b")


def test_a_whole_file_write_replaces_a_planted_link_and_leaves_its_target(tmp_path):
    target = tmp_path / "precious.txt"
    target.write_text("keep me")
    os.symlink(target, tmp_path / "out.csv")
    atomic_write(tmp_path / "out.csv", b"new")
    assert target.read_text() == "keep me"
    assert not (tmp_path / "out.csv").is_symlink() and (tmp_path / "out.csv").read_bytes() == b"new"


@pytest.mark.parametrize("exists", [True, False], ids=["to a file", "dangling"])
def test_a_lock_file_planted_as_a_link_is_refused(tmp_path, exists):
    target = tmp_path / "elsewhere" / "victim"
    target.parent.mkdir()
    if exists:
        target.write_text("keep me")
    os.symlink(target, tmp_path / ".manifest.json.lock")
    with pytest.raises(ConfigError, match=r"\.manifest\.json\.lock: is a symbolic link"), \
            locked(tmp_path / "manifest.json"):
        pass
    assert (target.read_text() == "keep me") if exists else not target.exists()


def test_open_no_follow_refuses_links_and_pipes_without_blocking(tmp_path):
    (tmp_path / "file").write_text("x")
    os.symlink(tmp_path / "file", tmp_path / "link")
    os.mkfifo(tmp_path / "pipe")
    with pytest.raises(ConfigError, match="link: is a symbolic link"):
        open_no_follow(tmp_path / "link", os.O_WRONLY | os.O_APPEND)
    for flags in (os.O_RDONLY, os.O_WRONLY | os.O_APPEND):  # no reader: would block for ever
        with pytest.raises(ConfigError, match="pipe: is not a regular file"):
            open_no_follow(tmp_path / "pipe", flags)
    os.close(open_no_follow(tmp_path / "file", os.O_RDONLY))


def test_refuse_links_checks_below_the_users_folder_only(tmp_path):
    (tmp_path / "real").mkdir()
    os.symlink(tmp_path / "real", tmp_path / "chosen")  # the user's own folder may be a link
    refuse_links("config.output", tmp_path / "chosen", tmp_path / "chosen/a/b")
    os.symlink(tmp_path / "real", tmp_path / "real/a")
    with pytest.raises(ConfigError, match=r"config.output: .*chosen/a is a symbolic link"):
        refuse_links("config.output", tmp_path / "chosen", tmp_path / "chosen/a/b")


def test_a_new_folder_appears_whole_with_the_usual_permissions(tmp_path):
    made = NewFolder(tmp_path / "run-1")
    with made as folder:
        assert folder.parent == tmp_path and folder.name.startswith(".run-1.tmp-")
        assert stat.S_IMODE(folder.stat().st_mode) == 0o700  # nothing planted meanwhile
        (folder / "episodes.csv").write_text("rows")
        assert not (tmp_path / "run-1").exists()
    assert made.path == tmp_path / "run-1"
    assert (made.path / "episodes.csv").read_text() == "rows"
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(made.path.stat().st_mode) == 0o777 & ~umask
    assert os.listdir(tmp_path) == ["run-1"]


def test_a_new_folder_never_replaces_what_has_its_name(tmp_path):
    (tmp_path / "run-1").mkdir()
    (tmp_path / "run-1/episodes.csv").write_text("older")
    os.symlink(tmp_path / "elsewhere", tmp_path / "run-1-2")
    (tmp_path / "run-1-3").write_text("a file")
    made = NewFolder(tmp_path / "run-1")
    with made as folder:
        (folder / "episodes.csv").write_text("newer")
    assert made.path == tmp_path / "run-1-4"
    assert (tmp_path / "run-1/episodes.csv").read_text() == "older"
    assert not (tmp_path / "elsewhere").exists()


def test_a_new_folder_whose_block_fails_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), NewFolder(tmp_path / "run-1") as folder:
        (folder / "episodes.csv").write_text("half")
        raise RuntimeError("disk full")
    assert os.listdir(tmp_path) == []


# -- faults: every OSError of a write is one line naming the path (issue 36, item 4) ----------
def fill_the_disk(monkeypatch) -> None:
    """Every temporary file the writers open is /dev/full from now on: its writes fail with
    ENOSPC when they reach the disk, as on a full one."""
    real = files._no_follow

    def opener(path: str, flags: int) -> int:
        if os.path.basename(path).startswith(".") and path.endswith(".tmp") \
                and flags & (os.O_WRONLY | os.O_RDWR):
            return os.open("/dev/full", os.O_RDWR)
        return real(path, flags)
    monkeypatch.setattr(files, "_no_follow", opener)


def _leftovers(folder) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if ".tmp" in p.name)


def test_a_full_disk_is_one_line_naming_the_file_and_keeps_the_old_one(tmp_path, monkeypatch):
    target = tmp_path / "out" / "summary.csv"
    atomic_write(target, b"old")
    fill_the_disk(monkeypatch)
    with pytest.raises(OutputError) as caught:
        atomic_write(target, b"new" * 100_000)
    assert str(caught.value) == f"{target}: cannot write it: No space left on device"
    assert caught.value.errno == errno.ENOSPC
    assert isinstance(caught.value, BounceGymError) and isinstance(caught.value, OSError)
    assert target.read_bytes() == b"old"
    assert _leftovers(tmp_path) == []


@pytest.mark.parametrize("call", ["replace", "chmod", "fsync", "mkstemp"])
def test_every_step_of_an_atomic_write_fails_in_one_line(tmp_path, monkeypatch, call):
    target = tmp_path / "results.json"

    def fail(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    module = files.tempfile if call == "mkstemp" else files.os
    with monkeypatch.context() as patched:
        patched.setattr(module, call, fail)
        with pytest.raises(OutputError, match=f"^{target}: cannot write it: No space left"):
            atomic_write(target, b"data")
    assert not target.exists()
    assert _leftovers(tmp_path) == []


def test_a_link_swapped_in_while_writing_is_one_line_and_not_followed(tmp_path):
    target, elsewhere = tmp_path / "plot.png", tmp_path / "elsewhere"
    elsewhere.write_bytes(b"untouched")
    with pytest.raises(OutputError, match=f"^{target}: cannot write it: a symbolic link is in "
                                          "the way"), atomic_path(target) as tmp:
        tmp.unlink()
        tmp.symlink_to(elsewhere)  # the race: a link where the writer's file was
    assert elsewhere.read_bytes() == b"untouched"
    assert not target.exists()
    assert not any(p.is_symlink() for p in tmp_path.iterdir())


def test_a_full_disk_in_a_new_folder_names_the_folder_it_was_to_become(tmp_path, monkeypatch):
    fill_the_disk(monkeypatch)
    with pytest.raises(OutputError) as caught, NewFolder(tmp_path / "run-1") as folder:
        atomic_write(folder / "episodes.csv", b"x" * 10_000)
    assert str(caught.value) == (f"{tmp_path / 'run-1' / 'episodes.csv'}: cannot write it: No "
                                 "space left on device")
    assert list(tmp_path.iterdir()) == []


def test_a_lock_that_cannot_be_created_is_one_line(tmp_path, monkeypatch):
    def refused(path: str, flags: int) -> int:
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), path)
    monkeypatch.setattr(files, "_no_follow", refused)
    lock = tmp_path / ".manifest.json.lock"
    with pytest.raises(OutputError, match=f"^{lock}: cannot create it: Permission denied$"), \
            locked(tmp_path / "manifest.json"):
        pass
