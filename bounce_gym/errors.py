"""Exceptions raised by bounce_gym for bad user input.

Every error names the offending field and what is allowed, so a malformed map, config or action
fails loudly at the point it enters the package instead of producing a silently wrong simulation.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from gymnasium.error import DependencyNotInstalled


class BounceGymError(ValueError):
    """Base class of every input error raised by bounce_gym."""


class InvalidWorldError(BounceGymError):
    """A polygon, hole, grid or map file does not describe a valid world."""


class MapFormatError(InvalidWorldError):
    """A map file or map dictionary does not follow the documented schema."""


class ConfigError(BounceGymError):
    """A constructor argument, rule, noise model or backend option is not allowed."""


class MissingExtraError(ConfigError, ImportError, DependencyNotInstalled):
    """A feature needs an optional dependency group (an extra) that is not installed; the
    message names the feature, the extra and the ``pip install`` command that adds it
    (`bounce_gym.extras.require`). Also an `ImportError`, and Gymnasium's
    `DependencyNotInstalled` as its envs raise for a missing render library."""


class UnknownArgumentError(ConfigError, TypeError):
    """An env or task is given a keyword argument it does not take: a `ConfigError`, and a
    `TypeError` as Python's own for an unexpected keyword argument is."""


class InvalidFlowError(BounceGymError):
    """A flow field (velocities, coordinates, land mask) is not valid."""


class FlowFileError(InvalidFlowError):
    """A flow file (NetCDF) is unreadable, or its variables, dimensions or units do not describe
    a valid flow field."""


class OutputError(BounceGymError, OSError):
    """A file or folder the package writes could not be written — the disk is full, a folder
    is not writable, a link was swapped in meanwhile: one line naming the path and the
    system's reason (``<path>: cannot write it: No space left on device``). The writers
    (`bounce_gym.files`) raise it for every `OSError` they meet and leave nothing half-written
    under the path's name. It is also an `OSError` carrying the original ``errno``, so code
    that handles a failed write as an `OSError` keeps doing so."""

    __str__ = BaseException.__str__  # the message, not OSError's "[Errno n] ..."

    def __init__(self, message: str, errno: int | None = None) -> None:
        super().__init__(message)
        if errno is not None:
            self.errno = errno

    def __reduce__(self):
        return type(self), (str(self), self.errno)


class ActionError(BounceGymError):
    """An action passed to ``step`` has the wrong type, shape or value."""


@contextlib.contextmanager
def config_errors(field: str) -> Iterator[None]:
    """Report a bad environment construction as a `ConfigError` whose message starts with
    ``field`` (where the arguments came from, e.g. ``config.env_kwargs``).

    Translated are this package's own errors (a bad map, world, option or an unknown keyword
    argument, `UnknownArgumentError`) and Python's `TypeError` of an unknown or missing keyword
    argument; any other exception is a bug and passes through unchanged.
    """
    try:
        yield
    except BounceGymError as exc:
        raise ConfigError(f"{field}: {exc}") from None
    except TypeError as exc:
        if "keyword argument" not in str(exc):
            raise
        raise ConfigError(f"{field}: {exc}") from None
