"""Tooth compliance, ISO 6336-1 method B and the face-width coupling."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gearjax import InvoluteGearPair
from gearjax.ltca import iso_mesh_stiffness
from gearjax.ltca.compliance import pasternak_compliance, symmetric_tridiagonal_inverse
from gearjax.ltca.tooth_stiffness import foundation_compliance, gauss_legendre, root_half_angle, tooth_compliance

E, NU = 206000.0, 0.3


def test_iso_tr_6336_30_example_1():
    # m_n 8, z 17/103, beta 15.8 deg, a = 500 mm, x2 = 0, basic rack h_fP = 1.4 m_n.
    # The TR evaluates q' with its printed x1 = 0.145 and eps_alpha from its printed tip
    # diameters 159.66 / 872.35 mm.
    x1 = 0.1452221
    pair = InvoluteGearPair((17, 103), 8.0, 20.0, 15.8, 100.0, profile_shift=(x1, 0.0),
                            dedendum_coefficient=1.4, root_radius_coefficient=0.39)
    rb = np.asarray(pair.base_radius)
    awt = float(pair.working_pressure_angle)
    eps = (math.sqrt(79.83**2 - rb[0] ** 2) + math.sqrt(436.175**2 - rb[1] ** 2) - 500 * math.sin(awt)) / float(pair.transverse_base_pitch)
    iso = iso_mesh_stiffness(pair, profile_shift=(0.145, 0.0), transverse_contact_ratio=eps)
    assert float(iso.single_stiffness) == pytest.approx(12.370, abs=5e-4)
    assert float(iso.mesh_stiffness) == pytest.approx(17.465, abs=5e-4)
    assert float(iso.single_stiffness_theoretical) == pytest.approx(17.85584, abs=5e-5)
    # with the exact shift the stiffness is 4.4e-5 higher
    exact = iso_mesh_stiffness(pair, transverse_contact_ratio=eps)
    assert float(exact.single_stiffness) / float(iso.single_stiffness) - 1 == pytest.approx(4.4e-5, abs=0.3e-5)


def direct_tooth_compliance(z, m, s, n=200001):
    """Bending, shear and axial compliance (mm^2/N) by direct integration along the tooth
    axis of the beam with the involute half-thickness, clamped at the root circle (with a
    straight segment of the base-circle half thickness below the base circle)."""
    a0 = math.radians(20)
    r = z * m / 2
    rb = r * math.cos(a0)
    rf = r - 1.25 * m
    a2 = math.pi / (2 * z) + math.tan(a0) - a0
    a1 = s / rb - a2
    # involute of the flank: polar angle relative to the centre line at radius R
    def half(R):
        inv = math.tan(math.acos(rb / R)) - math.acos(rb / R)
        return a2 - inv

    x_c = math.sqrt(rb**2 + s**2) * math.cos(half(math.hypot(rb, s)))
    h_c = math.sqrt(rb**2 + s**2) * math.sin(half(math.hypot(rb, s)))
    radii = np.linspace(max(rb, rf), math.hypot(rb, s), n)
    xs = np.array([R * math.cos(half(R)) for R in radii])
    hs = np.array([R * math.sin(half(R)) for R in radii])
    if rb > rf:  # straight segment of half thickness rb sin(a2) down to the root circle
        hb = rb * math.sin(a2)
        x_root = math.sqrt(rf**2 - hb**2)
        xs = np.concatenate([np.linspace(x_root, xs[0], 2001)[:-1], xs])
        hs = np.concatenate([np.full(2000, hb), hs])
    moment = (x_c - xs) * math.cos(a1) - h_c * math.sin(a1)
    inertia = 2.0 / 3.0 * hs**3
    area = 2 * hs
    g = E / (2 * (1 + NU))
    bend = np.trapezoid(moment**2 / (E * inertia), xs)
    shear = np.trapezoid(1.2 * math.cos(a1) ** 2 / (g * area), xs)
    axial = np.trapezoid(math.sin(a1) ** 2 / (E * area), xs)
    return (bend, shear, axial), (a1, a2, rb, rf)


@pytest.mark.parametrize("z, s_frac", [(17, 0.45), (17, 0.8), (43, 0.5), (80, 0.9)])
def test_potential_energy_integrals_match_direct_integration(z, s_frac):
    m = 1.0
    rb = z * m / 2 * math.cos(math.radians(20))
    ra = z * m / 2 + m
    s = s_frac * math.sqrt(ra**2 - rb**2) + (1 - s_frac) * 0.3 * math.sqrt(ra**2 - rb**2)
    direct, (a1, a2, rb, rf) = direct_tooth_compliance(z, m, s)
    ours = tooth_compliance(jnp.asarray(a1), jnp.asarray(a2), jnp.asarray(rb), jnp.asarray(rf),
                            jnp.asarray(E), jnp.asarray(NU), gauss_legendre(48))
    np.testing.assert_allclose([float(v) for v in ours], direct, rtol=2e-5)


def test_fillet_foundation_matches_an_independent_implementation():
    # 17-tooth standard spur pinion, m = 1, load at the pitch point, h_f = r_f / r_hub = 1.4:
    # the research implementation (scipy, recorded with the LTCA issue) gives 16.046e-6.
    z, m = 17, 1.0
    a0 = math.radians(20)
    r = z * m / 2
    rb, rf = r * math.cos(a0), r - 1.25 * m
    a2 = math.pi / (2 * z) + math.tan(a0) - a0
    a1 = math.tan(a0) - a2
    theta = root_half_angle(z, m, r, a0, 1.25 * m, 0.38 * m)
    assert float(theta) == pytest.approx(0.1772, abs=5e-5)
    cf = foundation_compliance(jnp.asarray(a1), rb, rf, rf / 1.4, theta, E)
    assert float(cf) * 1e6 == pytest.approx(16.046, abs=2e-3)


def test_pasternak_coupling_decays_geometrically_and_softens_the_ends():
    n, dz, lam = 61, 0.5, 2.0
    c = jnp.full(n, 1e-5)
    compliance = np.asarray(pasternak_compliance(c, dz, lam))
    k = 1e5
    a = k * dz / (k * lam**2 / dz)
    ratio = 1 + a / 2 - math.sqrt(a + a * a / 4)
    mid = n // 2
    col = compliance[:, mid]
    # the infinite strip's ratio; the free ends 30 slices away reflect ~ ratio**60 = 3e-7
    assert col[mid + 1] / col[mid] == pytest.approx(ratio, rel=2e-6)
    assert col[mid + 5] / col[mid] == pytest.approx(ratio**5, rel=1e-5)
    assert ratio == pytest.approx(math.exp(-dz / lam), rel=2e-3)  # the continuum decay
    # a uniform deflection does not stretch the shear layer: uniform load -> uniform w = c/dz
    w = compliance @ np.ones(n)
    np.testing.assert_allclose(w, 1e-5 / dz, rtol=1e-10)
    # an end slice is softer than a central one: with x_j = x_0 r^|j| the interior balance
    # gives 1/G_mid = s + 2 k_c (1 - r), the free end 1/G_end = s + k_c (1 - r), s/k_c = a;
    # the ratio -> 2 for strong coupling
    end_ratio = (a + 2 * (1 - ratio)) / (a + (1 - ratio))
    measured = compliance[0, 0] / compliance[mid, mid]
    assert measured == pytest.approx(end_ratio, rel=1e-6)
    assert 1.7 < measured < 2.0
    # no coupling: diagonal
    np.testing.assert_allclose(np.asarray(pasternak_compliance(c, dz, 0.0)), np.eye(n) * 1e-5 / dz, rtol=1e-12)


def _spring_chain(rng, n, coupling):
    """A random diagonally dominant tridiagonal matrix with off-diagonal entries <= 0."""
    springs = rng.uniform(0.5, 2.0, n)
    off = -coupling * rng.uniform(0.5, 2.0, n - 1)
    diag = springs + np.r_[0.0, -off] + np.r_[-off, 0.0]
    return diag, off


@pytest.mark.parametrize("n", [2, 3, 41, 161])
@pytest.mark.parametrize("coupling", [0.0, 1.0, 400.0])
def test_tridiagonal_inverse_equals_a_dense_inverse(n, coupling):
    rng = np.random.default_rng(n)
    diag, off = _spring_chain(rng, n, coupling)
    matrix = np.diag(diag) + np.diag(off, 1) + np.diag(off, -1)
    expected = np.linalg.inv(matrix)
    got = np.asarray(symmetric_tridiagonal_inverse(jnp.asarray(diag), jnp.asarray(off)))
    # the dense inverse's own error grows with the condition number (up to ~1e5 here)
    scale = np.abs(expected).max() * np.linalg.cond(matrix)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-14 * scale)
    np.testing.assert_array_equal(got, got.T)
    if coupling == 0.0:
        np.testing.assert_array_equal(got, np.diag(1.0 / diag))  # exact zeros off the diagonal
    # float32: finite at every size (no minors that overflow), a few eps of the condition number
    got32 = np.asarray(symmetric_tridiagonal_inverse(jnp.asarray(diag, jnp.float32), jnp.asarray(off, jnp.float32)))
    np.testing.assert_allclose(got32, expected, rtol=0, atol=1e-6 * scale)


def test_tridiagonal_inverse_gradient_equals_the_linear_solves():
    rng = np.random.default_rng(7)
    diag, off = _spring_chain(rng, 17, 3.0)
    weights = jnp.asarray(rng.normal(size=(17, 17)))

    def closed_form(d, o):
        return jnp.sum(weights * symmetric_tridiagonal_inverse(d, o))

    def solved(d, o):
        pad = jnp.zeros(1, d.dtype)
        inverse = jax.lax.linalg.tridiagonal_solve(jnp.concatenate([pad, o]), d, jnp.concatenate([o, pad]), jnp.eye(17, dtype=d.dtype))
        return jnp.sum(weights * inverse)

    args = (jnp.asarray(diag), jnp.asarray(off))
    for got, expected in zip(jax.grad(closed_form, (0, 1))(*args), jax.grad(solved, (0, 1))(*args)):
        np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-13)
