"""Involute curvilinear-tooth gears (seed 002) on the common TCA."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gearjax as gj
from gearjax.papers.curvilinear import contact_line
from gearjax.tca import ContactKind, tooth_contact_analysis


def seed_pair(radius=12.0):
    return gj.CurvilinearGearPair((20, 30), 2.0, 20.0, 20.0, radius)


@pytest.mark.parametrize("radius", [12.0, 15.0, 100.0])
def test_contact_line_is_the_closed_form_arc(radius):
    pair = seed_pair(radius)
    line = contact_line(pair, 9.6, face_slices=81)
    assert line["all_slices_in_contact"]
    assert abs(line["te_rad"]) < 1e-12
    assert line["max_distance_from_arc_mm"] < 1e-9
    # polyline through 83 points of an arc of radius R_t: chord error ~ h^2/(24 R_t^2)
    h = 20.0 / 81
    assert line["length_mm"] == pytest.approx(line["closed_form_length_mm"], rel=2 * h * h / (24 * radius * radius) + 1e-12)
    # the closed form against the arc length of the lead displacement d(z) on the plane of
    # action, integral of sqrt(1 + d'(z)^2) over the face (Gauss-Legendre, d' by autodiff)
    nodes, weights = np.polynomial.legendre.leggauss(64)
    slope = jax.vmap(jax.grad(lambda z: pair.lead_displacement(z)))(jnp.asarray(10.0 * nodes))
    length = 10.0 * float(np.sum(weights * np.sqrt(1.0 + np.asarray(slope) ** 2)))
    assert line["closed_form_length_mm"] == pytest.approx(length, rel=1e-9)


def test_seed_contact_parameter():
    pair = seed_pair()
    theta = math.acos(2.5 * float(pair.base_radius[0]) / float(pair.center_distance)) + math.pi / 12
    assert theta == pytest.approx(0.6109, abs=5e-5)


@eqx.filter_jit
def cycle(pair, accuracy):
    return tooth_contact_analysis(pair, accuracy=accuracy, pairs=(-2, -1, 0, 1, 2))


def test_large_trace_radius_is_the_spur_gear():
    acc = gj.Accuracy(positions_per_pitch=12, face_slices=9)
    curved = cycle(seed_pair(1e12), acc)
    spur = cycle(gj.InvoluteGearPair((20, 30), 2.0, 20.0, 0.0, 20.0), acc)
    assert float(jnp.max(jnp.abs(curved.transmission_error - spur.transmission_error))) < 1e-12
    both = curved.valid & spur.valid
    assert bool(jnp.all(curved.valid == spur.valid))
    gap = jnp.where(both[..., None], curved.pinion_point - spur.pinion_point, 0.0)
    assert float(jnp.max(jnp.abs(gap))) < 1e-9


@pytest.mark.parametrize("radius", [10.0 * (1 + 1e-9), 10.0001, 10.5])
def test_trace_radius_near_half_face_width_stays_finite_and_conjugate(radius):
    pair = seed_pair(radius)
    acc = gj.Accuracy(positions_per_pitch=12, face_slices=9)
    tca = cycle(pair, acc)
    assert float(jnp.max(jnp.abs(tca.transmission_error))) < 1e-12
    flank = tca.valid & (tca.kind == ContactKind.flank)
    assert bool(jnp.all(jnp.isfinite(jnp.where(flank[..., None], tca.pinion_point, 0.0))))
    # every flank contact lies on the arc s1 = r_b1 (tan a + phi - k p) - d(z) of the plane of action
    rb1 = float(pair.base_radius[0])
    k = tca.pair_index.astype(float)[None, :, None]
    phi = tca.pinion_angle[:, None, None]
    s1 = rb1 * (math.tan(float(pair.working_pressure_angle)) + phi - k * 2 * math.pi / 20) - pair.lead_displacement(tca.slice_z)
    expect = jax.vmap(jax.vmap(jax.vmap(pair.line_of_action_point)))(s1, jnp.broadcast_to(tca.slice_z, s1.shape))
    assert float(jnp.max(jnp.where(flank[..., None], jnp.abs(tca.pinion_point - expect), 0.0))) < 1e-8
    assert float(pair.contact_line_length) <= math.pi * 10.0 + 1e-12


def test_relief_te_is_differentiable_in_the_trace_radius():
    """Profile relief makes the TE depend on how the curved contact lines cross the relief
    zones; d(min TE)/d(R_t) and d(min TE)/d(relief) against central differences."""
    acc = gj.Accuracy(positions_per_pitch=12, face_slices=9)

    def te(radius, relief):
        pair = gj.CurvilinearGearPair((20, 30), 2.0, 20.0, 20.0, radius)
        mod = gj.FlankModification(root_relief=relief, tip_relief=relief, root_relief_length=4.5, tip_relief_length=4.5)
        scene = gj.Scene(pair, mod,
                         accuracy=acc, pairs=(-2, -1, 0, 1, 2))
        return jnp.min(gj.simulate(scene).tca.transmission_error)

    grad = eqx.filter_jit(jax.grad(te, argnums=(0, 1)))
    value = eqx.filter_jit(te)
    r0, c0 = jnp.asarray(20.0), jnp.asarray(0.01)
    assert float(value(r0, c0)) < -1e-5  # the relief shows in the TE here
    g_r, g_c = grad(r0, c0)
    fd_r = (float(value(r0 + 1e-4, c0)) - float(value(r0 - 1e-4, c0))) / 2e-4
    fd_c = (float(value(r0, c0 + 1e-6)) - float(value(r0, c0 - 1e-6))) / 2e-6
    assert float(g_r) == pytest.approx(fd_r, rel=1e-4)
    assert float(g_c) == pytest.approx(fd_c, rel=1e-4)
    # vmap over two radii equals single runs
    batch = eqx.filter_jit(jax.vmap(te, (0, None)))(jnp.array([13.0, 20.0]), c0)
    assert float(batch[1]) == pytest.approx(float(value(r0, c0)), rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("radius", [10.0, 5.0, -1.0, float("nan")])
def test_trace_radius_must_exceed_half_the_face_width(radius):
    with pytest.raises(ValueError, match="tooth_trace_radius"):
        seed_pair(radius)
