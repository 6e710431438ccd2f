"""Actuation noise: the error added to the heading a bounce rule commands.

Each model draws an angle offset per bump; the executed heading is the rule's heading plus the
offset. For Alam's relative rule that is "rotate φ ± error"; for Nilles' boundary rules it is an
error on the outgoing action u — the quantity both papers put the noise on.

* `Exact` — no error (the papers' noise-free simple cell mapping).
* `Reliable(r, eps)` — no error with probability r, otherwise U(−ε, ε): the generalized cell
  mapping model of Alam et al. (Alam, Bobadilla & Shell 2017, Sec. III-B; thesis §3.3.3).
* `Interval(lo, hi)` — U(lo, hi): Nilles' nondeterministic rule, where any action in an interval
  may be executed (IJRR 2021, Defs. 2–3); ``Interval(-eps, eps)`` is "u ± ε".

An offset can turn the robot back into the wall; it then simply bumps again on the next tick.
Noise models are small immutable objects drawing only from the generator they are given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bounce_gym.errors import ConfigError
from bounce_gym.validate import number


@dataclass(frozen=True)
class Exact:
    """No noise."""

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        del rng
        return np.zeros(n)

    def sample_bins(self, n: int, rng: np.random.Generator, bin_width: float) -> np.ndarray:
        """Offsets in whole orientation bins (the cell model); see `Reliable.sample_bins`."""
        del rng, bin_width
        return np.zeros(n, dtype=np.int64)


@dataclass(frozen=True)
class Reliable:
    """No error with probability ``r``, else an error U(−eps, eps) (radians)."""

    r: float
    eps: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "r", number("noise.r", self.r))
        object.__setattr__(self, "eps", number("noise.eps", self.eps))
        if not 0.0 <= self.r <= 1.0:
            raise ConfigError(f"noise: reliability r must be in [0, 1], got {self.r!r}")
        if not 0.0 <= self.eps < np.pi:
            raise ConfigError(f"noise: eps must be in [0, π) radians, got {self.eps!r}")

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        slip = rng.random(n) >= self.r
        return np.where(slip, rng.uniform(-self.eps, self.eps, n), 0.0)

    def sample_bins(self, n: int, rng: np.random.Generator, bin_width: float) -> np.ndarray:
        """Offsets in whole bins, as in the GCM: 0 with probability r, otherwise uniform over
        the 2·n_ε non-zero offsets within ±ε (n_ε = ε / bin width, which must be whole)."""
        n_eps = _whole_bins(self.eps, bin_width, "eps")
        slip = rng.random(n) >= self.r
        if n_eps == 0:
            return np.zeros(n, dtype=np.int64)
        j = rng.integers(1, n_eps + 1, n) * rng.choice([-1, 1], n)
        return np.where(slip, j, 0)


@dataclass(frozen=True)
class Interval:
    """An error U(lo, hi) (radians): any action in the interval may happen."""

    lo: float
    hi: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "lo", number("noise.lo", self.lo))
        object.__setattr__(self, "hi", number("noise.hi", self.hi))
        if not self.lo <= self.hi:
            raise ConfigError(
                f"noise: interval needs finite lo <= hi, got lo={self.lo!r}, hi={self.hi!r}"
            )

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return rng.uniform(self.lo, self.hi, n)

    def sample_bins(self, n: int, rng: np.random.Generator, bin_width: float) -> np.ndarray:
        """Offsets in whole bins, uniform over the bins in [lo, hi] (both whole multiples)."""
        lo = _whole_bins(self.lo, bin_width, "interval lo")
        hi = _whole_bins(self.hi, bin_width, "interval hi")
        return rng.integers(lo, hi + 1, n)


def _whole_bins(angle: float, bin_width: float, field: str) -> int:
    bins = angle / bin_width
    if abs(bins - round(bins)) > 1e-6:
        raise ConfigError(f"noise: {field} = {np.degrees(angle):g}° is not a whole number of "
                          f"{np.degrees(bin_width):g}° orientation bins (cell model)")
    return int(round(bins))


NoiseModel = Exact | Reliable | Interval


def make_noise(spec: object) -> NoiseModel:
    """Build a noise model from an instance, ``None``/``"exact"``, or a config dict.

    Dicts: ``{"type": "reliable", "r": 0.8, "eps_deg": 5}`` (or ``"eps"`` in radians),
    ``{"type": "interval", "lo_deg": -5, "hi_deg": 5}`` (or ``"lo"``/``"hi"`` in radians).
    """
    if isinstance(spec, Exact | Reliable | Interval):
        return spec
    if spec is None or spec == "exact":
        return Exact()
    if isinstance(spec, dict):
        spec = dict(spec)
        kind = spec.pop("type", None)
        fields = {"reliable": ("r", "eps"), "interval": ("lo", "hi")}
        if kind == "exact" and not spec:
            return Exact()
        if kind not in fields:
            raise ConfigError(
                f"noise.type: unknown noise model {kind!r}; allowed are exact, reliable, interval"
            )
        values = {}
        for key in fields[kind]:
            if key == "r":  # a probability: no degrees form
                if "r" in spec:
                    values["r"] = number("noise.r", spec.pop("r"))
                continue
            if key in spec and f"{key}_deg" in spec:
                raise ConfigError(f"noise: give {key!r} or {key + '_deg'!r}, not both")
            if f"{key}_deg" in spec:
                values[key] = float(np.radians(number(f"noise.{key}_deg",
                                                      spec.pop(f"{key}_deg"))))
            elif key in spec:
                values[key] = number(f"noise.{key}", spec.pop(key))
            else:
                raise ConfigError(f"noise: {kind} needs {key!r} (radians) or {key + '_deg'!r}")
        if kind == "reliable" and "r" not in values:
            raise ConfigError("noise: reliable needs 'r' (probability of the nominal angle)")
        if spec:
            raise ConfigError(f"noise: unknown keys {sorted(spec)} for type {kind!r}")
        return Reliable(**values) if kind == "reliable" else Interval(**values)
    raise ConfigError(
        f"noise: expected None, 'exact', a dict with 'type', or a noise model, got {spec!r}"
    )
