"""The user-level key and trusted digests (`bounce_gym.trust`)."""

import os
import stat

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
    home.mkdir(parents=True)
    (home / trust.KEY_FILE).write_bytes(b"short")
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
    home.mkdir(parents=True)
    (home / trust.TRUSTED_FILE).write_text("{not json")
    with pytest.raises(ConfigError, match="trusted.json: .*delete it"):
        trust.trusted_digests()
    (home / trust.TRUSTED_FILE).write_text('{"a": 1}')
    with pytest.raises(ConfigError, match="not a list"):
        trust.trusted_digests()
