"""``physics="dynamic"`` on the nasty worlds: rigid-body robots with motors never leave the free
space — scales 1e-4 … 1e5 (the world scaled so that each robot is a Create 2), shifted a million
units out, thin walls, needles, combs, 2,000-gons — with actuation noise, alone and four
colliding, while clocks, ticks and contacts stay consistent (`bounce_adversarial.checked_loop`).

The quick form runs a few dozen bounces per world; the slow form (``-m slow``) more than 10⁵
bounces in all, every rule and noisy model, and colliding robots with a narrow, frictionless
bumper that mostly stall rather than bump (`NARROW`).
"""

import itertools

import pytest
from bounce_adversarial import (
    KINDS,
    NOISES,
    RULE_NAMES,
    TRANSFORMS,
    InvariantError,
    make_world,
    run_checked,
    scale_label,
)

WORLDS = [(kind, scale, shift) for kind in KINDS for scale, shift in TRANSFORMS]
COMBOS = list(itertools.product(RULE_NAMES, [n for n in NOISES if n != "exact"]))
#: a bumper that misses most contacts, and no friction to yaw robots onto it: robots slide,
#: wedge, push each other and stall
NARROW = {"bumper_arc": 20.0, "friction": 0.0}
#: how far (in radii) robots of such a crowd may overlap a wall or each other: driving robots
#: press each other into walls until they stall, and the solver has no position correction
#: (`bounce_gym.dynamics.backends.dynamic_engine`); the deepest measured over the 63 worlds is
#: 2.7e-3 radii (a 2,000-gon)
NARROW_DEPTH = 1e-2


def _id(world) -> str:
    kind, scale, shift = world
    return f"{kind}-{scale_label(scale)}" + ("-shifted" if shift else "")


def _run(tally, world_key, rule, noise, radius_fraction, n, seed, **kwargs) -> None:
    world = make_world(world_key[0], 0, *world_key[1:])
    try:
        result = run_checked(world_key[0], world, "dynamic", rule, noise,
                             radius_fraction * world.diameter, n, seed, **kwargs)
    except InvariantError as exc:
        tally["escapes"] += "escape" in str(exc)
        tally["nonfinite"] += "non-finite" in str(exc)
        raise
    tally["bounces:pymunk-dynamic"] += result["bounces"]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("world", WORLDS, ids=_id)
def test_quick(tally, world):
    """One robot (40 bounces) and four colliding robots (15 bounce steps), one rule and noisy
    model per world, cycling."""
    index = WORLDS.index(world)
    rule, noise = COMBOS[index % len(COMBOS)]
    _run(tally, world, rule, noise, 0.002, 40, index)
    _run(tally, world, rule, noise, 0.01, 15, index, n_robots=4, robot_collisions="bounce")


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.parametrize("world", WORLDS, ids=_id)
def test_slow(tally, world):
    """Every rule x noisy model: one robot (130 bounces each) and four colliding robots (30
    bounce steps each) — over 10⁵ bounces over the 63 worlds (106,000 when written); then
    four colliding robots with the `NARROW` bumper (60 bounce steps)."""
    index = WORLDS.index(world)
    for k, (rule, noise) in enumerate(COMBOS):
        _run(tally, world, rule, noise, 0.002, 130, 1000 * index + k)
        _run(tally, world, rule, noise, 0.01, 30, 1000 * index + k, n_robots=4,
             robot_collisions="bounce")
    rule, noise = COMBOS[index % len(COMBOS)]
    _run(tally, world, rule, noise, 0.01, 60, index, n_robots=4, robot_collisions="bounce",
         physics=NARROW, depth=NARROW_DEPTH)
