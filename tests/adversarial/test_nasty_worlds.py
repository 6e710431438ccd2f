"""Robots on nasty worlds, on every backend, rule and noise model: nobody escapes, nothing turns
NaN, clocks and contacts stay consistent, disks never overlap.

The worlds (`bounce_adversarial.KINDS`): the package's random star polygons, room trees and grid
maps, and hand-made ones — two rooms joined by a corridor 1e-4 of the map wide, needles and
spikes 1e-4 wide, 64 holes, a regular and a star-shaped 2,000-gon, a comb of 1e-4 slots — each at
scales 1e-4 … 1e5 and shifted by 1e6 (`bounce_adversarial.TRANSFORMS`). The quick form runs one
rule and noise model per world and backend, cycling through all of them; the slow form
(``-m slow``) runs every combination on every world.
"""

import itertools

import numpy as np
import pytest
from bounce_adversarial import (
    BACKENDS,
    KINDS,
    NOISES,
    RULE_NAMES,
    TRANSFORMS,
    InvariantError,
    angles_for,
    make_dynamics,
    make_world,
    run_checked,
    scale_label,
)

from bounce_gym.worlds import World

WORLDS = [(kind, scale, shift) for kind in KINDS for scale, shift in TRANSFORMS]
COMBOS = list(itertools.product(RULE_NAMES, NOISES))  # 15 (rule, noise) pairs
QUICK_BOUNCES = {"kinematic": 300, "pymunk": 150, "cell": 150}


def _id(world) -> str:
    kind, scale, shift = world
    return f"{kind}-{scale_label(scale)}" + ("-shifted" if shift else "")


def _run(tally, kind, scale, shift, backend, rule, noise, radius_fraction, n, seed, **kwargs):
    world = make_world(kind, 0, scale, shift)
    tally["worlds"] = max(tally["worlds"], make_world.cache_info().currsize)
    try:
        result = run_checked(kind, world, backend, rule, noise, radius_fraction * world.diameter,
                             n, seed, **kwargs)
    except InvariantError as exc:
        tally["escapes"] += "escape" in str(exc)
        tally["nonfinite"] += "non-finite" in str(exc)
        raise
    tally[f"bounces:{backend}"] += result["bounces"]
    return result


def _combos(backend: str) -> list[tuple[str, str]]:
    """The (rule, noise) pairs a backend supports: the cell backend steps Alam's rule only."""
    return [c for c in COMBOS if backend != "cell" or c[0] == "relative"]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("world", WORLDS, ids=_id)
def test_quick(tally, world, backend):
    """One rule and noise model per world and backend, cycling so that every pair is run on
    several worlds; point robots and disks of 1/500 of the map alternate."""
    index = WORLDS.index(world)
    combos = _combos(backend)
    rule, noise = combos[index % len(combos)]
    _run(tally, *world, backend, rule, noise, 0.002 * (index % 2), QUICK_BOUNCES[backend], index)


@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.parametrize("n_robots", [1, 4])
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("world", WORLDS, ids=_id)
def test_slow(tally, world, backend, n_robots):
    """Every rule x noise model the backend supports: one robot (point and disk alternating,
    250 bounces each) and four colliding disks of 1/100 of the map (150 bounces each)."""
    index = WORLDS.index(world)
    for k, (rule, noise) in enumerate(_combos(backend)):
        if n_robots == 1:
            _run(tally, *world, backend, rule, noise, 0.002 * (k % 2), 250, 1000 * index + k)
        else:
            _run(tally, *world, backend, rule, noise, 0.01, 150, 1000 * index + k,
                 n_robots=n_robots, robot_collisions="bounce")


MULTI_WORLDS = [w for w in WORLDS if w[1] in (1e-4, 1.0, 1e5)]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("world", MULTI_WORLDS, ids=_id)
def test_multi_robot_disks_never_overlap(tally, world, backend):
    """Four colliding robots (disks of 1/100 of the map; distinct cells on the grid)."""
    index = MULTI_WORLDS.index(world)
    combos = _combos(backend)
    rule, noise = combos[index % len(combos)]
    _run(tally, *world, backend, rule, noise, 0.01, 100, index, n_robots=4,
         robot_collisions="bounce")


# -- kinematic vs pymunk -------------------------------------------------------------------------
AGREE_WORLDS = [w for w in WORLDS if w[0] in ("star", "rooms", "grid", "holes")]


@pytest.mark.parametrize("radius_fraction", [0.0, 0.002])
@pytest.mark.parametrize("world", AGREE_WORLDS, ids=_id)
def test_pymunk_agrees_with_kinematic(tally, world, radius_fraction):
    """tests/dynamics/test_pymunk_backend.py's check, at every scale and shift: from the same
    start the two backends hit the same walls with the same ticks for 50 bounces, and stop at
    the same points (to 1e-7 of the map: the 1e-6 of those maps, relative)."""
    w = make_world(*(world[0], 0), *world[1:])
    radius = radius_fraction * w.diameter
    rng = np.random.default_rng(AGREE_WORLDS.index(world))
    start = w.sample_free(rng, 1, radius), rng.uniform(0, 2 * np.pi, 1)
    runs = []
    for backend in ("kinematic", "pymunk"):
        dyn = make_dynamics(w, backend, "relative", "exact", radius, w.diameter / 40)
        dyn.reset(np.random.default_rng(0), *start)
        history = [dyn.drive_to_contact()]
        for phi in angles_for("relative", backend, np.random.default_rng(1), 50):
            history.append((dyn.bounce(phi), int(dyn.state.contact_edge[0]),
                            dyn.state.position[0].copy()))
        tally[f"bounces:{backend}"] += int(dyn.state.bumps.sum())
        runs.append(history)
    kin, phys = runs
    assert kin[0] == phys[0]
    for (tk, ek, pk), (tp, ep, pp) in zip(kin[1:], phys[1:], strict=True):
        assert (tk, ek) == (tp, ep)
        np.testing.assert_allclose(pp, pk, rtol=0, atol=1e-7 * w.diameter)


# -- small worlds far from the origin -------------------------------------------------------------
@pytest.mark.parametrize(("kind", "scale"), [("star", 1e-4), ("corridor", 1e-4),
                                             ("needles", 1.0), ("holes", 1.0)])
def test_world_shifted_far_from_the_origin_keeps_its_area(kind, scale):
    near = make_world(kind, 0, scale, 0.0)
    far = World(near.outer + 1e6, [h + 1e6 for h in near.holes])
    assert far.area == pytest.approx(near.area, rel=1e-3)
