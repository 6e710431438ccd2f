"""Perimeter patrol after Agmon, Kraus and Kaminka (ICRA 2008): the baselines that Alam (2018,
thesis ch. 4, Fig. 4.4 and Table 4.1) runs on the cycle C_n as "BMP", "DCP" and "DNCP".

The thesis never defines those three; the patrols here are **approximations** of that family,
not reconstructions of them. m robots stand equally spaced, d = n/m vertices apart, on the
cycle C_n and move synchronously: at every decision all of them continue one vertex in their
common direction with probability p, or all turn around with probability 1 - p, which costs
``turn_cost`` steps in place (τ = 1 by default). Because they move together the spacing stays d,
and a vertex is seen when some robot stands on it. Presets: ``deterministic`` (p = 1, a sweep
that never turns) and ``random_walk`` (p = 1/2).

The adversary's target is a uniformly random vertex and the team starts at a uniformly random
offset in a uniformly random direction; T = 0 when a robot starts on the target (the protocol
of the thesis' Table 4.1 for its own strategies).
"""

from __future__ import annotations

import numpy as np

from bounce_gym import validate
from bounce_gym.errors import ConfigError

__all__ = ["PRESETS", "perimeter_detection_times"]

#: The named continue probabilities p.
PRESETS = {"deterministic": 1.0, "random_walk": 0.5}


def perimeter_detection_times(n: int, m: int, p: float | str, *, turn_cost: int = 1,
                              n_runs: int = 10_000, seed: int = 0,
                              max_steps: int = 100_000) -> np.ndarray:
    """Simulate the first time a synchronised perimeter patrol sees a random target.

    Args:
        n: the number of vertices of the cycle.
        m: the number of robots; it must divide ``n`` (equal spacing d = n/m).
        p: the probability of continuing at each decision, or a name in `PRESETS`.
        turn_cost: the steps a turn takes, in place (τ).
        n_runs: the number of simulations.
        seed: the seed of the random stream; the same seed gives the same times.
        max_steps: runs not detected after this many steps get T = inf.

    Returns:
        (n_runs,) float64 first detection times (whole steps, or inf).

    Raises:
        ConfigError: ``m`` does not divide ``n``, ``p`` outside [0, 1] or an unknown preset,
            or bad counts.
    """
    n = validate.integer("n", n, 2)
    m = validate.integer("m", m, 1, n)
    if n % m:
        raise ConfigError(f"m: expected a divisor of n = {n} (equal spacing), got {m}")
    if isinstance(p, str):
        if p not in PRESETS:
            raise ConfigError(f"p: expected a number in [0, 1] or one of {sorted(PRESETS)}, "
                              f"got {p!r}")
        p = PRESETS[p]
    p = validate.number("p", p, minimum=0.0)
    if p > 1:
        raise ConfigError(f"p: expected a number in [0, 1], got {p!r}")
    turn_cost = validate.integer("turn_cost", turn_cost, 1)
    n_runs = validate.integer("n_runs", n_runs, 1)
    seed = validate.integer("seed", seed, 0)
    max_steps = validate.integer("max_steps", max_steps, 0)
    d = n // m
    rng = np.random.default_rng(seed)
    # the robots occupy one residue class mod d, so the target is seen when the team's offset
    # from it, mod d, is 0
    offset = rng.integers(n, size=n_runs) % d
    direction = rng.choice(np.array([-1, 1]), size=n_runs)
    busy = np.zeros(n_runs, dtype=np.int64)  # steps of a turn still to spend in place
    times = np.full(n_runs, np.inf)
    active = np.arange(n_runs)
    for t in range(max_steps + 1):
        hit = offset == 0
        times[active[hit]] = t
        keep = ~hit
        active, offset, direction, busy = active[keep], offset[keep], direction[keep], busy[keep]
        if len(active) == 0 or t == max_steps:
            break
        deciding = busy == 0
        turn = deciding & (rng.random(len(active)) >= p)
        move = deciding & ~turn
        offset = np.where(move, (offset + direction) % d, offset)
        direction = np.where(turn, -direction, direction)
        busy = np.where(turn, turn_cost - 1, np.maximum(busy - 1, 0))
    return times
