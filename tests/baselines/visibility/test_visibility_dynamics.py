"""Dynamics of bouncing paths (Nilles et al. 2021, §6 and §6.1: Defs. 8–13, Lemmas 2–3, Theorem 1,
Prop. 4, Cor. 4). Reference numbers not printed in the paper were computed independently."""

from __future__ import annotations

import math

import numpy as np
import pytest

from baselines.visibility import dynamics as vd
from bounce_gym.dynamics import BounceDynamics
from bounce_gym.worlds import World, get

HEPTAGON = [(450, 150), (650, 420), (425, 500), (200, 480), (50, 270), (170, 80), (300, 50)]


def regular(n: int, *, side: float | None = None, radius: float | None = None) -> World:
    """Regular n-gon, counter-clockwise, v_0 at angle 0 (circumradius, or side length)."""
    if radius is None:
        radius = side / (2 * math.sin(math.pi / n))
    ang = 2 * math.pi * np.arange(n) / n
    return World(np.column_stack((radius * np.cos(ang), radius * np.sin(ang))), name=f"reg{n}")


def unit_square() -> World:
    return World([(0, 0), (1, 0), (1, 1), (0, 1)], name="unit_square")


def converged_contacts(world: World, theta: float, starts, n_bounces: int, period: int):
    """The last ``period`` contacts of every simulated start (exact fixed rule, first_hit)."""
    trace = vd.simulate_fixed_rule(world, theta, starts, n_bounces)
    return trace.edges[:, -period:], trace.positions[:, -period:], trace.points[:, -period:]


# -- contraction (Def. 11, Lemma 2) ---------------------------------------------------------------

def test_square_adjacent_right_transition_is_tan_theta():
    """Def. 11 / Lemma 2: square, adjacent right transition: C = tan θ, contracting iff θ < π/4."""
    bottom, right = [(0, 0), (1, 0)], [(1, 0), (1, 1)]
    theta = np.linspace(0.05, math.pi / 2 - 0.05, 41)
    np.testing.assert_allclose(vd.contraction(bottom, right, theta), np.tan(theta), rtol=1e-12)
    np.testing.assert_array_equal(vd.is_contracting(bottom, right, theta), theta < math.pi / 4)
    assert vd.transition_side(bottom, right) == "right"
    assert vd.interior_angle(bottom, right) == pytest.approx(math.pi / 2)
    assert vd.contracting_range(bottom, right) == pytest.approx((0.0, math.pi / 4))
    # the paper's Def. 11 form agrees with the unified γ form
    np.testing.assert_allclose(vd.contraction_coefficient(theta, math.pi / 2, "right"),
                               np.tan(theta), rtol=1e-12)


def test_adjacent_left_transition_at_right_angle():
    """Def. 11 / Lemma 2: adjacent left transition with φ = π/2 contracts iff θ > 3π/4 (Lemma 2)."""
    bottom, left = [(0, 0), (1, 0)], [(0, 1), (0, 0)]
    assert vd.transition_side(bottom, left) == "left"
    phi = vd.interior_angle(bottom, left)
    assert phi == pytest.approx(math.pi / 2)
    assert vd.lemma2_threshold(phi, "left") == pytest.approx(3 * math.pi / 4)
    theta = np.linspace(math.pi / 2 + 0.05, math.pi - 0.05, 41)
    np.testing.assert_array_equal(vd.is_contracting(bottom, left, theta), theta > 3 * math.pi / 4)
    np.testing.assert_allclose(vd.contraction(bottom, left, theta),
                               vd.contraction_coefficient(theta, phi, "left"), rtol=1e-12)
    assert vd.contracting_range(bottom, left) == pytest.approx((3 * math.pi / 4, math.pi))


def test_lemma2_threshold_on_general_angles():
    """Lemma 2 with the unified γ: C crosses 1 exactly at π/2 ∓ φ/2, for any φ."""
    for phi in (0.4, 1.0, 2.0, 2.8):
        a = [(0, 0), (1, 0)]
        b_right = [(1, 0), (1 + math.cos(math.pi - phi), math.sin(math.pi - phi))]
        th = vd.lemma2_threshold(phi, "right")
        assert vd.interior_angle(a, b_right) == pytest.approx(phi)
        assert vd.contraction(a, b_right, th) == pytest.approx(1.0)
        assert vd.is_contracting(a, b_right, th - 1e-3) and not vd.is_contracting(a, b_right,
                                                                                 th + 1e-3)


def test_opposite_sides_of_rectangle_are_isometric():
    """Def. 11 / Lemma 2: opposite sides of a rectangle: C = 1 for every θ, and the map is a
    reflection."""
    bottom, top = [(0, 0), (2, 0)], [(2, 1), (0, 1)]
    theta = np.linspace(0.5, 2.6, 30)
    np.testing.assert_allclose(vd.contraction(bottom, top, theta), 1.0, rtol=1e-12)
    assert vd.transition_side(bottom, top) == "parallel"
    assert vd.contracting_range(bottom, top) is None
    np.testing.assert_allclose(vd.slope(bottom, top, theta), -1.0, rtol=1e-12)


@pytest.mark.parametrize("angle", [0.3, 0.7, 1.2])
def test_opposite_sides_stay_parallel_far_from_the_origin(angle):
    """A rotated 7 x 3 rectangle shifted by (10⁵, −7·10⁴): its opposite walls' tangents differ by
    about 2e-12 rad of rounding, which the former 1e-12 tolerance called a turn."""
    rot = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    v = [np.array([1e5, -7e4]) + rot @ np.array(p) for p in [(0, 0), (7, 0), (7, 3), (0, 3)]]
    bottom, top = np.array([v[0], v[1]]), np.array([v[2], v[3]])
    assert vd.transition_side(bottom, top) == "parallel"
    assert vd.interior_angle(bottom, top) == 0.0


def random_valid_pair(rng):
    """Two random segments and a (s, θ) whose ray really hits the second one."""
    while True:
        seg_i, seg_j = rng.uniform(-5, 5, (2, 2, 2))
        s = rng.uniform(0.1, 0.9) * np.hypot(*(seg_i[1] - seg_i[0]))
        theta = rng.uniform(0.05, math.pi - 0.05)
        if vd.hits_segment(seg_i, seg_j, s, theta):
            return seg_i, seg_j, s, theta


def test_slope_is_minus_c_by_finite_differences():
    """Def. 11 / Lemma 2: every valid transition has ∂μ/∂s = −C < 0 (finite differences on random
    pairs), is increasing in θ, and the image of a box is [μ(s_hi, θ_lo), μ(s_lo, θ_hi)]."""
    rng = np.random.default_rng(4)
    for _ in range(200):
        seg_i, seg_j, s, theta = random_valid_pair(rng)
        h = 1e-6
        fd = (vd.transition(seg_i, seg_j, s + h, theta) - vd.transition(seg_i, seg_j, s - h, theta))
        fd /= 2 * h
        c = float(vd.contraction(seg_i, seg_j, theta))
        assert fd == pytest.approx(-c, rel=1e-5, abs=1e-7)
        assert float(vd.slope(seg_i, seg_j, theta)) == pytest.approx(-c, rel=1e-12)
        dth = (vd.transition(seg_i, seg_j, s, theta + h) - vd.transition(seg_i, seg_j, s, theta - h))
        assert dth > 0
        # the hit computed by μ is where the ray meets the segment
        vi, vj = seg_i[0], seg_j[0]
        ti = (seg_i[1] - vi) / np.hypot(*(seg_i[1] - vi))
        tj = (seg_j[1] - vj) / np.hypot(*(seg_j[1] - vj))
        ni = np.array([-ti[1], ti[0]])
        q = vj + vd.transition(seg_i, seg_j, s, theta) * tj
        d = math.cos(theta) * ti + math.sin(theta) * ni
        w = q - (vi + s * ti)
        assert abs(w[0] * d[1] - w[1] * d[0]) < 1e-9
        lo, hi = vd.interval_image(seg_i, seg_j, (s - 1e-3, s + 1e-3), (theta - 1e-3, theta + 1e-3))
        assert lo == pytest.approx(float(vd.transition(seg_i, seg_j, s + 1e-3, theta - 1e-3)))
        assert hi == pytest.approx(float(vd.transition(seg_i, seg_j, s - 1e-3, theta + 1e-3)))


def test_composite_contraction_is_the_product_and_the_set_ratio():
    """Def. 12: C(F) is the product of the factors and the ratio by which a set of
    positions shrinks along the composed path (checked on random valid chains)."""
    rng = np.random.default_rng(7)
    for _ in range(50):
        seg_i, seg_j, s, t1 = random_valid_pair(rng)
        # a third segment hit from the contact on seg_j
        mu = float(vd.transition(seg_i, seg_j, s, t1))
        while True:
            seg_k = rng.uniform(-5, 5, (2, 2))
            t2 = rng.uniform(0.05, math.pi - 0.05)
            if vd.hits_segment(seg_j, seg_k, mu, t2):
                break
        expect = float(vd.contraction(seg_i, seg_j, t1) * vd.contraction(seg_j, seg_k, t2))
        cf = vd.composite_contraction([seg_i, seg_j, seg_k], [t1, t2])
        assert cf == pytest.approx(expect, rel=1e-12)
        h = 1e-5
        s2 = np.array([s - h, s + h])
        end = vd.transition(seg_j, seg_k, vd.transition(seg_i, seg_j, s2, t1), t2)
        assert abs(end[1] - end[0]) / (2 * h) == pytest.approx(cf, rel=1e-6)
        assert (end[1] - end[0]) > 0  # two reversals preserve orientation


# -- Lemma 3 (§6.1) -------------------------------------------------------------------------------

@pytest.mark.parametrize("n", [3, 4, 5, 6, 7, 10])
def test_lemma3_regular_ngon(n):
    """Lemma 3: regular n-gon: bound π/n with both terms equal."""
    b = vd.lemma3_bound(regular(n, radius=1.0))
    assert b.bound == pytest.approx(math.pi / n, abs=1e-12)
    assert b.visibility == pytest.approx(math.pi / n, abs=1e-12)
    assert b.contraction == pytest.approx(math.pi / n, abs=1e-12)


def test_lemma3_rectangle_and_heptagon():
    """Lemma 3, 2×1 rectangle and Fig. 9's 7-gon: 0.463648 = atan(1/2); the 7-gon terms 0.2090640
    and 0.1726225."""
    r = vd.lemma3_bound(World([(0, 0), (2, 0), (2, 1), (0, 1)]))
    assert r.bound == pytest.approx(0.463648, abs=1e-6)
    assert r.bound == pytest.approx(math.atan(0.5), abs=1e-12)
    h = vd.lemma3_bound(World(HEPTAGON))
    assert h.visibility == pytest.approx(0.2090640, abs=1e-7)
    assert h.contraction == pytest.approx(0.1726225, abs=1e-7)
    assert h.bound == pytest.approx(0.1726225, abs=1e-7)
    # the zoo's 10×20 rectangle: scale-free
    assert vd.lemma3_bound(get("rectangle")).bound == pytest.approx(math.atan(0.5), abs=1e-12)


def test_lemma3_rejects_nonconvex():
    with pytest.raises(ValueError, match="not convex"):
        vd.lemma3_bound(get("l_shape"))


# -- Theorem 1 (§6.1) -----------------------------------------------------------------------------

THEOREM1_TABLE = [
    # (world, θ, d_FP, ΠC or None)
    ("square", math.pi / 8, 1 - 1 / math.sqrt(2), (math.sqrt(2) - 1) ** 4),
    ("square", 0.706858, 0.460649, None),
    ("triangle", math.pi / 6, 1 / 3, 1 / 8),
    ("pentagon", math.pi / 10, 0.324920, None),
    ("hexagon", math.pi / 12, 2 - math.sqrt(3), None),
    ("rect21", math.atan(math.sqrt(5) - 2), 0.131966, None),
    ("heptagon", 0.1, 67.741096, 5.0864e-6),
    ("heptagon", 0.15, 122.687040, None),
]


def table_world(name: str) -> World:
    return {
        "square": unit_square,
        "triangle": lambda: regular(3, side=1.0),
        "pentagon": lambda: regular(5, radius=1.0),
        "hexagon": lambda: regular(6, side=1.0),
        "rect21": lambda: World([(0, 0), (2, 0), (2, 1), (0, 1)]),
        "heptagon": lambda: World(HEPTAGON),
    }[name]()


@pytest.mark.parametrize(("name", "theta", "d_fp", "prod"), THEOREM1_TABLE)
def test_theorem1_table_and_simulation(name, theta, d_fp, prod):
    """Theorem 1: d_FP (and ΠC) of the table, the composite fixed point agrees, and every random
    start of the exact simulation converges to d_FP and to every forward-projected contact to
    1e-6."""
    world = table_world(name)
    cyc = vd.fixed_rule_cycle(world, theta)
    assert cyc.valid and cyc.stable
    assert cyc.d_fp == pytest.approx(d_fp, abs=1e-6)
    if prod is not None:
        assert cyc.product == pytest.approx(prod, rel=1e-4)
    n = len(world.outer)
    comp = vd.composite_fixed_point([vd.edge_segment(world, k) for k in range(n)], theta)
    np.testing.assert_allclose(comp.positions, cyc.positions, atol=1e-9 * world.diameter)
    assert comp.coefficient == pytest.approx(cyc.product, rel=1e-12)
    # simulation: laps needed for 1e-9 relative accuracy
    laps = math.ceil(math.log(1e-10) / math.log(cyc.product)) + 2
    rng = np.random.default_rng(5)
    starts = vd.sample_boundary(world, rng, 16)
    edges, pos, pts = converged_contacts(world, theta, starts, laps * n, n)
    scale = max(1.0, world.diameter)
    for row in range(16):
        # reorder the last lap so that it starts on e_0
        k0 = int(np.flatnonzero(edges[row] == 0)[0])
        order = np.roll(np.arange(n), -k0)
        np.testing.assert_array_equal(edges[row, order], np.arange(n))
        np.testing.assert_allclose(pos[row, order], cyc.positions, atol=1e-6 * scale)
        np.testing.assert_allclose(pts[row, order], cyc.points, atol=1e-6 * scale)


def test_theorem1_special_cases():
    """Theorem 1 special cases (§6.1): the regular n-gon closed form ℓC/(1+C) and the rectangle (Hc
    − Wc²)/(1 − c²)."""
    for n, theta in [(3, math.pi / 6), (4, math.pi / 8), (5, 0.5), (6, math.pi / 12), (9, 0.2)]:
        w = regular(n, side=1.0)
        assert vd.fixed_rule_cycle(w, theta).d_fp == pytest.approx(
            vd.regular_ngon_fixed_point(n, 1.0, theta), abs=1e-12)
    for width, height, theta in [(2, 1, 0.2318238), (600, 230, 0.2), (20, 10, 0.3), (1, 3, 0.2)]:
        w = World([(0, 0), (width, 0), (width, height), (0, height)])
        assert vd.fixed_rule_cycle(w, theta).d_fp == pytest.approx(
            vd.rectangle_fixed_point(width, height, theta), rel=1e-12)
    # zoo square (10×10): d_FP scales with the side
    assert vd.fixed_rule_cycle(get("square"), math.pi / 8).d_fp == pytest.approx(
        10 * (1 - 1 / math.sqrt(2)), rel=1e-12)


def test_theorem1_agrees_with_bounce_dynamics():
    """The fixed rule of `BounceDynamics` (bounce mode, kinematic backend) reaches the Theorem 1
    contacts in the zoo's 10×10 square."""
    world = get("square")
    theta = math.pi / 8
    cyc = vd.fixed_rule_cycle(world, theta)
    dyn = BounceDynamics(world, rule="fixed", step_length=1.0)
    dyn.reset(np.random.default_rng(0), position=np.array([[3.0, 4.0]]), heading=np.array([0.3]))
    dyn.drive_to_contact()
    contacts = []
    for _ in range(60):
        dyn.bounce(np.array([theta]))
        contacts.append(dyn.state.position[0].copy())
    last = np.array(contacts[-4:])
    dist = np.min(np.linalg.norm(last[:, None] - cyc.points[None], axis=2), axis=1)
    assert np.all(dist < 1e-6)


def test_theorem1_flags_invalid_and_unstable_cycles():
    """Above Lemma 3's visibility term (atan ½ for the 2×1 rectangle) the formula's contacts leave
    their edges (invalid); at θ = 1.2 the period-4 orbit exists but C_k > 1 (unstable)."""
    rect = World([(0, 0), (2, 0), (2, 1), (0, 1)])
    assert vd.fixed_rule_cycle(rect, 0.45).stable
    assert not vd.fixed_rule_cycle(rect, 0.5).valid
    steep = vd.fixed_rule_cycle(rect, 1.2)
    assert steep.valid and not steep.stable and steep.product > 1
    # it is a genuine periodic orbit: one simulated lap from d_FP returns to it
    trace = vd.simulate_fixed_rule(rect, 1.2, (0, steep.d_fp), 4)
    np.testing.assert_allclose(trace.positions[0], [*steep.positions, steep.d_fp], atol=1e-9)


# -- Corollary 4 (§6.2) ---------------------------------------------------------------------------

def test_corollary4_square():
    """Corollary 4 (docs/choices/visibility.md, "Corollary 4 is conservative"): square θ = π/8, ℓ = 1, ε =
    1e-3: k = ⌈2.156⌉ = 3 (conservative); two laps already shrink the whole edge to a diameter of
    8.7e-4 (simulated)."""
    world = unit_square()
    cyc = vd.fixed_rule_cycle(world, math.pi / 8)
    ratio = math.log(1e-3 / 2) / math.log(cyc.product)
    assert ratio == pytest.approx(2.156, abs=1e-3)
    assert vd.iterations_to(1e-3, cyc.product, 1.0) == 3
    s0 = np.linspace(1e-6, 1 - 1e-6, 201)
    trace = vd.simulate_fixed_rule(world, math.pi / 8, (np.zeros(201, dtype=int), s0), 8)
    assert np.all(trace.edges[:, 4] == 0) and np.all(trace.edges[:, 8] == 0)
    one_lap, two_laps = np.ptp(trace.positions[:, 4]), np.ptp(trace.positions[:, 8])
    assert one_lap == pytest.approx(cyc.product * (s0[-1] - s0[0]), rel=1e-6)
    assert two_laps == pytest.approx(8.7e-4, abs=0.05e-4)
    assert two_laps < 1e-3 < one_lap
    assert two_laps <= vd.cor3_bound(cyc.product, 1.0, 2)
    # |F^k(x0) − x_FP| ≤ C^k ℓ (Cor. 3)
    for k in range(3):
        err = np.abs(trace.positions[:, 4 * k] - cyc.d_fp)
        assert np.all(err <= vd.cor3_bound(cyc.product, 1.0, k) + 1e-12)


# -- Prop. 4 (§6.1) -------------------------------------------------------------------------------

def test_prop4_l_shape_converges_to_one_four_cycle():
    """Prop. 4: L-shape, θ = 0.2: 20 random starts converge to one 4-cycle in the lower arm with
    contacts (22.9099, 0), (600, 116.9820), (577.0901, 230), (0, 113.0180) (rectangle formula)."""
    world = get("l_shape")
    expected = np.array([(22.9099, 0), (600, 116.9820), (577.0901, 230), (0, 113.0180)])
    rng = np.random.default_rng(10)
    starts = vd.sample_boundary(world, rng, 20)
    edges, _, pts = converged_contacts(world, 0.2, starts, 400, 4)
    for row in range(20):
        k0 = int(np.flatnonzero(edges[row] == 0)[0])
        order = np.roll(np.arange(4), -k0)
        np.testing.assert_array_equal(edges[row, order], [0, 1, 2, 5])
        np.testing.assert_allclose(pts[row, order], expected, atol=1e-4)
    # the same cycle analytically: composite fixed point and the 600×230 rectangle formula
    comp = vd.composite_fixed_point([vd.edge_segment(world, k) for k in (0, 1, 2, 5)], 0.2)
    assert comp.stable
    np.testing.assert_allclose(comp.points, expected, atol=1e-4)
    assert comp.positions[0] == pytest.approx(vd.rectangle_fixed_point(600, 230, 0.2), rel=1e-12)
