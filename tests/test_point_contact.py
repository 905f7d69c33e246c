"""Point-contact loaded contact (`gearjax.ltca.point_contact`): the sampled-section tooth
compliance against the constant-section cantilever, and the load sharing of point-contact
pairs (one pair exactly, the load conserved, the rigid contact at zero load, derivatives)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gearjax.ltca.point_contact import pair_loads, section_compliance, share_load, shared_approach

E, NU = 206000.0, 0.3


@pytest.mark.parametrize("angle, offset", [(0.0, 0.0), (0.4, 0.0), (0.3, 1.5)])
def test_a_constant_section_is_the_cantilever_closed_form(angle, offset):
    """Half thickness h over a length L: bending (L³cos²γ/3 − L²y_F sinγ cosγ + L y_F² sin²γ)/(E'I),
    shear 1.2 L cos²γ/(G'A), compression L sin²γ/(E'A)."""
    length, h = 9.0, 3.2
    x = jnp.linspace(0.0, length, 4001)
    c = section_compliance(x, jnp.full_like(x, h), offset, angle, E, NU)
    e_plane = E / (1 - NU**2)
    g_plane = e_plane / (2 * (1 + NU))
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


def test_one_pair_takes_the_whole_load_with_its_own_approach():
    c, h, gap, load = 2e-5, 3e-4, 0.004, 1800.0
    z, loads = share_load(load, jnp.array([gap]), jnp.array([c]), jnp.array([h]))
    np.testing.assert_allclose(z, gap + c * load + h * load ** (2 / 3), rtol=1e-12)
    np.testing.assert_allclose(loads, [load], rtol=1e-10)


def test_the_pairs_carry_the_load_together_and_open_pairs_carry_none():
    gaps = jnp.array([0.0, 0.002, 0.2, jnp.inf])
    linear = jnp.array([2e-5, 2.5e-5, 2e-5, 2e-5])
    hertz = jnp.array([3e-4, 3e-4, 3e-4, 3e-4])
    z, loads = share_load(2500.0, gaps, linear, hertz)
    np.testing.assert_allclose(jnp.sum(loads), 2500.0, rtol=1e-10)
    assert float(loads[0]) > float(loads[1]) > 0.0  # the second pair touches later
    assert float(loads[2]) == 0.0 and float(loads[3]) == 0.0 and float(z) < 0.2
    # each loaded pair's approach is the shared one
    closing = linear[:2] * loads[:2] + hertz[:2] * loads[:2] ** (2 / 3)
    np.testing.assert_allclose(closing, z - gaps[:2], rtol=1e-9)


def test_zero_load_gives_the_rigid_contact():
    gaps = jnp.array([0.004, 0.001, jnp.inf])
    z, loads = share_load(0.0, gaps, jnp.full(3, 2e-5), jnp.full(3, 3e-4))
    assert float(z) == pytest.approx(0.001, abs=1e-15)
    assert np.all(np.asarray(loads) == 0.0)


def test_batched_positions_and_the_derivatives_match_finite_differences():
    gaps = jnp.array([[0.0, 0.003], [0.001, 0.0]])
    linear, hertz = jnp.full((2, 2), 2e-5), jnp.full((2, 2), 3e-4)
    z = shared_approach(jnp.array([900.0, 900.0]), gaps, linear, hertz)
    assert z.shape == (2,)
    np.testing.assert_allclose(jnp.sum(pair_loads(z[:, None], gaps, linear, hertz), -1), 900.0, rtol=1e-10)

    def f(load, gap1):
        return shared_approach(load, jnp.array([0.0, gap1]), linear[0], hertz[0])

    for argnum, args, step in ((0, (900.0, 0.001), 1e-3), (1, (900.0, 0.001), 1e-8)):
        plus, minus = list(args), list(args)
        plus[argnum] += step
        minus[argnum] -= step
        fd = (f(*plus) - f(*minus)) / (2 * step)
        np.testing.assert_allclose(jax.grad(f, argnums=argnum)(*args), fd, rtol=1e-5)
