"""Exceptions raised by bounce_gym for bad user input.

Every error names the offending field and what is allowed, so a malformed map, config or action
fails loudly at the point it enters the package instead of producing a silently wrong simulation.
"""

from __future__ import annotations


class BounceGymError(ValueError):
    """Base class of every input error raised by bounce_gym."""


class InvalidWorldError(BounceGymError):
    """A polygon, hole, grid or map file does not describe a valid world."""


class MapFormatError(InvalidWorldError):
    """A map file or map dictionary does not follow the documented schema."""


class ConfigError(BounceGymError):
    """A constructor argument, rule, noise model or backend option is not allowed."""


class ActionError(BounceGymError):
    """An action passed to ``step`` has the wrong type, shape or value."""
