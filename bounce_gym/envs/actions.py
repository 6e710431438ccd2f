"""Turning env actions into bounce angles, with clear errors for anything malformed.

Nothing is clipped: an action outside its space raises `ActionError` naming the problem.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from bounce_gym.errors import ActionError

#: action types taken as an index without further checks (exact types: bool is not among them)
_INDEX_TYPES = frozenset({int, np.int64, np.int32})


def action_space(action_type: str, n_angles: int) -> spaces.Space:
    """``Discrete(|Φ|)`` or a symmetric ``Box(-1, 1, (1,), float32)``."""
    if action_type == "discrete":
        return spaces.Discrete(n_angles)
    return spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)


def to_angle(action: object, action_type: str, angles: np.ndarray,
             angle_range: tuple[float, float], who: str = "action") -> float:
    """The bounce angle (radians) an action selects.

    Discrete: an integer index into Φ (Python int, numpy integer, or a 0-d / 1-element integer
    array). Continuous: one number a ∈ [-1, 1] (shape () or (1,)), mapped linearly onto
    ``angle_range``.
    """
    if action_type == "discrete":
        if type(action) in _INDEX_TYPES and 0 <= action < len(angles):  # the common case, fast
            return float(angles[action])
        if isinstance(action, bool | np.bool_):
            raise ActionError(f"{who}: expected an integer index, got a bool")
        value = np.asarray(action)
        if value.size != 1 or value.ndim > 1 or not np.issubdtype(value.dtype, np.integer):
            raise ActionError(f"{who}: expected one integer index in [0, {len(angles)}), got "
                              f"{action!r} (dtype {value.dtype}, shape {value.shape})")
        index = int(value.reshape(()))
        if not 0 <= index < len(angles):
            raise ActionError(f"{who}: index {index} is out of range [0, {len(angles)})")
        return float(angles[index])
    raw = np.asarray(action)
    if raw.dtype.kind not in "iuf":  # not bools, strings, objects, nor complex (no part dropped)
        raise ActionError(f"{who}: expected a number in [-1, 1] (real: not a bool, string or "
                          f"complex), got {action!r} (dtype {raw.dtype})")
    value = raw.astype(np.float64)
    if value.shape not in ((), (1,)):
        raise ActionError(f"{who}: expected shape (1,), got shape {value.shape}")
    a = float(value.reshape(()))
    if not np.isfinite(a):
        raise ActionError(f"{who}: expected a finite number in [-1, 1], got {a}")
    if not -1.0 <= a <= 1.0:
        raise ActionError(f"{who}: {a} is outside [-1, 1] (actions are not clipped)")
    lo, hi = angle_range
    return lo + (a + 1.0) / 2.0 * (hi - lo)
