"""Bounce rules: pure functions from the contact to the new heading.

Two families:

* **Heading-relative** (Alam, Bobadilla & Shell; thesis Eq. 2.4): ``relative`` rotates the robot
  counter-clockwise by the bounce angle φ from its *current* heading, whatever the wall. If the new
  heading still points into the boundary the next tick is another bump (the dynamics detects it),
  so a corner produces several bumps in a row, as in the papers' observation strings.
* **Boundary-relative** (Nilles, Ren, Becerra & LaValle, IJRR 2021, Def. 1): the outgoing heading
  ``u`` is measured counter-clockwise from the boundary tangent at the contact, ``u ∈ (0, π)``, as
  a function ``u = b(α, θ)`` of the incoming angle ``α`` (the reversed velocity in the same frame)
  and a control parameter ``θ``: ``fixed`` (u = θ), ``specular`` (u = π − α), ``monotonic``
  (θ or π − θ, keeping the direction of travel along the wall), and ``nilles_relative``
  (u = α − kθ, the smallest k ≥ 1 that points into free space).

Frame: with inward unit normal n at the contact, the tangent is t = (n_y, −n_x) so that n is t
rotated by +90°, exactly the paper's frame (free space on the left of each directed edge).
All angles are radians; functions are vectorised over robots.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bounce_gym.errors import ConfigError

TWO_PI = 2.0 * np.pi


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles reduced to [0, 2π)."""
    out = np.mod(angle, TWO_PI)
    return np.where(out >= TWO_PI, 0.0, out)


def tangent_angle(normal: np.ndarray) -> np.ndarray:
    """Direction angle of the boundary tangent t = (n_y, −n_x) for inward normals (m, 2)."""
    normal = np.asarray(normal, dtype=np.float64).reshape(-1, 2)
    return np.arctan2(-normal[:, 0], normal[:, 1])


def incoming_alpha(heading: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Nilles' α: angle of the reversed velocity, measured CCW from the tangent, in [0, 2π)."""
    return wrap(np.asarray(heading) + np.pi - tangent_angle(normal))


def heading_from_u(u: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """World heading of the action u (measured CCW from the tangent)."""
    return wrap(tangent_angle(normal) + np.asarray(u))


# -- b(α, θ) of Nilles et al., Def. 1 ---------------------------------------------------------

def fixed_u(alpha: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Fixed rule: u = θ, a constant angle to the boundary."""
    return np.broadcast_to(np.asarray(theta, dtype=np.float64), np.shape(alpha)).copy()


def specular_u(alpha: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Specular (billiard) rule: u = π − α. θ is ignored."""
    del theta
    return np.pi - np.asarray(alpha, dtype=np.float64)


def monotonic_u(alpha: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Monotonic fixed rule: θ or π − θ, whichever keeps the sign of travel along the tangent.

    u = θ if sign(cos θ) = −sign(cos α), else π − θ. At α = π/2 (head-on) the paper leaves the
    choice open; we use θ (docs/choices/visibility.md, "Relative rule: keep rotating until free").
    """
    alpha = np.asarray(alpha, dtype=np.float64)
    theta = np.broadcast_to(np.asarray(theta, dtype=np.float64), alpha.shape)
    cos_a = np.cos(alpha)
    head_on = np.abs(cos_a) < 1e-12
    keep = np.sign(np.cos(theta)) == -np.sign(cos_a)
    return np.where(head_on | keep, theta, np.pi - theta)


def nilles_relative_u(alpha: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Nilles' relative rule: u = (α − kθ) mod 2π for the smallest k ≥ 1 with u ∈ (0, π).

    A result exactly on 0 or π (grazing the wall) keeps rotating (a choice where Nilles et al. 2021,
    §3 is open: docs/choices/visibility.md, "Relative rule: keep rotating until free").
    """
    alpha = np.asarray(alpha, dtype=np.float64)
    theta = np.broadcast_to(np.asarray(theta, dtype=np.float64), alpha.shape)
    out = np.full(alpha.shape, np.nan)
    k_max = int(np.ceil(TWO_PI / np.min(theta))) + 2 if theta.size else 0
    for k in range(1, k_max + 1):
        u = wrap(alpha - k * theta)
        ok = np.isnan(out) & (u > 1e-12) & (u < np.pi - 1e-12)
        out[ok] = u[ok]
        if not np.isnan(out).any():
            break
    return out


# -- rules as heading maps --------------------------------------------------------------------

def relative(heading: np.ndarray, normal: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Alam's rule: rotate counter-clockwise by φ from the current heading (normal unused)."""
    del normal
    return wrap(np.asarray(heading, dtype=np.float64) + phi)


class BoundaryRule:
    """Heading map of a boundary-relative rule ``b(α, θ)``: measure α, apply b, turn u back into
    a world heading.

    A small class rather than a closure so that rules, and the dynamics and envs holding them,
    can be pickled (process pools, Gymnasium's ``AsyncVectorEnv``, SB3's ``SubprocVecEnv``);
    the instances below pickle by reference to their module-level names.
    """

    def __init__(self, b: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> None:
        self.b = b
        self.__name__ = b.__name__.removesuffix("_u")
        self.__doc__ = f"Heading map of the boundary-relative rule: {b.__doc__.splitlines()[0]}"

    def __call__(self, heading: np.ndarray, normal: np.ndarray, theta: np.ndarray) -> np.ndarray:
        return heading_from_u(self.b(incoming_alpha(heading, normal), theta), normal)

    def __reduce__(self) -> str:
        return self.__name__  # pickled by reference to the module-level rule of that name

    def __repr__(self) -> str:
        return f"BoundaryRule({self.b.__name__})"


fixed = BoundaryRule(fixed_u)
specular = BoundaryRule(specular_u)
monotonic = BoundaryRule(monotonic_u)
nilles_relative = BoundaryRule(nilles_relative_u)

#: Rule name -> heading map ``(heading, normal, parameter) -> new heading``.
RULES: dict[str, Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]] = {
    "relative": relative,
    "fixed": fixed,
    "specular": specular,
    "monotonic": monotonic,
    "nilles_relative": nilles_relative,
}


def get_rule(name: str) -> Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
    """Look up a rule by name, raising `ConfigError` with the allowed names."""
    try:
        return RULES[name]
    except (KeyError, TypeError):
        raise ConfigError(
            f"bounce_rule: unknown rule {name!r}; allowed are {sorted(RULES)}"
        ) from None


def check_parameters(rule: str, params: np.ndarray, field: str = "angles") -> None:
    """Validate bounce parameters (radians) for a rule; raise `ConfigError` naming ``field``.

    ``relative`` needs φ ≢ 0 (mod 2π) (a zero turn never leaves the wall); the boundary rules
    need θ ∈ (0, π) (specular ignores θ but it must still be finite).
    """
    get_rule(rule)
    params = np.asarray(params, dtype=np.float64)
    if params.size == 0:
        raise ConfigError(f"{field}: the set of bounce angles is empty")
    if not np.all(np.isfinite(params)):
        raise ConfigError(f"{field}: angles must be finite, got {params.tolist()}")
    if rule == "relative":
        turn = np.mod(params, TWO_PI)
        bad = (turn < 1e-9) | (turn > TWO_PI - 1e-9)
        if np.any(bad):
            raise ConfigError(
                f"{field}: a relative bounce angle must not be a multiple of 360° "
                f"(got {np.degrees(params[bad]).tolist()} degrees)"
            )
    elif rule in ("fixed", "monotonic", "nilles_relative"):
        bad = (params <= 0) | (params >= np.pi)
        if np.any(bad):
            raise ConfigError(
                f"{field}: rule {rule!r} needs angles strictly between 0° and 180° "
                f"(got {np.degrees(params[bad]).tolist()} degrees)"
            )
