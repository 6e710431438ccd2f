"""The optimal mixture of bounce policies as a policy."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from baselines.coverage.mixture import coverage_mixture
from baselines.policy import Policy
from bounce_gym.errors import ConfigError

#: Switching schedules of `MixturePolicy`.
SCHEDULES = ("time", "bumps", "random")
#: Default epoch of `MixturePolicy`, in bumps.
DEFAULT_EPOCH = 50


# -- running the mixture ------------------------------------------------------------------------
class MixturePolicy(Policy):
    """Time-based switching among the bounce policies with proportions α (Eq. 4).

    Time is cut into **epochs of ``epoch`` bumps** (bounce step mode: one `act` call per bump; tick
    mode: counted from ``info["bumps"]``). At the start of every epoch the policy picks the angle
    for the whole epoch; `act` returns its discrete action index (alpha is ordered like the env's
    Φ). Schedules:

    * ``"time"`` (default): the policy whose share of the elapsed ticks lags its α_i the most,
      ``argmax_i α_i T − T_i`` (T_i ticks spent under φ_i, from ``info["ticks"]``; ties to the
      larger α_i, then the smaller index). The realised time fractions track α (the paper's
      "proportion of time") to within about one epoch's ticks over T; policies with α_i = 0 are
      never used. Without ``info["ticks"]`` every bump counts as one tick.
    * ``"bumps"``: the same rule on epoch counts (fractions of epochs, not of time).
    * ``"random"``: i.i.d. draws from α per epoch with the policy's own generator.

    Deterministic given ``seed``: the generator is created once, so successive episodes of the
    ``"random"`` schedule differ but repeat from run to run; the other schedules use no randomness.
    Long epochs bring the simulated coverage closer to the model's ``A α`` (docs/choices/navigation_coverage.md, "The
    mixture's coverage is the model A α") but make the proportions coarser over a short budget; the
    default (50 bumps, a few hundred ticks) is a compromise for budgets of thousands of bumps.
    """

    def __init__(self, alpha: Sequence[float], epoch: int = DEFAULT_EPOCH,
                 schedule: str = "time", seed: int | None = None,
                 angles: Sequence[float] | None = None) -> None:
        a = np.asarray(alpha, dtype=np.float64).reshape(-1)
        if len(a) == 0 or not np.all(np.isfinite(a)) or np.any(a < 0) or not a.sum() > 0:
            raise ConfigError(f"alpha: expected non-negative weights with a positive sum, "
                              f"got {alpha!r}")
        if abs(a.sum() - 1.0) > 1e-6:
            raise ConfigError(f"alpha: the proportions must sum to 1, got {a.sum()!r}")
        if isinstance(epoch, bool) or not isinstance(epoch, int | np.integer) or epoch < 1:
            raise ConfigError(f"epoch: expected a whole number of bumps >= 1, got {epoch!r}")
        if schedule not in SCHEDULES:
            raise ConfigError(f"schedule: expected one of {SCHEDULES}, got {schedule!r}")
        self.alpha = a / a.sum()
        self.epoch = int(epoch)
        self.schedule = schedule
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        label = ", ".join(f"{x:.2f}" for x in self.alpha)
        if angles is not None:
            label = ", ".join(f"{math.degrees(p):g}°:{x:.2f}"
                              for p, x in zip(angles, self.alpha, strict=True))
        self.name = f"mixture ({label})"
        self._order = np.lexsort((np.arange(len(a)), -self.alpha))  # larger α first, then index
        self._start()

    @classmethod
    def for_env(cls, env, space: str = "positions", target: object = None,
                mode: str | np.ndarray = "all", **kwargs) -> MixturePolicy:
        """The optimal mixture for a `BounceEnv` (Φ, noise, world and discretisation from its
        options). ``target``: None takes the env's coverage target when it is on the model's grid
        (else uniform); otherwise as in `target_vector`. α is exact for the ``cell`` backend
        (its ``cell_bins``) and an approximation on the continuous ones (the env's
        ``cell_model`` with 1° bins). ``kwargs`` go to the constructor. The result of Eq. 5 is
        kept in ``policy.mixture``."""
        from bounce_gym.dynamics.noise import Exact, Reliable

        base = env.unwrapped
        options = base.options
        model = base.cell_model(n_bins=360)  # the cell backend brings its own bins
        noise = options.noise
        if isinstance(noise, Reliable):
            r, eps = noise.r, noise.eps
        elif isinstance(noise, Exact):
            r, eps = 1.0, 0.0
        else:
            raise ConfigError(f"MixturePolicy.for_env: the GCM needs 'reliable' or no noise, "
                              f"got {noise!r}")
        if target is None:
            grid = getattr(getattr(base, "task", None), "target", None)
            if isinstance(grid, np.ndarray) and grid.shape == model.free.shape:
                target = grid
        angles = options.angles[0]
        result = coverage_mixture(model, angles, eps, r, target=target, space=space, mode=mode)
        policy = cls(result.alpha, angles=angles, **kwargs)
        policy.mixture = result
        return policy

    def _start(self) -> None:
        m = len(self.alpha)
        self.current: int | None = None
        self.epoch_index = -1
        self.ticks = np.zeros(m)  # ticks spent under each policy this episode
        self.epochs = np.zeros(m, dtype=np.int64)  # epochs given to each policy this episode
        self._last_ticks: float | None = None
        self._calls = 0

    @property
    def time_fractions(self) -> np.ndarray:
        """(m,) the fraction of this episode's ticks (since the first `act`) under each policy."""
        total = self.ticks.sum()
        return self.ticks / total if total > 0 else np.zeros_like(self.ticks)

    def reset(self, env) -> None:
        n = getattr(getattr(env, "action_space", None), "n", None)
        if n is not None and int(n) != len(self.alpha):
            raise ConfigError(f"MixturePolicy: {len(self.alpha)} proportions for an env with "
                              f"{int(n)} actions")
        self._start()

    def act(self, observation, info: dict) -> int:
        bumps = int(info["bumps"]) if "bumps" in info else self._calls
        ticks = float(info["ticks"]) if "ticks" in info else float(self._calls)
        if self.current is not None and self._last_ticks is not None:
            self.ticks[self.current] += max(ticks - self._last_ticks, 0.0)
        self._last_ticks = ticks
        self._calls += 1
        epoch = bumps // self.epoch
        if epoch != self.epoch_index or self.current is None:
            self.epoch_index = epoch
            self.current = self._choose()
            self.epochs[self.current] += 1
        return int(self.current)

    def _choose(self) -> int:
        if self.schedule == "random":
            return int(self.rng.choice(len(self.alpha), p=self.alpha))
        spent = self.ticks if self.schedule == "time" else self.epochs.astype(np.float64)
        lag = np.where(self.alpha > 0, self.alpha * spent.sum() - spent, -np.inf)
        order = self._order  # ties: larger α, then smaller index
        return int(order[np.argmax(lag[order])])
