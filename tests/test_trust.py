"""The user-level key and trusted digests (`bounce_gym.trust`)."""

import os
import stat
import threading

import pytest

from bounce_gym import trust
from bounce_gym.errors import ConfigError


@pytest.fixture
def home(tmp_path, monkeypatch):
    monkeypatch.setenv(trust.HOME_VARIABLE, str(tmp_path / "home"))
    return tmp_path / "home"


def test_the_key_is_made_once_private_and_reused(home):
    key = trust.secret_key()
    assert len(key) == 32
    assert trust.secret_key() == key
    mode = stat.S_IMODE(os.stat(home / trust.KEY_FILE).st_mode)
    assert mode == 0o600


def test_a_signature_checks_its_data_and_purpose(home):
    signature = trust.sign(b"abc", "unit")
    assert trust.verify(b"abc", signature, "unit")
    assert not trust.verify(b"abd", signature, "unit")
    assert not trust.verify(b"abc", signature, "resume")
    assert not trust.verify(b"abc", None, "unit")
    assert not trust.verify(b"abc", "0" * 64, "unit")


def test_another_key_does_not_verify(home, tmp_path, monkeypatch):
    signature = trust.sign(b"abc", "unit")
    monkeypatch.setenv(trust.HOME_VARIABLE, str(tmp_path / "other"))
    assert not trust.verify(b"abc", signature, "unit")


def test_a_damaged_key_is_one_line(home):
    home.mkdir(parents=True, mode=0o700)
    (home / trust.KEY_FILE).write_bytes(b"short")
    (home / trust.KEY_FILE).chmod(0o600)
    with pytest.raises(ConfigError, match="is not 32 bytes"):
        trust.secret_key()


def test_a_symlinked_key_is_refused(home, tmp_path):
    home.mkdir(parents=True)
    (tmp_path / "elsewhere").write_bytes(b"x" * 32)
    (home / trust.KEY_FILE).symlink_to(tmp_path / "elsewhere")
    with pytest.raises(ConfigError, match="cannot read or create the key"):
        trust.secret_key()


def test_trusted_digests_accumulate(home):
    assert trust.trusted_digests() == frozenset()
    a, b = trust.digest(b"a"), trust.digest(b"b")
    trust.add_trusted(a)
    trust.add_trusted(b)
    trust.add_trusted(a)
    assert trust.trusted_digests() == {a, b}


@pytest.mark.parametrize("bad", ["", "xyz", "A" * 64, "0" * 63])
def test_only_digests_are_trusted(home, bad):
    with pytest.raises(ConfigError, match="sha256 digest"):
        trust.add_trusted(bad)


def test_a_damaged_trust_list_is_one_line(home):
    home.mkdir(parents=True, mode=0o700)
    (home / trust.TRUSTED_FILE).write_text("{not json")
    with pytest.raises(ConfigError, match="trusted.json: .*delete it"):
        trust.trusted_digests()
    (home / trust.TRUSTED_FILE).write_text('{"a": 1}')
    with pytest.raises(ConfigError, match="not a list"):
        trust.trusted_digests()


# -- the folder and the key are checked as ssh checks its keys (issue 36, item 3) -------------
def _another_user(path, monkeypatch) -> None:
    """Make ``path`` another user's: given away when this process may (root), else this
    process pretends to be someone else."""
    if os.geteuid() == 0:
        os.chown(path, 65534, 65534, follow_symlinks=False)
    else:
        monkeypatch.setattr(os, "geteuid", lambda: os.getuid() + 1)


def _one_line(call, match: str) -> str:
    with pytest.raises(ConfigError, match=match) as caught:
        call()
    assert "\n" not in str(caught.value)
    return str(caught.value)


def test_a_key_others_can_read_is_refused_with_the_fix(home):
    trust.secret_key()
    key = home / trust.KEY_FILE
    for mode in (0o644, 0o640, 0o604, 0o660):
        key.chmod(mode)
        message = _one_line(trust.secret_key, f"chmod 600 {key}$")
        assert f"mode {mode:04o}" in message
    key.chmod(0o400)  # stricter is fine
    assert len(trust.secret_key()) == 32


def test_a_key_of_another_user_is_refused(home, monkeypatch):
    trust.secret_key()
    _another_user(home / trust.KEY_FILE, monkeypatch)
    if os.geteuid() != 0:  # the folder too is then not "ours"
        _one_line(trust.secret_key, "belongs to another user")
        return
    _one_line(trust.secret_key, r"the key .* belongs to another user \(uid 65534\)")


def test_a_folder_others_can_write_is_refused_with_the_fix(home):
    trust.secret_key()
    for mode in (0o777, 0o775, 0o757, 0o1777):
        home.chmod(mode)
        _one_line(trust.secret_key, f"can be written by others .*chmod go-w {home}$")
        _one_line(trust.trusted_digests, "chmod go-w")
        _one_line(lambda: trust.add_trusted("0" * 64), "chmod go-w")
    home.chmod(0o755)  # others may read and enter it; the key itself is private
    assert len(trust.secret_key()) == 32


def test_a_folder_of_another_user_is_refused(home, monkeypatch):
    home.mkdir(mode=0o700)
    _another_user(home, monkeypatch)
    _one_line(trust.secret_key, f"the folder {home} belongs to another user")
    _one_line(trust.trusted_digests, "belongs to another user")


@pytest.mark.timeout(20)  # the old code waited for ever for a writer to the pipe
def test_a_pipe_at_the_key_is_refused_without_waiting(home):
    home.mkdir(mode=0o700)
    os.mkfifo(home / trust.KEY_FILE, 0o600)
    done = []
    worker = threading.Thread(target=lambda: done.append(
        _one_line(trust.secret_key, "is not a regular file; remove it")), daemon=True)
    worker.start()
    worker.join(10)
    assert done, "secret_key() blocked on a pipe at the key's name"


def test_a_pipe_or_link_at_the_trust_list_is_refused(home, tmp_path):
    home.mkdir(mode=0o700)
    os.mkfifo(home / trust.TRUSTED_FILE, 0o600)
    _one_line(trust.trusted_digests, "is not a regular file")
    (home / trust.TRUSTED_FILE).unlink()
    (tmp_path / "planted.json").write_text(f'["{"0" * 64}"]')
    (home / trust.TRUSTED_FILE).symlink_to(tmp_path / "planted.json")
    _one_line(trust.trusted_digests, "symbolic link")


def test_a_trust_list_others_can_write_is_refused(home):
    trust.add_trusted("a" * 64)
    listed = home / trust.TRUSTED_FILE
    assert stat.S_IMODE(listed.stat().st_mode) == 0o600
    listed.chmod(0o666)
    _one_line(trust.trusted_digests, f"can be written by others .*chmod go-w {listed}$")
    listed.chmod(0o644)  # readable by others is fine: it holds no secret
    assert trust.trusted_digests() == {"a" * 64}


def test_a_relative_xdg_config_home_is_ignored(tmp_path, monkeypatch):
    monkeypatch.delenv(trust.HOME_VARIABLE)
    monkeypatch.setenv("HOME", str(tmp_path / "me"))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CONFIG_HOME", "relative/config")
    assert trust.home() == tmp_path / "me" / ".config" / "bounce_gym"
    trust.secret_key()
    assert not (tmp_path / "relative").exists()  # nothing beside the working folder
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "xdg"))
    assert trust.home() == tmp_path / "xdg" / "bounce_gym"


@pytest.mark.parametrize("given", ["~nosuchuser-bounce-gym/x", "~nosuchuser-bounce-gym"])
def test_an_unknown_users_home_is_one_line(monkeypatch, given):
    monkeypatch.setenv(trust.HOME_VARIABLE, given)
    _one_line(trust.home, f"BOUNCE_GYM_HOME: cannot expand '{given}': no such user")
    _one_line(trust.secret_key, "no such user")


def test_the_test_sessions_home_passes_the_checks():
    """The suite's own folder (tests/conftest.py) is private, so the checks let it through."""
    assert stat.S_IMODE(os.stat(trust.home()).st_mode) & 0o022 == 0
