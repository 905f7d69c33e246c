"""Loaded point contact of the double-circular-arc seed pair (`gearjax.ltca.point_analysis`)
on the rigid TCA of `test_hard_cases_double_arc.py`'s program (the same scene structure:
the persistent test cache shares it): the torque is carried, zero torque is the rigid TE,
the mesh stiffness is the derivative of the torque, and the tooth sections and contact
ellipses are those of the seed's teeth."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gearjax as gj
from gearjax.ltca.point_analysis import (MIN_CURVATURE, ToothSection, closest_contact, parabola_peak,
                                         point_contact_analysis)
from gearjax.papers.double_arc import SEED_CASE

WINDOW = (-2, -1, 0, 1, 2, 3)  # test_hard_cases_double_arc.py's
TORQUE = 1.0e5  # N·mm, the seed's 100 N·m


@pytest.fixture(scope="module")
def seed():
    pair = gj.DoubleArcGearPair(SEED_CASE["teeth"], SEED_CASE["normal_module"], SEED_CASE["helix_angle_deg"],
                                SEED_CASE["face_width"], 0.0)
    tca = gj.simulate(gj.Scene(pair, pairs=WINDOW, accuracy="fast"), throw=False).tca
    resolved = pair.resolve()
    analysis = eqx.filter_jit(point_contact_analysis)  # the pair traced, its sections too

    def loaded(torque):
        return analysis(resolved, tca, jnp.asarray(torque, float))

    return resolved, tca, loaded


def test_the_pairs_carry_the_torque_at_every_position(seed):
    pair, _, loaded = seed
    result = loaded(TORQUE)
    gear_torque = TORQUE * pair.teeth[1] / pair.teeth[0]
    np.testing.assert_allclose(jnp.sum(result.arms * result.loads, axis=-1), gear_torque, rtol=1e-9)
    assert bool(jnp.all(jnp.isfinite(result.rotation))) and bool(jnp.all(result.rotation > 0.0))
    assert bool(jnp.all(result.loads >= 0.0))


def test_zero_torque_is_the_rigid_transmission_error(seed):
    """The solve's unloaded branch: no load anywhere and no lag (the gaps are measured from
    the largest of the pairs' peaks, so the rigid contact is at zero lag)."""
    _, tca, loaded = seed
    result = loaded(0.0)
    assert float(jnp.max(result.loads)) == 0.0
    np.testing.assert_allclose(result.transmission_error, tca.transmission_error, atol=1e-15)


def test_the_mesh_stiffness_is_the_derivative_of_the_torque(seed):
    """dT2/dΘ of the result against a central difference of two solves (the same program)."""
    pair, _, loaded = seed
    ratio = pair.teeth[1] / pair.teeth[0]
    step = 1e-3 * TORQUE
    plus, minus, mid = loaded(TORQUE + step), loaded(TORQUE - step), loaded(TORQUE)
    fd = 2 * step * ratio / (plus.rotation - minus.rotation)
    np.testing.assert_allclose(mid.mesh_stiffness, fd, rtol=1e-4)


def test_the_contact_ellipse_is_hertzs_for_the_pairs_load(seed):
    """Each loaded pair's ellipse and pressure are the Hertz contact of its own load: the
    approach c F + h F^(2/3) equals its share of the lag, and p0 = 3F/(2πab)."""
    _, _, loaded = seed
    result = loaded(TORQUE)
    loads = np.asarray(result.loads)
    on = loads > 0
    closing = result.linear_compliance * result.loads + result.hertz_coefficient * result.loads ** (2 / 3)
    np.testing.assert_allclose(np.asarray(closing)[on], np.asarray(result.arms * result.rotation[:, None]
                                                                     - result.gaps)[on], rtol=1e-8)
    p0 = 3 * loads[on] / (2 * np.pi * np.asarray(result.semi_major)[on] * np.asarray(result.semi_minor)[on])
    np.testing.assert_allclose(np.asarray(result.max_pressure)[on], p0, rtol=1e-10)
    # the seed's teeth are nearly conformal across the profile: an ellipse long along the face
    assert (np.asarray(result.semi_major)[on] > 3 * np.asarray(result.semi_minor)[on]).all()


def test_the_contacts_profile_curvature_is_the_basic_racks(seed):
    """The generated flanks touch with the relative curvature of the rack's arcs across the
    profile, B ≈ (1/ρ_a − 1/ρ_f)/2 (the normal section of a circular-arc flank is close to
    its rack's arc; decision 0009 gives the measured B and A), and A ≪ B: the flanks are
    nearly straight along the face."""
    pair, _, loaded = seed
    result = loaded(TORQUE)
    on = np.asarray(result.loads) > 0
    a, b = np.asarray(result.curvature_a)[on], np.asarray(result.curvature_b)[on]
    m = float(pair.normal_module)
    rack_b = 0.5 * (1.0 / (pair.rack.convex_radius * m) - 1.0 / (pair.rack.concave_radius * m))
    np.testing.assert_allclose(b, rack_b, rtol=0.1)
    assert (a > MIN_CURVATURE).all() and (a < 0.2 * b).all()  # flank contacts: not floored


def test_the_tooth_section_runs_from_the_root_circle_to_the_tip(seed):
    pair, _, _ = seed
    for gear in (0, 1):
        section = ToothSection.of(pair, gear)
        x, h = np.asarray(section.x), np.asarray(section.half_thickness)
        assert np.hypot(x[0], h[0]) == pytest.approx(float(pair.root_radius[gear]), abs=1e-6)
        assert np.hypot(x[-1], h[-1]) >= float(pair.tip_radius[gear]) - 1e-6
        assert (np.diff(x) >= 0).all() and (h > 0).all()
        # thickest at the root, thinnest at the tip
        assert h[0] == pytest.approx(h.max()) and h[-1] < 0.5 * h[0]


def _synthetic(tca, te, kinds=0, **fields):
    """`tca` with slice TEs `te` (rad, per slice) at every position and pair, every slice
    valid and of candidate `kinds` (0: flank; per slice or one for all), and `fields`."""
    shape = tca.slice_te.shape
    kind = jax.tree_util.tree_map(lambda _: jnp.broadcast_to(jnp.asarray(kinds, jnp.int32), shape), tca.kind)
    fields = {"valid": jnp.ones(shape, bool), **fields}
    names = ("slice_te", "kind", *fields)
    values = (jnp.broadcast_to(te, shape), kind, *fields.values())
    return eqx.tree_at(lambda t: tuple(getattr(t, n) for n in names), tca, values)


@pytest.mark.parametrize("end, spacings", [(0.0, 0.3), (1.0, -0.2), (-1.0, 0.3), (1.0, 0.5)])
def test_a_peak_near_a_face_end_is_located_as_one_mid_face(seed, end, spacings):
    """`closest_contact` on slice TEs that are a parabola along the face finds its vertex
    and value exactly (to rounding) wherever it lies (`spacings` slice spacings from
    mid-face or from the face end `end`): between two middle slices, between the outer middle
    slice and a face end (half a spacing away, a node of the fit), or beyond the face (then at
    the end, with the end's value). Fields are
    interpolated linearly at the located point: a pinion parameter equal to z comes back as
    the located z, a constant normal as itself."""
    _, tca, _ = seed
    z = np.asarray(tca.slice_z)
    n_mid = z.size - 2
    half = float(z[-1])
    vertex = end * half + spacings * 2.0 * half / n_mid
    te = 1e-3 - 2e-5 * (z - vertex) ** 2  # rad, z in mm
    shape = tca.slice_te.shape
    tilt = 0.02 * z  # rad: a normal turning along the face
    normal = np.broadcast_to(np.stack([np.sin(tilt), 0.0 * z, np.cos(tilt)], -1), shape + (3,))
    contact = closest_contact(_synthetic(tca, te, pinion_parameter=jnp.broadcast_to(z, shape), normal=jnp.asarray(normal)))
    expected = np.clip(vertex, -half, half)
    np.testing.assert_allclose(contact["z"], expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(contact["te"], 1e-3 - 2e-5 * (expected - vertex) ** 2, rtol=1e-13)
    np.testing.assert_allclose(contact["u1"], expected, rtol=0, atol=1e-12)
    # the normal: the unit vector of the linear blend of the two nodes' normals around z
    nodes = np.sort(z)
    right = np.clip(np.searchsorted(nodes, expected), 1, nodes.size - 1)
    w = (expected - nodes[right - 1]) / (nodes[right] - nodes[right - 1])
    blend = (1 - w) * np.stack([np.sin(0.02 * nodes[right - 1]), 0.0, np.cos(0.02 * nodes[right - 1])]) + w * np.stack(
        [np.sin(0.02 * nodes[right]), 0.0, np.cos(0.02 * nodes[right])])
    np.testing.assert_allclose(contact["normal"], np.broadcast_to(blend / np.linalg.norm(blend), shape[:2] + (3,)),
                               rtol=0, atol=1e-13)


def test_the_parabolas_vertex_is_exact_for_any_spacing():
    """`parabola_peak` through three unequally spaced points of a downward parabola gives its
    vertex and value; one opening upwards gives the middle point."""
    x = (-1.0, 0.5, 1.5)
    y = tuple(2.0 - 3.0 * (v - 0.2) ** 2 for v in x)
    vertex, peak, concave = parabola_peak(x, y)
    assert bool(concave)
    np.testing.assert_allclose([vertex, peak], [0.2, 2.0], rtol=1e-14)
    vertex, peak, concave = parabola_peak(x, tuple(-v for v in y))
    assert not bool(concave) and float(vertex) == 0.5 and float(peak) == -y[1]
    # a vertex beyond the outer point is clipped to it, with the parabola's value there
    vertex, peak, _ = parabola_peak((-1.0, 0.0, 1.0), (0.0, 1.0, 1.5))
    assert float(vertex) == 1.0 and float(peak) == 1.5


def test_no_parabola_is_fitted_across_a_change_of_contact_kind(seed):
    """Where a tip edge binds in the slice beside the largest one (the slice TE steps there),
    the largest slice is the contact, not the vertex of a parabola through the step: here
    the face end, with its own value, not the vertex that a fit through the step would put
    inside the face above it."""
    from gearjax.tca._slice_problem import CANDIDATES

    _, tca, _ = seed
    z = np.asarray(tca.slice_z)
    n_mid = z.size - 2
    te = np.where(z > z[n_mid - 2] + 1e-9, -4e-4 + 1e-4 * (z - z[-1]), -4e-3)  # a step below the last two
    kinds = np.where(z > z[n_mid - 2] + 1e-9, 0, 2)
    assert bool(jnp.all((_synthetic(tca, te, kinds).kind == CANDIDATES[2]) == (kinds == 2)))
    contact = closest_contact(_synthetic(tca, te, kinds))
    np.testing.assert_array_equal(contact["z"], z[-1])
    np.testing.assert_array_equal(contact["te"], -4e-4)
    # with one kind throughout, the same values give a vertex inside the face, above the end
    same = closest_contact(_synthetic(tca, te))
    assert (np.asarray(same["z"]) < z[-1]).all() and (np.asarray(same["te"]) > -4e-4).all()


def test_a_pair_out_of_mesh_leaves_the_contacts_derivatives_finite(seed):
    """A pair that touches nowhere (every slice TE -inf) has no contact (`gap` inf, `te`
    0) and does not spoil the reverse-mode derivative of the others' located contacts in the
    slice positions: finite, and equal to the forward-mode one."""
    _, tca, _ = seed
    z = np.asarray(tca.slice_z)
    te = 1e-3 - 2e-5 * (z - 0.3 * z[-1]) ** 2
    valid = np.ones(tca.slice_te.shape, bool)
    valid[:, 0] = False
    base = _synthetic(tca, te, valid=jnp.asarray(valid), pinion_parameter=jnp.broadcast_to(z, tca.slice_te.shape))
    contact = closest_contact(base)
    assert bool(jnp.all(jnp.isinf(contact["gap"][:, 0]))) and float(jnp.max(jnp.abs(contact["te"][:, 0]))) == 0.0

    def located(slice_z):
        c = closest_contact(eqx.tree_at(lambda t: t.slice_z, base, slice_z))
        return jnp.sum(jnp.where(jnp.isfinite(c["gap"]), c["z"] + c["u1"], 0.0))

    direction = jnp.asarray(np.linspace(0.5, 1.5, z.size))
    grad = jax.grad(located)(jnp.asarray(z))
    assert bool(jnp.all(jnp.isfinite(grad)))
    np.testing.assert_allclose(jnp.dot(grad, direction), jax.jvp(located, (jnp.asarray(z),), (direction,))[1],
                               rtol=1e-12)
