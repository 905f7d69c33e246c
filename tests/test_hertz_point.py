"""Hertz point contact (`gearjax.ltca.hertz_point`) against closed forms: a sphere on a
plane, crossed cylinders of equal radius (the same circle) and of unequal radii (an ellipse,
checked against an independent solution of Johnson's equations by quadrature and
bisection), with the relative curvatures taken from the parametric surfaces themselves."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gearjax.ltca.hertz_point import (
    effective_modulus,
    elliptic_integrals,
    ellipse_ratio,
    hertz_point_contact,
    relative_curvatures,
)

E_STAR = float(effective_modulus(206000.0, 0.3))
LOAD = 1500.0  # N


def _sphere(radius):
    """A sphere of `radius` on top of the origin as a graph, z = sqrt(R² − x² − y²) − R (its top at 0)."""
    return lambda x, y: jnp.array([x, y, jnp.sqrt(radius**2 - x**2 - y**2) - radius])


def _plane(x, y):
    return jnp.array([x, y, 0.0 * x])


def _cylinder_along_x(radius):
    """Body 1: a cylinder whose top line is the x axis."""
    return lambda s, x: jnp.array([x, radius * jnp.sin(s), radius * jnp.cos(s) - radius])


def _cylinder_along_y(radius):
    """Body 2: a cylinder above the origin whose lowest line is the y axis."""
    return lambda s, y: jnp.array([radius * jnp.sin(s), y, radius - radius * jnp.cos(s)])


def _johnson(load, a_curv, b_curv, modulus):
    """Johnson (1985) §4.2 solved independently: K and E by 20 000-point midpoint
    quadrature, the eccentricity by bisection on B/A, then a, b, p0 and the approach."""
    theta = (np.arange(20000) + 0.5) * (np.pi / 2) / 20000

    def k_e(m):
        root = np.sqrt(1.0 - m * np.sin(theta) ** 2)
        return np.mean(1.0 / root) * np.pi / 2, np.mean(root) * np.pi / 2

    target = max(a_curv, b_curv) / min(a_curv, b_curv)
    lo, hi = 1e-12, 1.0 - 1e-12
    for _ in range(200):
        m = 0.5 * (lo + hi)
        k, e = k_e(m)
        ratio = (e / (1.0 - m) - k) / (k - e)
        lo, hi = (m, hi) if ratio < target else (lo, m)
    k, e = k_e(m)
    a = (3.0 * load * (k - e) / (2.0 * np.pi * modulus * m * min(a_curv, b_curv))) ** (1.0 / 3.0)
    b = a * np.sqrt(1.0 - m)
    p0 = 3.0 * load / (2.0 * np.pi * a * b)
    return a, b, p0, p0 * b * k / modulus


def _circle(load, radius, modulus):
    """A sphere of radius R on a plane: a = (3PR/4E*)^(1/3), δ = a²/R, p0 = 3P/(2πa²)."""
    a = (3.0 * load * radius / (4.0 * modulus)) ** (1.0 / 3.0)
    return a, a * a / radius, 3.0 * load / (2.0 * np.pi * a * a)


def test_elliptic_integrals_match_tabulated_values():
    # Abramowitz & Stegun Table 17.1 (m = 0.5, 0.9)
    k, e = elliptic_integrals(jnp.array([0.0, 0.5, 0.9]))
    np.testing.assert_allclose(k, [np.pi / 2, 1.854074677301372, 2.578092113348173], rtol=1e-13)
    np.testing.assert_allclose(e, [np.pi / 2, 1.350643881047675, 1.104774732704073], rtol=1e-13)


@pytest.mark.parametrize("radius", [5.0, 40.0])
def test_sphere_on_a_plane_is_the_closed_form_circle(radius):
    a_curv, b_curv, _ = relative_curvatures(_sphere(radius), [0.0, 0.0], _plane, [0.0, 0.0], [0.0, 0.0, 1.0])
    np.testing.assert_allclose([a_curv, b_curv], [0.5 / radius] * 2, rtol=1e-12)
    contact = hertz_point_contact(LOAD, a_curv, b_curv, E_STAR)
    a, delta, p0 = _circle(LOAD, radius, E_STAR)
    np.testing.assert_allclose([contact.semi_major, contact.semi_minor], [a, a], rtol=1e-10)
    np.testing.assert_allclose(contact.approach, delta, rtol=1e-10)
    np.testing.assert_allclose(contact.max_pressure, p0, rtol=1e-10)


def test_crossed_cylinders_of_equal_radius_are_a_sphere_on_a_plane():
    radius = 12.0
    a_curv, b_curv, _ = relative_curvatures(_cylinder_along_x(radius), [0.0, 0.0], _cylinder_along_y(radius),
                                            [0.0, 0.0], [0.0, 0.0, 1.0])
    contact = hertz_point_contact(LOAD, a_curv, b_curv, E_STAR)
    a, delta, _ = _circle(LOAD, radius, E_STAR)
    np.testing.assert_allclose([contact.semi_major, contact.semi_minor, contact.approach], [a, a, delta], rtol=1e-10)


@pytest.mark.parametrize("r1, r2", [(5.0, 20.0), (3.0, 300.0), (50.0, 4.0)])
def test_crossed_cylinders_of_unequal_radii_give_johnsons_ellipse(r1, r2):
    a_curv, b_curv, direction = relative_curvatures(_cylinder_along_x(r1), [0.0, 0.0], _cylinder_along_y(r2),
                                                    [0.0, 0.0], [0.0, 0.0, 1.0])
    # cylinder 2 curves along x, cylinder 1 along y: A = 1/(2 max R), along the larger cylinder's curvature
    np.testing.assert_allclose([a_curv, b_curv], [0.5 / max(r1, r2), 0.5 / min(r1, r2)], rtol=1e-12)
    major_axis = [1.0, 0.0, 0.0] if r2 > r1 else [0.0, 1.0, 0.0]
    np.testing.assert_allclose(np.abs(direction), major_axis, atol=1e-12)
    contact = hertz_point_contact(LOAD, a_curv, b_curv, E_STAR)
    a, b, p0, delta = _johnson(LOAD, float(a_curv), float(b_curv), E_STAR)
    np.testing.assert_allclose([contact.semi_major, contact.semi_minor, contact.max_pressure, contact.approach],
                               [a, b, p0, delta], rtol=1e-7)


def test_the_approach_grows_as_the_load_to_the_two_thirds():
    contact = hertz_point_contact(jnp.array([100.0, 800.0]), 0.01, 0.2, E_STAR)
    np.testing.assert_allclose(contact.approach[1] / contact.approach[0], 8.0 ** (2.0 / 3.0), rtol=1e-12)
    np.testing.assert_allclose(contact.approach, contact.approach_coefficient * jnp.array([100.0, 800.0]) ** (2 / 3),
                               rtol=1e-12)
    zero = hertz_point_contact(0.0, 0.01, 0.2, E_STAR)
    assert float(zero.approach) == 0.0 and float(zero.max_pressure) == 0.0


def test_gradients_match_finite_differences():
    def approach(p, ratio):
        return hertz_point_contact(p, 0.01, 0.01 * ratio, E_STAR).approach

    for argnum, x0, h in ((0, 700.0, 1e-3), (1, 7.0, 1e-6)):
        args = [700.0, 7.0]
        grad = jax.grad(approach, argnums=argnum)(*args)
        plus, minus = list(args), list(args)
        plus[argnum] += h
        minus[argnum] -= h
        fd = (approach(*plus) - approach(*minus)) / (2 * h)
        np.testing.assert_allclose(grad, fd, rtol=1e-6)
    fd = (ellipse_ratio(5.0 + 1e-6) - ellipse_ratio(5.0 - 1e-6)) / 2e-6
    np.testing.assert_allclose(jax.grad(ellipse_ratio)(5.0), fd, rtol=1e-6)
    # the second derivative too (`second_order_root`): the impact differentiates rates
    d_ratio = jax.grad(ellipse_ratio)
    fd = (d_ratio(5.0 + 1e-4) - d_ratio(5.0 - 1e-4)) / 2e-4
    np.testing.assert_allclose(jax.grad(d_ratio)(5.0), fd, rtol=1e-6)


def test_the_gradient_is_finite_at_a_circular_contact():
    """A = B (sphere on a plane) is where the eigenvalues meet: the derivative of the approach
    with respect to the radius is the closed form's, dδ/dR = −δ/(3R)."""
    def approach(radius):
        a_curv, b_curv, _ = relative_curvatures(_sphere(radius), [0.0, 0.0], _plane, [0.0, 0.0], [0.0, 0.0, 1.0])
        return hertz_point_contact(LOAD, a_curv, b_curv, E_STAR).approach

    grad = jax.grad(approach)(10.0)
    _, delta, _ = _circle(LOAD, 10.0, E_STAR)
    np.testing.assert_allclose(grad, -delta / 30.0, rtol=1e-8)
