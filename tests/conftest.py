"""Every test run keeps its user-level bounce_gym folder (the signing key and the trusted
digests, `bounce_gym.trust`) in a temporary folder of its own, never the user's: tests, and the
processes they start, which inherit the variable."""

import os
import shutil
import tempfile

from bounce_gym.trust import HOME_VARIABLE

_HOME = tempfile.mkdtemp(prefix="bounce-gym-home-")
os.environ[HOME_VARIABLE] = _HOME


def pytest_unconfigure(config):
    shutil.rmtree(_HOME, ignore_errors=True)
