"""Involute helical geometry against hand-computed and published values."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gearjax import InvoluteGearPair


def inv(a):
    return math.tan(a) - a


def inv_inverse(v):
    lo, hi = 0.0, 1.5
    for _ in range(200):  # bisection: independent of the library's Newton
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if inv(mid) < v else (lo, mid)
    return 0.5 * (lo + hi)


def test_seed_001_pair_matches_design_numbers(seed_pair):
    # DESIGN.md: alpha_t 22.310 deg, r_b 75.617 / 185.131 mm, p_bt 16.383 mm,
    # eps_alpha 1.452, eps_beta 1.235, standard centre distance 281.85 mm.
    p = seed_pair
    assert math.degrees(float(p.transverse_pressure_angle)) == pytest.approx(22.310, abs=5e-4)
    np.testing.assert_allclose(p.base_radius, [75.617, 185.131], atol=5e-4)
    assert float(p.transverse_base_pitch) == pytest.approx(16.383, abs=5e-4)
    assert float(p.transverse_contact_ratio) == pytest.approx(1.452, abs=5e-4)
    assert float(p.overlap_ratio) == pytest.approx(1.235, abs=5e-4)
    assert float(p.center_distance) == pytest.approx(281.85, abs=5e-3)


def test_seed_001_pair_matches_hand_calculation(seed_pair):
    mn, an, b, z1, z2 = 5.0, math.radians(20), math.radians(27.5), 29, 71
    at = math.atan(math.tan(an) / math.cos(b))
    mt = mn / math.cos(b)
    r1, r2 = z1 * mt / 2, z2 * mt / 2
    rb1, rb2 = r1 * math.cos(at), r2 * math.cos(at)
    ra1, ra2 = r1 + mn, r2 + mn
    a = (r1 + r2)
    pbt = math.pi * mt * math.cos(at)
    eps_a = (math.sqrt(ra1**2 - rb1**2) + math.sqrt(ra2**2 - rb2**2) - a * math.sin(at)) / pbt
    beta_b = math.atan(math.tan(b) * math.cos(at))
    p = seed_pair
    np.testing.assert_allclose(p.base_radius, [rb1, rb2], rtol=1e-13)
    np.testing.assert_allclose(p.tip_radius, [ra1, ra2], rtol=1e-13)
    assert float(p.center_distance) == pytest.approx(a, rel=1e-13)
    assert float(p.transverse_contact_ratio) == pytest.approx(eps_a, rel=1e-12)
    assert float(p.base_helix_angle) == pytest.approx(beta_b, rel=1e-13)
    assert float(p.normal_base_pitch) == pytest.approx(math.pi * mn * math.cos(an), rel=1e-13)
    assert float(p.axial_pitch) == pytest.approx(math.pi * mn / math.sin(b), rel=1e-13)
    # start of active profile: where the gear's tip circle meets the line of action
    s_start = a * math.sin(at) - math.sqrt(ra2**2 - rb2**2)
    assert float(p.start_of_active_profile[0]) == pytest.approx(s_start, rel=1e-12)


def test_profile_shifted_pair_iso_tr_6336_30_example_1():
    # ISO/TR 6336-30 example 1: z 17/103, m_n 8, beta 15.8 deg, a_w = 500 mm given,
    # x2 = 0, x1 follows (printed 0.14522); tip diameters 159.66 / 872.35 mm (printed).
    mn, an, b, z1, z2 = 8.0, math.radians(20), math.radians(15.8), 17, 103
    at = math.atan(math.tan(an) / math.cos(b))
    a0 = mn * (z1 + z2) / (2 * math.cos(b))
    awt = math.acos(a0 * math.cos(at) / 500.0)
    x1 = (inv(awt) - inv(at)) * (z1 + z2) / (2 * math.tan(an))
    assert x1 == pytest.approx(0.14522, abs=5e-6)
    p = InvoluteGearPair((17, 103), 8.0, 20.0, 15.8, 100.0, profile_shift=(x1, 0.0), center_distance=500.0,
                         dedendum_coefficient=1.4, root_radius_coefficient=0.39)
    assert float(p.center_distance) == pytest.approx(500.0, abs=1e-9)
    assert float(p.working_pressure_angle) == pytest.approx(awt, abs=1e-12)
    np.testing.assert_allclose(2 * np.asarray(p.tip_radius), [159.66, 872.35], atol=0.006)
    # hand contact ratio from the pair's own tip radii
    rb = np.asarray(p.base_radius)
    ra = np.asarray(p.tip_radius)
    pbt = math.pi * mn / math.cos(b) * math.cos(at)
    eps_a = (math.sqrt(ra[0] ** 2 - rb[0] ** 2) + math.sqrt(ra[1] ** 2 - rb[1] ** 2) - 500 * math.sin(awt)) / pbt
    assert float(p.transverse_contact_ratio) == pytest.approx(eps_a, rel=1e-12)
    # with the TR's printed (rounded) tip diameters the TR's eps_alpha is 1.549090
    eps_tr = (math.sqrt(79.83**2 - rb[0] ** 2) + math.sqrt(436.175**2 - rb[1] ** 2) - 500 * math.sin(awt)) / pbt
    assert eps_tr == pytest.approx(1.549090, abs=2e-6)


def test_spur_profile_shift_changes_centre_distance_as_by_hand():
    z1, z2, m, x1, x2 = 20, 40, 4.0, 0.3, -0.1
    a_t = math.radians(20.0)
    awt = inv_inverse(inv(a_t) + 2 * (x1 + x2) * math.tan(a_t) / (z1 + z2))
    a = m * (z1 + z2) / 2 * math.cos(a_t) / math.cos(awt)
    p = InvoluteGearPair((z1, z2), m, 20.0, 0.0, 30.0, profile_shift=(x1, x2))
    assert float(p.working_pressure_angle) == pytest.approx(awt, abs=1e-12)
    assert float(p.center_distance) == pytest.approx(a, rel=1e-12)
    # transverse tip thickness by hand
    ra = z1 * m / 2 + m * (1 + x1)
    rb = z1 * m / 2 * math.cos(a_t)
    alpha_a = math.acos(rb / ra)
    s_a = 2 * ra * (math.pi / (2 * z1) + 2 * x1 * math.tan(a_t) / z1 + inv(a_t) - inv(alpha_a))
    assert float(p.tip_thickness[0]) == pytest.approx(s_a, rel=1e-12)


def test_flank_surface_is_the_involute_helicoid(seed_pair):
    p = seed_pair
    rb1 = float(p.base_radius[0])
    beta_b = float(p.base_helix_angle)
    for s, z in [(20.0, 0.0), (30.0, -15.0), (40.0, 18.0)]:
        x = np.asarray(p.flank_point(0, s, z, 0.0))
        # every point of an involute of r_b at roll length s lies at radius sqrt(r_b^2 + s^2)
        assert math.hypot(x[0], x[1]) == pytest.approx(math.hypot(rb1, s), rel=1e-13)
        assert x[2] == pytest.approx(z)
    # a transverse section at z is the z = 0 section turned by z tan(beta_b) / r_b
    x0 = np.asarray(p.flank_point(0, 25.0, 0.0, 0.0))[:2]
    xz = np.asarray(p.flank_point(0, 25.0, 10.0, 0.0))[:2]
    turn = math.atan2(xz[1], xz[0]) - math.atan2(x0[1], x0[0])
    assert turn == pytest.approx(10.0 * math.tan(beta_b) / rb1, rel=1e-12)
    # the normal of the helicoid makes the angle beta_b with the transverse plane
    frac = float(p.transverse_normal_fraction(0, 25.0, 10.0))
    assert frac == pytest.approx(math.cos(beta_b), rel=1e-14)


def test_closed_form_normals_match_autodiff(seed_pair):
    from gearjax.geometry._base import generic_profile_normal, generic_profile_tangent, generic_transverse_normal_fraction

    for gear in (0, 1):
        for s in (20.0, 35.0):
            closed = np.asarray(seed_pair.profile_normal(gear, s))
            generic = np.asarray(generic_profile_normal(seed_pair, gear, s))
            np.testing.assert_allclose(closed, generic, atol=1e-14)
            for c, g in zip(seed_pair.profile_tangent(gear, s), generic_profile_tangent(seed_pair, gear, s)):
                np.testing.assert_allclose(np.asarray(c), np.asarray(g), rtol=1e-13, atol=1e-12)
            frac = generic_transverse_normal_fraction(seed_pair, gear, s, 7.0)
            assert float(frac) == pytest.approx(float(seed_pair.transverse_normal_fraction(gear, s, 7.0)), rel=1e-13)


@pytest.mark.parametrize("family", ["helical", "curvilinear"])
def test_closed_form_slice_point_and_tangent_match_autodiff(seed_pair, family):
    # The TCA's residual uses AbstractInvolutePair's closed forms; the generic
    # point (profile, normal and normal fraction composed) and its jvp are the reference.
    from gearjax import CurvilinearGearPair, FlankModification
    from gearjax.geometry._base import generic_slice_point

    pair = seed_pair if family == "helical" else CurvilinearGearPair((20, 30), 2.0, 20.0, 20.0, 60.0)
    mod = FlankModification(tip_relief=0.02, root_relief=0.015, tip_relief_length=1.2 * float(pair.normal_module),
                            root_relief_length=2.0, crowning=0.01, unmodified_length=0.5 * float(pair.face_width))
    z = 0.3 * float(pair.face_width)
    for gear in (0, 1):
        start, tip = pair.relief_coordinates(gear)
        depth = lambda t: mod.depth(t, z, start, tip, pair.face_width)  # noqa: E731
        lo, hi = (float(v) for v in pair.profile_limits(gear))
        for s in np.linspace(lo - 1.0, hi + 0.5, 7):  # the reliefs' parabolas and beyond the tip
            generic = lambda t: generic_slice_point(pair, gear, t, z, 0.3, depth(t))  # noqa: E731
            point, tangent = jax.jvp(generic, (jnp.asarray(s),), (jnp.asarray(1.0),))
            closed_point, closed_tangent = pair.slice_point_tangent(gear, s, z, 0.3, depth)
            np.testing.assert_allclose(closed_point, point, rtol=0, atol=1e-12)
            np.testing.assert_allclose(pair.slice_point(gear, s, z, 0.3, depth(s)), point, rtol=0, atol=1e-12)
            np.testing.assert_allclose(closed_tangent, tangent, rtol=0, atol=1e-14)


def test_derived_quantities_are_differentiable(seed_pair):
    def eps(x1):
        p = InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0, profile_shift=jnp.stack([x1, 0.0]))
        return p.transverse_contact_ratio + p.center_distance

    g = jax.grad(eps)(0.2)
    h = 1e-6
    fd = (eps(0.2 + h) - eps(0.2 - h)) / (2 * h)
    assert float(g) == pytest.approx(float(fd), rel=1e-6)


def test_a_flank_without_depth_gives_the_same_point_and_tangent():
    """`generic_slice_point` with a depth of Python 0 traces the profile point alone; it
    equals the full computation with a zero array as the depth bit for bit (the normal
    offset is 0 × a finite normal), and so does `generic_slice_point_tangent` without a
    depth function against one returning zeros."""
    from gearjax.geometry._base import generic_slice_point, generic_slice_point_tangent

    from gearjax import DoubleArcGearPair

    pair = DoubleArcGearPair((24, 24), 4.0, 15.0, 55.0, 0.0).resolve()
    for zone in pair.contact_zones():
        for gear in (0, 1):
            lo, hi = (float(v) for v in zone.profile_limits(gear))
            for u in (lo, 0.5 * (lo + hi), hi):
                np.testing.assert_array_equal(generic_slice_point(zone, gear, u, 7.0, 0.3, 0.0),
                                              generic_slice_point(zone, gear, u, 7.0, 0.3, jnp.zeros(())))
                bare = generic_slice_point_tangent(zone, gear, u, 7.0, 0.3, None)
                zeros = generic_slice_point_tangent(zone, gear, u, 7.0, 0.3, lambda t: jnp.zeros_like(t))
                for a, b in zip(bare, zeros):
                    np.testing.assert_array_equal(a, b)


def test_a_flank_with_nothing_applied_has_a_python_zero_depth():
    """`FlankDepth` gives a Python 0.0 (nothing traced) for a flank with no modification and
    no error, in the normal and in the transverse section; where a relief is applied the
    transverse depth is the normal depth over $|n_t|$ and positive in the relief."""
    from gearjax import FlankModification, MeshErrors
    from gearjax.geometry.depth import FlankDepth

    pair = InvoluteGearPair((23, 37), 4.0, 20.0, 15.0, 40.0).resolve()
    tip = float(pair.profile_limits(0)[1])
    relief = FlankDepth(pinion=FlankModification(tip_relief=0.008, tip_relief_length=3.0))
    assert relief(pair, 1, 0, tip, 5.0) == 0.0 and type(relief(pair, 1, 0, tip, 5.0)) is float
    assert type(relief.transverse(pair, 1, 0, tip, 5.0)) is float
    assert not relief.is_zero and FlankDepth().is_zero and not FlankDepth(errors=MeshErrors()).is_zero
    normal = relief(pair, 0, 0, tip, 5.0)
    assert float(normal) > 0.0
    np.testing.assert_allclose(relief.transverse(pair, 0, 0, tip, 5.0),
                               normal / pair.transverse_normal_fraction(0, tip, 5.0), rtol=1e-15)
    errors = FlankDepth(errors=MeshErrors())
    assert errors.applies_to(0) and not errors.applies_to(1) and type(errors(pair, 1, 0, tip, 5.0)) is float
