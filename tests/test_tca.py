"""General TCA: conjugate action, meshing equation, TE shapes from theory, edge contact."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gearjax import Accuracy, FlankDepth, FlankModification, InvoluteGearPair, MeshErrors
from gearjax.papers.seed001 import paper_optimum
from gearjax.tca import ContactKind, pair_window, tooth_contact_analysis

ACC = Accuracy(positions_per_pitch=12, face_slices=7)


@eqx.filter_jit
def tca(pair, depth, accuracy, pairs, angles=None):
    return tooth_contact_analysis(pair, depth, accuracy=accuracy, pairs=pairs, pinion_angles=angles)


def plane_distance(pair, points):
    """Signed distance of points from the plane of action (mm)."""
    a = float(pair.working_pressure_angle)
    rb1 = float(pair.base_radius[0])
    t1 = np.array([rb1 * math.cos(a), -rb1 * math.sin(a)])
    normal = np.array([math.cos(a), -math.sin(a)])
    return (np.asarray(points)[..., :2] - t1) @ normal


@pytest.fixture(scope="module")
def seed_unmodified(seed_pair):
    return tca(seed_pair, FlankDepth(), ACC, pair_window(seed_pair))


def test_unmodified_pair_has_zero_te_and_contacts_on_the_plane_of_action(seed_pair, seed_unmodified):
    r = seed_unmodified
    assert np.max(np.abs(np.asarray(r.transmission_error))) < 1e-9
    contact = np.asarray(r.in_contact(1e-9))
    # at every position some slices touch, and only contact lines of the pairs in mesh
    assert np.all(contact.sum((1, 2)) >= ACC.face_slices)
    d = plane_distance(seed_pair, r.pinion_point)
    assert np.max(np.abs(d[contact])) < 1e-9
    # both flank points coincide at the contact
    gap = np.linalg.norm(np.asarray(r.pinion_point) - np.asarray(r.gear_point), axis=-1)
    assert np.max(gap[contact]) < 1e-9


def test_contact_lines_are_inclined_at_the_base_helix_angle(seed_pair, seed_unmodified):
    r = seed_unmodified
    contact = np.asarray(r.in_contact(1e-9))
    s = np.asarray(r.pinion_parameter)
    z = np.asarray(r.slice_z)
    tan_bb = math.tan(float(seed_pair.base_helix_angle))
    slopes = []
    for i in range(contact.shape[0]):
        for k in range(contact.shape[1]):
            mask = contact[i, k, : ACC.face_slices]
            if mask.sum() >= 2:
                slopes.append(np.polyfit(z[: ACC.face_slices][mask], s[i, k, : ACC.face_slices][mask], 1)[0])
    assert len(slopes) > 10
    np.testing.assert_allclose(slopes, tan_bb, rtol=1e-9)


def test_unmodified_spur_pair_has_zero_te(spur_pair):
    r = tca(spur_pair, FlankDepth(), ACC, pair_window(spur_pair))
    assert np.max(np.abs(np.asarray(r.transmission_error))) < 1e-9
    # contact ratio between 1 and 2: one or two pairs carry at each position
    pairs_in_contact = np.asarray(r.in_contact(1e-9)).any(-1).sum(-1)
    assert set(np.unique(pairs_in_contact)) <= {1, 2}
    assert {1, 2} <= set(np.unique(pairs_in_contact))


def test_meshing_equation_holds_at_every_contact(seed_pair, seed_unmodified):
    # unmodified: the ratio is constant, n . v12 = 0 with the nominal ratio
    r = seed_unmodified
    contact = np.asarray(r.in_contact(1e-9))
    nv = np.einsum("...i,...i", np.asarray(r.normal), np.asarray(r.relative_velocity))
    rb1 = float(seed_pair.base_radius[0])
    assert np.max(np.abs(nv[contact])) / rb1 < 1e-12
    # the normals of pinion and gear are collinear: n is along the plane-of-action normal
    beta_b = float(seed_pair.base_helix_angle)
    n = np.asarray(r.normal)[contact]
    assert np.max(np.abs(np.abs(n[:, 2]) - math.sin(beta_b))) < 1e-12


def test_meshing_equation_with_modification_uses_the_instantaneous_ratio(seed_pair):
    # modified flanks: the ratio varies; n . v12 = 0 with omega2 = z1/z2 + dTE/dphi1
    depth = FlankDepth(pinion=FlankModification(tip_relief=0.02, tip_relief_length=12.0, crowning=0.01))
    angles = jnp.linspace(-0.09, 0.09, 7)
    pairs = pair_window(seed_pair, 2)
    r = tca(seed_pair, depth, ACC, pairs, angles)
    slope = jax.jvp(lambda a: tca(seed_pair, depth, ACC, pairs, a).transmission_error, (angles,), (jnp.ones_like(angles),))[1]
    pair_idx, slice_idx = (np.asarray(a) for a in r.binding)
    rows = np.arange(angles.size)
    n = np.asarray(r.normal)[rows, pair_idx, slice_idx]
    x = np.asarray(r.pinion_point)[rows, pair_idx, slice_idx]
    v = np.asarray(r.relative_velocity)[rows, pair_idx, slice_idx]
    a = float(seed_pair.center_distance)
    # add the gear's extra angular velocity -slope e_z (clockwise positive): -(-slope e_z) x (x - O2)
    lever = np.stack([-(x[:, 1]), x[:, 0] - a, np.zeros(len(x))], -1)
    v_inst = v + np.asarray(slope)[:, None] * lever
    residual = np.einsum("ij,ij->i", n, v_inst) / float(seed_pair.base_radius[0])
    flank = np.asarray(r.kind == ContactKind.flank)[rows, pair_idx, slice_idx]
    assert flank.sum() >= 4
    # the binding slice is the best of the discrete slices, so the residual is that of a
    # point a fraction of a slice from the exact peak: small, and exactly zero where the
    # contact is a line (unmodified zone).
    assert np.max(np.abs(residual[flank])) < 2e-4
    nonzero_slope = np.abs(np.asarray(slope)) > 1e-8
    assert nonzero_slope.any()


def tip_relief_case(pair):
    z1 = pair.teeth[0]
    pbt = float(pair.transverse_base_pitch)
    eps = float(pair.transverse_contact_ratio)
    length = 0.6 * eps * pbt  # longer than the double-contact zone (eps - 1) p_bt
    amount = 0.01
    s_start = float(pair.start_of_active_profile[0])
    s_tip = float(pair.tip_roll_length[0])
    rb1, rb2 = (float(v) for v in pair.base_radius)
    alpha = float(pair.working_pressure_angle)
    # pair 0 at roll s is alone until pair +1 reaches its start of active profile at
    # s* = s_start + p_bt; the relief there is the TE dip of theory.
    s_star = s_start + pbt
    dip = amount * ((s_star - (s_tip - length)) / length) ** 2
    phi_star = s_star / rb1 - math.tan(alpha)
    del z1
    return FlankModification(tip_relief=amount, tip_relief_length=length), dip / rb2, phi_star, rb1


def test_tip_relief_te_dip_amplitude_and_location_plane_of_action(spur_pair):
    mod, dip, phi_star, rb1 = tip_relief_case(spur_pair)
    acc = ACC.replace(tca_method="plane_of_action")
    eps = 1e-9
    angles = jnp.array([phi_star - 0.02, phi_star - eps, phi_star + eps, phi_star + 0.02])
    r = tca(spur_pair, FlankDepth(pinion=mod), acc, pair_window(spur_pair, 2), angles)
    te = np.asarray(r.transmission_error)
    # just before the next pair enters, TE = -relief of the only pair in contact
    assert te[1] == pytest.approx(-dip, rel=1e-6)
    # earlier in single contact the relief (hence |TE|) is smaller: the dip is at phi*
    assert -dip < te[0] < 0
    # the entering unrelieved pair restores zero TE
    assert abs(te[2]) < 1e-15 and abs(te[3]) < 1e-15


def test_tip_relief_te_surface_agrees_with_theory_and_edge_contact_cuts_the_dip(spur_pair):
    mod, dip, phi_star, rb1 = tip_relief_case(spur_pair)
    angles = phi_star + jnp.linspace(-0.03, 0.01, 17)
    depth = FlankDepth(pinion=mod)
    pairs = pair_window(spur_pair, 2)
    surf = tca(spur_pair, depth, ACC, pairs, angles)
    poa = tca(spur_pair, depth, ACC.replace(tca_method="plane_of_action"), pairs, angles)
    ts, tp = np.asarray(surf.transmission_error), np.asarray(poa.transmission_error)
    # edge contact can only add first contacts: surface TE >= plane-of-action TE
    assert np.all(ts >= tp - 1e-12)
    pair_idx, slice_idx = (np.asarray(a) for a in surf.binding)
    kind = np.asarray(surf.kind_name)[np.arange(angles.size), pair_idx, slice_idx]
    flank = kind == "flank"
    # where the binding contact is on the flanks, both methods agree up to the second-order
    # effect of the relief slope d' (the true tangency leaves the plane of action):
    # |dTE| ~ rho_rel d'^2 / 2 with rho_rel the relative radius of curvature
    s1, s2 = 20.0, float(spur_pair.line_of_action_length) - 20.0
    slope = 2 * float(mod.tip_relief) / float(mod.tip_relief_length)
    bound = 0.5 * (s1 * s2 / (s1 + s2)) * slope**2 / float(spur_pair.base_radius[1])
    np.testing.assert_allclose(ts[flank], tp[flank], atol=bound)
    assert np.max(np.abs(ts[flank] - tp[flank])) > 1e-4 * bound  # it is a real, not a zero, effect
    # just before phi*, the incoming pair's gear tip edge touches first (before its SAP)
    assert np.any(kind == "gear_tip_edge")
    assert np.all(angles[kind == "gear_tip_edge"] <= phi_star + 1e-12)
    # so the dip seen by the surface TCA is shallower than the plane-of-action one
    assert -dip * (1 - 1e-6) < ts.min() < 0


def test_crowning_te_dip_from_contact_line_geometry():
    # eps_alpha < 1: between two contact lines crossing mid-face there is a gap where the
    # nearest line ends |z*| = (p_bt - g_alpha) / (2 tan beta_b) from mid-face; full crowning
    # y5 (w / (b/2))^2 gives the dip y5 (2 z*/b)^2 / cos(beta_b), transverse.
    pair = InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0, addendum_coefficient=0.6)
    y5 = 0.05
    depth = FlankDepth(pinion=FlankModification(crowning=y5))
    pbt = float(pair.transverse_base_pitch)
    g_alpha = float(pair.transverse_contact_ratio) * pbt
    beta_b = float(pair.base_helix_angle)
    b = float(pair.face_width)
    z_star = (pbt - g_alpha) / (2 * math.tan(beta_b))
    dip = y5 * (2 * z_star / b) ** 2 / math.cos(beta_b) / float(pair.base_radius[1])
    # location: the pair-0 line crosses mid-face at s_end + (p_bt - g_alpha)/2
    s_end = float(pair.tip_roll_length[0])
    s0 = s_end + 0.5 * (pbt - g_alpha)
    phi_star = s0 / float(pair.base_radius[0]) - math.tan(float(pair.working_pressure_angle))
    angles = phi_star + jnp.array([-0.004, 0.0, 0.004])
    pairs = pair_window(pair, 3)
    for method in ("plane_of_action", "surface"):
        acc = Accuracy(positions_per_pitch=12, face_slices=41, tca_method=method)
        te = np.asarray(tca(pair, depth, acc, pairs, angles).transmission_error)
        assert te[1] == pytest.approx(-dip, rel=2e-3), method
        assert te[0] > te[1] and te[2] > te[1], method


def test_base_pitch_deviation_gives_early_edge_contact(seed_pair):
    # f_pb < 0: pair +1 stands 5 um proud and comes into mesh early, on the gear tip edge
    f_pb = -0.005
    depth = FlankDepth(errors=MeshErrors(base_pitch_deviation=f_pb))
    r = tca(seed_pair, depth, ACC.replace(positions_per_pitch=24), pair_window(seed_pair))
    te = np.asarray(r.transmission_error)
    full = -f_pb / math.cos(float(seed_pair.base_helix_angle)) / float(seed_pair.base_radius[1])
    # while pair +1 is in flank contact it leads by exactly 5 um (normal)
    assert te.max() == pytest.approx(full, rel=1e-9)
    assert np.all(te <= full * (1 + 1e-9)) and np.all(te >= -1e-12)
    pair_idx, slice_idx = (np.asarray(a) for a in r.binding)
    kind = np.asarray(r.kind_name)[np.arange(te.size), pair_idx, slice_idx]
    # before its start of active profile it touches with the gear's tip edge, TE rising
    early = kind == "gear_tip_edge"
    assert early.any()
    assert np.all((te[early] > 0) & (te[early] < full))


def test_the_kept_contacts_derivatives_are_those_through_its_own_solve(seed_pair):
    """The TCA solves on stop-gradient'ed data and gives each kept contact the derivatives of
    its own root (`attach_derivatives`): in the pinion angles and a base pitch deviation they
    equal the derivatives through that slice's own Newton solve (`_solution.ImplicitAdjoint`),
    for flank and gear-tip-edge contacts alike (the early edge contact of
    `test_base_pitch_deviation_gives_early_edge_contact`), and reverse mode gives what
    forward mode gives."""
    import optimistix as optx

    from gearjax.tca._slice import solve_slice
    from gearjax.tca._slice_problem import kind_index, make_problem
    from gearjax.tca.analysis import _lead_correction, on_grid
    from gearjax.tca.grid import face_slices, positions

    acc = ACC.replace(positions_per_pitch=24)
    pairs = pair_window(seed_pair)
    ks = jnp.asarray(pairs)
    z, _ = face_slices(seed_pair, acc)
    rtol, atol = acc.newton_tolerances(jnp.float64)
    data = jnp.append(positions(seed_pair, acc, 1), -0.005)  # pinion angles (rad), f_pb (mm)

    def depth(f_pb):
        return FlankDepth(errors=MeshErrors(base_pitch_deviation=f_pb))

    def kept(p):
        r = tooth_contact_analysis(seed_pair, depth(p[-1]), accuracy=acc, pairs=pairs, pinion_angles=p[:-1])
        offset = jnp.where(r.valid, r.slice_te, 0.0)
        return jnp.stack([r.pinion_parameter, r.gear_parameter, offset]), (r.valid, kind_index(r.kind))

    def through_solve(p):
        def one(phi1, k, zz):
            c = solve_slice(make_problem(seed_pair, depth(p[-1]), k, zz, phi1), optx.Newton(rtol=rtol, atol=atol),
                            acc.newton_max_steps)
            offset = jnp.where(c.valid, c.offset + _lead_correction(seed_pair, zz), 0.0)
            return jnp.stack([c.pinion_parameter, c.gear_parameter, offset])

        return jnp.moveaxis(on_grid(one, p[:-1], ks, z), -1, 0)

    (values, (valid, kind)), jac = jax.jit(lambda p: (kept(p), jax.jacfwd(lambda q: kept(q)[0])(p)))(data)
    ref_values, ref_jac = jax.jit(lambda p: (through_solve(p), jax.jacfwd(through_solve)(p)))(data)
    valid, kind = np.asarray(valid), np.asarray(kind)
    # where both solved the same contact (the fallback, which `solve_slice` lacks, changed none here)
    same = valid & np.all(np.abs(np.asarray(values) - np.asarray(ref_values)) < 1e-12, axis=0)
    assert same.sum() == valid.sum() > 0
    assert set(np.unique(kind[same])) >= {0, 1}  # flank and gear-tip edge contacts
    weights = np.random.default_rng(0).standard_normal(np.shape(values))
    grad = jax.jit(jax.grad(lambda p: jnp.sum(weights * kept(p)[0])))(data)
    np.testing.assert_allclose(grad, np.tensordot(weights, np.asarray(jac), weights.ndim), rtol=1e-9, atol=1e-9)
    jac, ref_jac = np.moveaxis(np.asarray(jac), 0, -2), np.moveaxis(np.asarray(ref_jac), 0, -2)
    np.testing.assert_allclose(jac[same], ref_jac[same], rtol=1e-9, atol=1e-12)


def test_plane_of_action_fast_path_is_second_order_accurate(seed_pair):
    """The fast path's separations exceed the true ones by the second-order effect of the
    relief slope. Near the conjugate point the transverse gap as a function of the pinion
    roll shift ds is delta_t' ds + (K + delta_t'') ds^2 / 2 with K = (s1/r_b1)^2 / rho_rel
    (conjugate involutes, rho_rel = s1 s2/(s1 + s2)); its minimum lies delta_t'^2 /
    (2 (K + delta_t'')) below the plane-of-action value."""
    mod = paper_optimum()
    depth = FlankDepth(pinion=mod)
    pairs = pair_window(seed_pair)
    surf = tca(seed_pair, depth, ACC, pairs)
    fast = tca(seed_pair, depth, ACC.replace(tca_method="plane_of_action"), pairs)
    rb1, rb2 = (float(v) for v in seed_pair.base_radius)
    cos_bb = math.cos(float(seed_pair.base_helix_angle))
    # TE is set by the unmodified central zone here: both methods agree to round-off
    diff_um = np.abs(np.asarray(surf.transmission_error) - np.asarray(fast.transmission_error)) * rb2 * 1e3
    assert diff_um.max() < 1e-6
    s_surf, s_fast = np.asarray(surf.separation), np.asarray(fast.separation)
    both = np.asarray(surf.valid) & np.asarray(fast.valid) & np.asarray(surf.kind == ContactKind.flank) & (s_surf < 0.02)
    assert both.sum() > 50
    excess = s_fast[both] - s_surf[both]
    assert np.all(excess >= -1e-10)  # the exact first contact is never farther away
    start, tip = seed_pair.relief_coordinates(0)
    s1 = np.asarray(fast.pinion_parameter)[both]
    z = np.broadcast_to(np.asarray(fast.slice_z), s_fast.shape)[both]
    d1 = jax.grad(mod.depth)
    d2 = jax.grad(d1)
    args = (start, tip, seed_pair.face_width)
    slope = np.array([float(d1(si, zi, *args)) for si, zi in zip(s1, z)]) / cos_bb
    curvature = np.array([float(d2(si, zi, *args)) for si, zi in zip(s1, z)]) / cos_bb
    s2 = float(seed_pair.line_of_action_length) - s1
    k = (s1 / rb1) ** 2 * (s1 + s2) / (s1 * s2)
    predicted = 0.5 * slope**2 / (k + curvature) * cos_bb  # back to the normal direction
    np.testing.assert_allclose(excess, predicted, rtol=0.03, atol=2e-6)
    assert excess.max() > 2e-4  # a real effect: 0.2 um and more near the root


def test_safeguarded_newton_converges_where_newton_diverges():
    """f(x) = arctan x from x = 1.5: plain Newton's steps overshoot further each time
    (1.5 → -1.69 → 2.32 → ...) and never converge; `SafeguardedNewton` (the TCA's fallback)
    backtracks on |f|², which has no other minimum, and reaches the root 0."""
    import optimistix as optx

    from gearjax.tca._newton import SafeguardedNewton

    def f(y, args):
        return jnp.arctan(y)

    y0 = jnp.full(1, 1.5)
    newton = optx.root_find(f, optx.Newton(rtol=1e-12, atol=1e-12), y0, max_steps=40, throw=False)
    assert newton.result != optx.RESULTS.successful
    sol = optx.root_find(f, SafeguardedNewton(rtol=1e-12, atol=1e-12), y0, max_steps=40, throw=False)
    assert sol.result == optx.RESULTS.successful
    assert abs(float(sol.value[0])) < 1e-12


def test_flank_contact_inside_a_steep_tip_relief_is_not_missed():
    """A spur pair with a short, deep pinion tip relief (27 um over 0.27 mm, random design
    0 of `test_hard_cases.py`) just after the conjugate contact has left the pinion's tip:
    the first contact is on the flanks at the start of the relief, ahead of the tip edge
    (a flank solve that runs past the tip would make the TCA take the edge, ~3e-4 rad lower,
    and the impact search meet a jump). The TCA's slice values equal the largest offset
    along the curve of coincident points, found independently by brute force: for 2 001
    pinion profile points $u_1$ on the active flank, the gear point $u_2$ and offset that
    bring the flanks together (2 equations, Newton), the largest offset among those with
    $u_2$ on the gear's active flank, refined on 2 001 points between the best one's
    neighbours. (Before the fix, the TCA's values at these angles were those of the tip
    edge instead.)"""
    import optimistix as optx

    from gearjax.tca._slice_problem import make_problem

    pair = InvoluteGearPair((29, 71), 2.2647, 19.2261, 0.0, 19.1957, (-0.2895, 0.1502),
                            addendum_coefficient=1.0743, dedendum_coefficient=1.3243).resolve()
    depth = FlankDepth(FlankModification(0.02716, 0.02701, 0.49686, 0.26748))
    (lo1, hi1), (lo2, hi2) = (tuple(float(v) for v in pair.profile_limits(g)) for g in (0, 1))
    rb1, tan_a = float(pair.base_radius[0]), math.tan(float(pair.working_pressure_angle))
    past_tip = np.array([0.05, 0.2, 0.4, 0.6])  # conjugate contact beyond the pinion tip (mm)
    angles = jnp.asarray((hi1 + past_tip) / rb1 - tan_a)
    # The spur pair's slices are alike, so 3 do: with ACC's 9, the 36 missed flank solves
    # would exceed the fallback's capacity for this small grid (32, `fallback_capacity`)
    # and the last 4 would stay unconverged, as reported.
    result = tca(pair, depth, ACC.replace(face_slices=1), (0,), angles)
    assert int(np.sum(result.unconverged)) == 0

    u1 = jnp.linspace(lo1, hi1, 2001)

    def largest_offset(angle):
        problem = make_problem(pair, depth, 0, 0.0, angle)

        def mate(u):
            def coincide(y, _):
                return problem.pinion_point(u) - problem.gear_point(y[0], y[1])

            start = jnp.stack([pair.line_of_action_length - u, jnp.zeros_like(u)])
            sol = optx.root_find(coincide, optx.Newton(rtol=1e-12, atol=1e-14), start, max_steps=50, throw=False)
            ok = (sol.result == optx.RESULTS.successful) & (sol.value[0] >= lo2) & (sol.value[0] <= hi2)
            return jnp.where(ok, sol.value[1], -jnp.inf)

        coarse = jax.vmap(mate)(u1)
        best = jnp.argmax(coarse)  # then 2 001 points between its neighbours: the offset's
        # curvature in a relief (~0.03 rad/mm^2) would leave ~3e-7 rad on the coarse grid
        fine = jnp.linspace(u1[jnp.maximum(best - 1, 0)], u1[jnp.minimum(best + 1, u1.size - 1)], 2001)
        return jnp.max(jax.vmap(mate)(fine))

    expected = np.asarray(jax.jit(jax.vmap(largest_offset))(angles))
    te = np.asarray(result.slice_te[:, 0, :])  # (angle, slice): every slice alike (spur)
    assert np.all(np.isfinite(expected))
    np.testing.assert_allclose(te, np.broadcast_to(expected[:, None], te.shape), rtol=0, atol=1e-8)
    # and it is a flank contact, not the tip edge's (an interior maximum)
    assert np.all(np.asarray(result.kind == ContactKind.flank)[:, 0, :])


def test_edge_reachable_agrees_with_a_fine_scan_of_the_flanks(seed_pair):
    """`edge_reachable` samples the active flanks' distance from the gear's axis at 5 points;
    a scan of 2 001 points agrees at 96 pinion angles over three pitches around the mesh
    of pair 0 (both answers occur for both edges), and wherever Newton's edge solve
    converged on the active flanks the corner was judged able to reach them."""
    import optimistix as optx

    from gearjax.tca._slice import edge_reachable, solve_candidates
    from gearjax.tca._slice_problem import make_problem

    pair = seed_pair.resolve()
    depth = FlankDepth(pinion=paper_optimum())
    (lo1, hi1), (lo2, hi2) = pair.profile_limits(0), pair.profile_limits(1)
    o2 = pair.center(1)
    pitch = float(pair.angular_pitch(0))
    angles = jnp.linspace(-1.5 * pitch, 1.5 * pitch, 96)
    u1, u2 = jnp.linspace(lo1, hi1, 2001), jnp.linspace(lo2, hi2, 2001)

    def one(angle):
        problem = make_problem(pair, depth, 0, 0.0, angle)
        zero = jnp.zeros_like(angle)
        pinion_flank = jax.vmap(lambda u: jnp.linalg.norm(problem.pinion_point(u) - o2))(u1)
        gear_flank = jax.vmap(lambda u: jnp.linalg.norm(problem.gear_point(u, zero) - o2))(u2)
        gear_corner = jnp.linalg.norm(problem.gear_point(hi2, zero) - o2)
        pinion_corner = jnp.linalg.norm(problem.pinion_point(hi1) - o2)
        scan = jnp.stack([gear_corner >= pinion_flank.min(), gear_corner <= pinion_flank.max(),
                          pinion_corner >= gear_flank.min(), pinion_corner <= gear_flank.max()])
        values, converged, failed = solve_candidates(problem, optx.Newton(rtol=1e-10, atol=1e-10), 12)
        on_flanks = (values[:, 0] >= lo1 - 1e-9) & (values[:, 0] <= hi1 + 1e-9) & \
                    (values[:, 1] >= lo2 - 1e-9) & (values[:, 1] <= hi2 + 1e-9)
        return edge_reachable(problem), scan, converged & on_flanks, failed

    reach, scan, solved, failed = (np.asarray(a) for a in jax.jit(jax.vmap(one))(angles))
    truth = np.stack([scan[:, 0] & scan[:, 1], scan[:, 2] & scan[:, 3]], -1)
    np.testing.assert_array_equal(reach[:, 1:], truth)
    assert np.all(reach[:, 0])
    for edge in (0, 1):
        assert truth[:, edge].any() and not truth[:, edge].all()
    assert np.all(reach[solved])
    assert solved[:, 1].any() and solved[:, 2].any()
    # and `solve_candidates` counts no failed edge solve whose corner cannot reach
    assert not np.any(failed[:, 1:] & ~reach[:, 1:])


def test_a_position_of_a_result_is_the_result_at_that_angle_alone(seed_pair, seed_unmodified):
    """`TCAResult.position(i)`: the result at grid position `i` with a position axis of one,
    every field the TCA at that angle alone gives (the positions are solved independently),
    the result code recomputed from its own slices."""
    pairs = pair_window(seed_pair)
    i = 5
    one = seed_unmodified.position(i)
    alone = tca(seed_pair, FlankDepth(), ACC, pairs, seed_unmodified.pinion_angle[i:i + 1])
    for (path, a), b in zip(jax.tree_util.tree_leaves_with_path(one), jax.tree_util.tree_leaves(alone)):
        assert np.shape(a) == np.shape(b), path
        np.testing.assert_allclose(np.asarray(a, float), np.asarray(b, float), rtol=1e-12, atol=1e-15, err_msg=str(path))
    assert one.pinion_angle.shape == (1,) and one.slice_z.shape == seed_unmodified.slice_z.shape
