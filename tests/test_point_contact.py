"""Point-contact loaded contact (`gearjax.ltca.point_contact`): the sampled-section tooth
compliance against the constant-section cantilever, and the load sharing of point-contact
pairs (one pair exactly, the load conserved, the rigid contact at zero load, derivatives)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gearjax.ltca.point_contact import pair_loads, point_load_compliance, section_compliance, share_load, shared_rotation

E, NU = 206000.0, 0.3


@pytest.mark.parametrize("angle, offset", [(0.0, 0.0), (0.4, 0.0), (0.3, 1.5)])
def test_a_constant_section_is_the_cantilever_closed_form(angle, offset):
    """Half thickness h over a length L: bending (L³cos²γ/3 − L²y_F sinγ cosγ + L y_F² sin²γ)/(E'I),
    shear 1.2 L cos²γ/(G'A), compression L sin²γ/(E'A)."""
    length, h = 9.0, 3.2
    x = jnp.linspace(0.0, length, 4001)
    c = section_compliance(x, jnp.full_like(x, h), offset, angle, E, NU)
    e_plane = E
    g_plane = E / (2 * (1 + NU))
    area, inertia = 2 * h, (2 * h) ** 3 / 12
    cos, sin = np.cos(angle), np.sin(angle)
    bending = (length**3 * cos**2 / 3 - length**2 * offset * sin * cos + length * offset**2 * sin**2) / (e_plane * inertia)
    expected = bending + 1.2 * length * cos**2 / (g_plane * area) + length * sin**2 / (e_plane * area)
    np.testing.assert_allclose(c, expected, rtol=1e-7)


def test_a_tapered_section_is_stiffer_at_the_root_than_the_tip_section():
    """The compliance lies between those of constant sections at the tip and root thicknesses."""
    x = jnp.linspace(0.0, 8.0, 801)
    h = jnp.linspace(4.0, 2.0, 801)
    c = section_compliance(x, h, 0.0, 0.2, E, NU)
    thick = section_compliance(x, jnp.full_like(x, 4.0), 0.0, 0.2, E, NU)
    thin = section_compliance(x, jnp.full_like(x, 2.0), 0.0, 0.2, E, NU)
    assert thick < c < thin


@pytest.mark.parametrize("z", [0.0, 20.0, 26.5, 27.5])
def test_a_point_load_deflects_as_the_slices_shear_layer_does(z):
    """The continuous Green's function against `SliceCompliance`'s discrete model (slices
    coupled by a shear layer with free ends, `pasternak_compliance`) on 2 201 slices of a
    55 mm face: a unit load on the slice at z deflects it as the closed form says; c_t/(2λ)
    mid-face, twice that at the face end."""
    from gearjax.ltca.compliance import pasternak_compliance

    section, decay, width, n = 1.0e-4, 4.4, 55.0, 2201
    dz = width / n
    centres = -0.5 * width + dz * (np.arange(n) + 0.5)
    j = int(np.argmin(np.abs(centres - z)))
    matrix = pasternak_compliance(jnp.full(n, section), dz, decay)
    # the slice's load acts at its centre; the end slice's centre is dz/2 inside the face
    closed = float(point_load_compliance(section, decay, centres[j], width))
    assert float(matrix[j, j]) == pytest.approx(closed, rel=1e-5)
    if z == 0.0:
        assert closed == pytest.approx(section / (2 * decay), rel=1e-5)
    if z == 27.5:
        assert float(point_load_compliance(section, decay, z, width)) == pytest.approx(section / decay, rel=1e-5)


def test_one_pair_takes_the_whole_torque_with_its_own_approach():
    c, h, gap, arm, torque = 2e-5, 3e-4, 0.004, 45.0, 81000.0
    theta, loads = share_load(torque, jnp.array([gap]), jnp.array([arm]), jnp.array([c]), jnp.array([h]))
    load = torque / arm
    np.testing.assert_allclose(arm * theta, gap + c * load + h * load ** (2 / 3), rtol=1e-12)
    np.testing.assert_allclose(loads, [load], rtol=1e-10)


def test_the_pairs_carry_the_torque_together_and_open_pairs_carry_none():
    gaps = jnp.array([0.0, 0.002, 0.2, jnp.inf])
    arms = jnp.array([45.0, 44.0, 46.0, 45.0])
    linear = jnp.array([2e-5, 2.5e-5, 2e-5, 2e-5])
    hertz = jnp.full(4, 3e-4)
    theta, loads = share_load(110000.0, gaps, arms, linear, hertz)
    np.testing.assert_allclose(jnp.sum(arms * loads), 110000.0, rtol=1e-10)
    assert float(loads[0]) > float(loads[1]) > 0.0  # the second pair touches later
    assert float(loads[2]) == 0.0 and float(loads[3]) == 0.0 and float(arms[2] * theta) < 0.2
    # each loaded pair's approach is its arm times the shared lag, less its gap
    closing = linear[:2] * loads[:2] + hertz[:2] * loads[:2] ** (2 / 3)
    np.testing.assert_allclose(closing, arms[:2] * theta - gaps[:2], rtol=1e-9)


def test_zero_torque_gives_the_rigid_contact():
    gaps = jnp.array([0.004, 0.001, jnp.inf])
    theta, loads = share_load(0.0, gaps, jnp.full(3, 40.0), jnp.full(3, 2e-5), jnp.full(3, 3e-4))
    assert float(theta) == pytest.approx(0.001 / 40.0, abs=1e-16)
    assert np.all(np.asarray(loads) == 0.0)


def test_batched_positions_and_the_derivatives_match_finite_differences():
    gaps = jnp.array([[0.0, 0.003], [0.001, 0.0]])
    arms = jnp.full((2, 2), 45.0)
    linear, hertz = jnp.full((2, 2), 2e-5), jnp.full((2, 2), 3e-4)
    theta = shared_rotation(jnp.array([40000.0, 40000.0]), gaps, arms, linear, hertz)
    assert theta.shape == (2,)
    np.testing.assert_allclose(jnp.sum(arms * pair_loads(theta[:, None], gaps, arms, linear, hertz), -1), 40000.0,
                               rtol=1e-10)

    def f(torque, gap1):
        return shared_rotation(torque, jnp.array([0.0, gap1]), arms[0], linear[0], hertz[0])

    for argnum, args, step in ((0, (40000.0, 0.001), 1e-2), (1, (40000.0, 0.001), 1e-8)):
        plus, minus = list(args), list(args)
        plus[argnum] += step
        minus[argnum] -= step
        fd = (f(*plus) - f(*minus)) / (2 * step)
        np.testing.assert_allclose(jax.grad(f, argnums=argnum)(*args), fd, rtol=1e-5)


def test_the_second_derivatives_are_the_implicit_functions():
    """The shared lag's second derivatives (the impact differentiates its rates along the
    pinion angle once more) against central differences of its first: in the torque, and
    across the torque and a gap. With one Newton step from the root instead of two
    (`second_order_root`) they miss the $f_{\\Theta\\Theta}\\Theta'^2$ term."""
    arms, linear, hertz = jnp.full(2, 45.0), jnp.full(2, 2e-5), jnp.full(2, 3e-4)

    def f(torque, gap1):
        return shared_rotation(torque, jnp.stack([jnp.zeros_like(gap1), gap1]), arms, linear, hertz)

    torque, gap = 40000.0, 0.001
    d_torque = jax.grad(f, argnums=0)
    second = jax.jacfwd(d_torque, argnums=(0, 1))(torque, gap)
    for argnum, step in ((0, 1e-1), (1, 1e-7)):
        plus, minus = [torque, gap], [torque, gap]
        plus[argnum] += step
        minus[argnum] -= step
        fd = (d_torque(*plus) - d_torque(*minus)) / (2 * step)
        np.testing.assert_allclose(second[argnum], fd, rtol=1e-5)


def test_the_second_order_root_keeps_the_first_steps_value():
    """`second_order_root` returns the first Newton step's value bit for bit (the second
    step only adds derivatives), for a finite root and an infinite one (no pair in mesh:
    the lag is infinite, not NaN)."""
    from gearjax._numerics import second_order_root

    p = jnp.asarray(2.0)
    cube_root = lambda x: x - (x**3 - p) / (3.0 * x**2)  # noqa: E731
    root = jnp.asarray(2.0 ** (1 / 3) * (1 + 1e-6))  # a loose root: the two steps differ
    assert float(second_order_root(root, cube_root)) == float(cube_root(root))
    assert float(second_order_root(root, cube_root)) != float(cube_root(cube_root(root)))
    theta = shared_rotation(1000.0, jnp.full(2, jnp.inf), jnp.full(2, 45.0), jnp.full(2, 2e-5), jnp.full(2, 3e-4))
    assert np.isposinf(float(theta))
