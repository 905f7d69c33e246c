"""Mesh-in impact: first contact under load, velocity, local stiffness, energy-method force."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gearjax as gj
from gearjax._solution import RESULTS
from gearjax.impact import ImpactRegime
from gearjax.impact.closed_form import edge_contact_closed_form
from gearjax.impact.stiffness import local_stiffness, point_local_stiffness
from gearjax.sweep import regime_transition

ACC = gj.Accuracy(positions_per_pitch=16, face_slices=9)
RPM = 5000.0
PAPER = jnp.array([5.9, 6.8, 3800.0, 4300.0, 6.2, 4600.0]) / 1000.0
# Zero amounts, same lengths: geometrically unmodified, same program as the modified pair.
PLAIN = PAPER.at[jnp.array([0, 1, 4])].set(0.0)


def scene(pair, y, torque_Nm, speed_rpm=RPM):
    return gj.Scene(
        pair,
        gj.FlankModification.from_vector(y),
        operating=gj.OperatingPoint(torque_Nm=torque_Nm, speed_rpm=speed_rpm),
        effects=("impact",),
        accuracy=ACC,
        pairs=(-2, -1, 0, 1, 2),
    )


def impact(pair, y, torque_Nm, speed_rpm=RPM):
    return gj.simulate(scene(pair, y, torque_Nm, speed_rpm)).impact


def test_zero_load_gives_zero_velocity_and_force(seed_pair):
    imp = impact(seed_pair, PLAIN, 0.0)
    assert bool(imp.result == RESULTS.successful)
    # tangential engagement of perfect flanks: zero up to the rounding of the loaded TE's
    # rate, a central difference at h ~ eps^(1/3) rad (~ eps^(2/3) of the angles' scale):
    # 1e-10 of the pitch-line speed (4e-6 mm/s)
    pitch_line_speed = RPM * 2 * math.pi / 60 * float(seed_pair.base_radius[1])
    assert abs(float(imp.velocity)) < 1e-10 * pitch_line_speed
    assert float(imp.force) < 1e-3


def test_unmodified_impact_is_edge_contact_growing_with_load(seed_pair):
    results = [impact(seed_pair, PLAIN, t) for t in (300.0, 800.0, 1600.0)]
    forces = [float(r.force) for r in results]
    assert all(bool(r.regime == ImpactRegime.edge) for r in results)
    assert forces[0] < forces[1] < forces[2]
    # the strike point moves up the pinion flank (from the root towards mid-flank), and
    # the first contact comes earlier
    rolls = [float(r.pinion_parameter) for r in results]
    assert rolls[0] < rolls[1] < rolls[2]
    assert rolls[0] > float(seed_pair.form_roll_length[0])
    angles = [float(r.pinion_angle) for r in results]
    assert angles[0] > angles[1] > angles[2]
    # the gear touches with its tip edge
    tip = float(seed_pair.tip_roll_length[1])
    assert all(abs(float(r.gear_parameter) - tip) < 1e-9 for r in results)


def test_force_grows_with_speed_as_the_energy_method_predicts(seed_pair):
    slow, fast = impact(seed_pair, PAPER, 1000.0, 2500.0), impact(seed_pair, PAPER, 1000.0, 5000.0)
    n = float(fast.stiffness.exponent)
    assert float(slow.stiffness.exponent) == pytest.approx(n, rel=1e-12)
    assert float(fast.velocity) == pytest.approx(2.0 * float(slow.velocity), rel=1e-9)
    assert float(fast.force) / float(slow.force) == pytest.approx(2.0 ** (2 * n / (n + 1)), rel=1e-9)


def test_energy_balance_and_power_law(seed_pair):
    imp = impact(seed_pair, PAPER, 1600.0)
    k, n = float(imp.stiffness.coefficient), float(imp.stiffness.exponent)
    delta = float(imp.approach)
    # strain energy by quadrature, t = delta u^2 smoothing the t^n singularity at 0
    x, w = np.polynomial.legendre.leggauss(60)
    u = 0.5 * (x + 1.0)
    strain = 0.5 * np.sum(w * k * (delta * u * u) ** n * 2.0 * delta * u)
    kinetic = 0.5 * float(imp.mass) * float(imp.velocity) ** 2
    assert strain == pytest.approx(kinetic, rel=1e-10)
    assert float(imp.kinetic_energy) == pytest.approx(strain, rel=1e-10)
    # seed 001's closed form F_s = ((n+1)/2 m v^2)^(n/(n+1)) K^(1/(n+1)) (the code goes
    # through delta_s instead)
    seed_form = ((n + 1) / 2 * float(imp.mass) * float(imp.velocity) ** 2) ** (n / (n + 1)) * k ** (1 / (n + 1))
    assert float(imp.force) == pytest.approx(seed_form, rel=1e-12)
    # the fitted law is the least-squares line through the computed curve in log-log
    forces, approaches = np.asarray(imp.stiffness.forces), np.asarray(imp.stiffness.approaches)
    slope, intercept = np.polyfit(np.log(approaches), np.log(forces), 1)
    assert n == pytest.approx(slope, rel=1e-10)
    assert k == pytest.approx(math.exp(intercept), rel=1e-9)
    # finite differences of the computed curve: its local exponents d ln F / d ln delta
    # vary as the contact spreads, and the least-squares n, a positively weighted mean of
    # them, lies within their range
    local = np.diff(np.log(forces)) / np.diff(np.log(approaches))
    assert local.min() < n < local.max()
    # the peak force agrees with the computed curve itself (not the fit), interpolated in
    # log-log at delta_s, to within the fit's reported error
    assert approaches[0] < delta < approaches[-1]
    on_curve = math.exp(np.interp(math.log(delta), np.log(approaches), np.log(forces)))
    assert abs(float(imp.force) / on_curve - 1) <= float(imp.stiffness.fit_error)
    assert float(imp.stiffness.fit_error) < 0.1


@pytest.mark.parametrize("linear", [0.0, 1e-6])
def test_local_stiffness_fit_against_a_closed_form_curve(linear):
    """One contact point with compliance c and Palmgren's contact approach a F^0.9: the
    force-approach curve is delta = c F + a F^0.9 in closed form; for c = 0 it is the power
    law F = a^(-1/0.9) delta^(1/0.9) itself, which the fit must return with no error."""
    a, e = 3.84e-5 / 42.0**0.8, 0.9
    fit = local_stiffness(jnp.array([[linear]]), jnp.array([a]), e, jnp.array([0.0]), jnp.array([True]),
                          jnp.asarray(2.0e4), gj.Accuracy())
    forces = np.asarray(fit.forces)
    lo, hi = gj.Accuracy().impact_fit_range
    assert forces == pytest.approx(2.0e4 * np.geomspace(lo, hi, forces.size), rel=1e-12)
    exact = linear * forces + a * forces**e
    assert np.asarray(fit.approaches) == pytest.approx(exact, rel=1e-7)
    slope, intercept = np.polyfit(np.log(exact), np.log(forces), 1)
    worst = np.max(np.abs(np.exp(intercept) * exact**slope / forces - 1))
    assert float(fit.exponent) == pytest.approx(slope, rel=1e-7)
    assert float(fit.coefficient) == pytest.approx(np.exp(intercept), rel=1e-6)
    if linear == 0.0:
        assert float(fit.exponent) == pytest.approx(1 / e, rel=1e-8)
        assert float(fit.coefficient) == pytest.approx(a ** (-1 / e), rel=1e-7)
        assert float(fit.fit_error) < 1e-8
    else:
        assert float(fit.fit_error) == pytest.approx(worst, rel=1e-4)
        # the linear term (as large as the Hertz term at the top load) bends the curve:
        # by 9e-4 over the default range's decade of forces
        assert float(fit.fit_error) > 5e-4


@pytest.mark.parametrize("linear", [0.0, 2e-6])
def test_point_local_stiffness_is_the_general_fit_of_one_point(linear):
    """A point contact's explicit curve delta = c F + h F^(2/3) against the LTCA's contact
    solver on one point with the same law; Hertz alone is F = h^(-3/2) delta^(3/2)."""
    h, acc = 1.2e-4, gj.Accuracy()
    point = point_local_stiffness(jnp.asarray(linear), jnp.asarray(h), jnp.asarray(2.0e3), acc)
    general = local_stiffness(jnp.array([[linear]]), jnp.array([h]), 2.0 / 3.0, jnp.array([0.0]), jnp.array([True]),
                              jnp.asarray(2.0e3), acc)
    assert point.result == RESULTS.successful and general.result == RESULTS.successful
    assert np.asarray(point.forces) == pytest.approx(np.asarray(general.forces), rel=1e-12)
    forces = np.asarray(point.forces)
    assert np.asarray(point.approaches) == pytest.approx(linear * forces + h * forces ** (2 / 3), rel=1e-12)
    # the solver's law is regularised at zero load: less h (f/2)^e, f = 1e-9 (1 + F) here
    shift = h * (0.5e-9 * (1.0 + forces)) ** (2 / 3)
    assert np.asarray(general.approaches) == pytest.approx(np.asarray(point.approaches) - shift, rel=1e-9)
    assert float(point.exponent) == pytest.approx(float(general.exponent), rel=1e-5)
    if linear == 0.0:
        assert float(point.exponent) == pytest.approx(1.5, rel=1e-10)
        assert float(point.coefficient) == pytest.approx(h**-1.5, rel=1e-9)
    else:
        # the teeth's linear compliance, a third of the approach at the top load, lowers n
        assert 1.0 < float(point.exponent) < 1.45


def _turn(point, center, angle):
    """`point` turned by `angle` (rad) about the z-parallel axis through `center`."""
    c, s = math.cos(angle), math.sin(angle)
    x, y = point[0] - center[0], point[1] - center[1]
    return np.array([center[0] + c * x - s * y, center[1] + s * x + c * y, point[2]])


def test_velocity_from_kinematics_equals_the_gap_closing_rate(seed_pair):
    omega1 = RPM * 2 * math.pi / 60
    center1, center2 = np.zeros(2), np.asarray(seed_pair.center(1))
    for y, t in ((PLAIN, 1000.0), (PAPER, 400.0)):
        imp = impact(seed_pair, y, t)
        assert float(imp.velocity) > 0.0
        assert float(imp.velocity) == pytest.approx(float(imp.gap_closing_velocity), rel=1e-6)
        # Second method: turn the material points at M with the gears (pinion about +z at
        # omega1, gear about -z at omega1 (z1/z2 + LTE')) and difference their positions.
        omega2 = omega1 * (29 / 71 + float(imp.lte_slope))
        x = np.asarray(imp.pinion_point)
        dt = 1e-5 / omega1  # 1e-5 rad of pinion turn
        v1 = (_turn(x, center1, omega1 * dt) - _turn(x, center1, -omega1 * dt)) / (2 * dt)
        v2 = (_turn(x, center2, -omega2 * dt) - _turn(x, center2, omega2 * dt)) / (2 * dt)
        v12 = v1 - v2
        assert np.max(np.abs(np.asarray(imp.relative_velocity) - v12)) < 1e-8 * np.linalg.norm(v12)
        normal = np.asarray(imp.normal)
        assert np.linalg.norm(normal) == pytest.approx(1.0, abs=1e-12)
        assert float(imp.velocity) == pytest.approx(float(v12 @ normal), rel=1e-6)


def test_equivalent_mass_reduces_to_the_seed_form_on_the_line_of_action(seed_pair):
    imp = impact(seed_pair, PLAIN, 1000.0)
    j1, j2 = (float(v) for v in imp.inertia)
    rb1, rb2 = (float(v) for v in seed_pair.base_radius)
    hub1, hub2 = 0.5 * float(seed_pair.root_radius[0]), 0.5 * float(seed_pair.root_radius[1])
    rho_b = 7.85e-9 * 42.0
    assert j1 == pytest.approx(math.pi * rho_b * (rb1**4 - hub1**4) / 2, rel=1e-12)
    assert j2 == pytest.approx(math.pi * rho_b * (rb2**4 - hub2**4) / 2, rel=1e-12)
    # An equivalent mass is the mass whose kinetic energy 1/2 m v^2 a perfectly plastic
    # impact at the closing speed v removes; any spin rates will do.
    w1, w2 = 1.0, 0.3

    def plastic_mass(after):
        """2 (E_0 - E_end) / v_0^2 for `after(P)` = (closing speed, kinetic energy) after an
        impulse P; the closing speed is linear in P, so two trials give the stopping P."""
        (v0, e0), (v1, _) = after(0.0), after(1.0)
        v_end, e_end = after(v0 / (v0 - v1))
        assert abs(v_end) < 1e-9 * abs(v0)
        return 2 * (e0 - e_end) / v0**2

    def seed_after(impulse):
        """Seed 001: the impulse acts tangent to both base circles."""
        s1, s2 = w1 - impulse * rb1 / j1, w2 + impulse * rb2 / j2
        return rb1 * s1 - rb2 * s2, 0.5 * j1 * s1**2 + 0.5 * j2 * s2**2

    assert float(imp.base_radius_mass) == pytest.approx(plastic_mass(seed_after), rel=1e-10)
    # Ours: the impulse acts along the normal at M; spins, velocities and torques from 3-D
    # cross products.
    x, n = np.asarray(imp.pinion_point), np.asarray(imp.normal)
    r2 = x - np.append(np.asarray(seed_pair.center(1)), 0.0)
    ez = np.array([0.0, 0.0, 1.0])

    def normal_after(impulse):
        """-P n on the pinion and +P n on the gear at M; the gear spins about -z."""
        s1 = w1 + np.cross(x, -impulse * n)[2] / j1
        s2 = -w2 + np.cross(r2, impulse * n)[2] / j2  # z-component of the gear's spin
        closing = (np.cross(s1 * ez, x) - np.cross(s2 * ez, r2)) @ n
        return closing, 0.5 * j1 * s1**2 + 0.5 * j2 * s2**2

    assert float(imp.mass) == pytest.approx(plastic_mass(normal_after), rel=1e-9)
    # Every normal of an involute helicoid is tangent to the base cylinder at the lead angle,
    # so on the unmodified pinion flank the pinion arm is r_b1 cos(beta_b) exactly (the gear's
    # tip edge strikes here, so the gear arm is not r_b2 cos(beta_b)).
    cb = math.cos(float(seed_pair.base_helix_angle))
    assert imp.regime_name == "edge"
    assert abs(float(imp.pinion_arm)) == pytest.approx(rb1 * cb, rel=1e-9)
    # Flank on flank (the modified pair at 400 N m) both arms are r_bi cos(beta_b) up to the
    # modification's tilt of the normal, so m_eq is the seed form / cos^2(beta_b) within 1 %.
    flank = impact(seed_pair, PAPER, 400.0)
    assert flank.regime_name == "surface"
    assert abs(float(flank.pinion_arm)) == pytest.approx(rb1 * cb, rel=5e-3)
    assert abs(float(flank.gear_arm)) == pytest.approx(rb2 * cb, rel=5e-3)
    assert float(flank.mass) == pytest.approx(float(flank.base_radius_mass) / cb**2, rel=1e-2)


def test_general_search_agrees_with_the_closed_form_edge_equation(seed_pair):
    """Seed 001's closed form at the lag found by the general search: same strike point."""
    for torque in (400.0, 1600.0):
        imp = impact(seed_pair, PLAIN, torque)
        lag = -float(imp.loaded_te)
        closed = edge_contact_closed_form(seed_pair, lag)
        assert bool(closed.converged) and float(closed.pinion_rotation) < 0.0
        assert float(closed.roll_length) == pytest.approx(float(imp.pinion_parameter), abs=1e-6)
        # pinion angle from the theoretical start A of the struck section
        k = int(imp.pair_index)
        z = float(imp.slice_z)
        rb1 = float(seed_pair.base_radius[0])
        start = (
            float(seed_pair.start_of_active_profile[0]) / rb1
            - math.tan(float(seed_pair.working_pressure_angle))
            + k * 2 * math.pi / 29
            - float(seed_pair.lead_rotation(0, z))
        )
        assert float(imp.pinion_angle) - start == pytest.approx(float(closed.pinion_rotation), abs=1e-8)


def test_regime_switches_from_surface_to_edge_continuously(seed_pair):
    assert impact(seed_pair, PAPER, 400.0).regime_name == "surface"
    assert impact(seed_pair, PAPER, 1600.0).regime_name == "edge"
    base = scene(seed_pair, PAPER, 400.0)
    below, above = regime_transition(base, low_Nm=400.0, high_Nm=1600.0, tolerance=1e-4)  # returns N·mm
    low, high = impact(seed_pair, PAPER, below / 1e3), impact(seed_pair, PAPER, above / 1e3)
    assert (low.regime_name, high.regime_name) == ("surface", "edge")
    # at the switch the flank contact has reached the gear's tip edge...
    tip = float(seed_pair.tip_roll_length[1])
    assert tip - float(low.gear_parameter) < 0.05
    # ...so the strike point and the force are continuous across it
    assert float(jnp.linalg.norm(low.pinion_point - high.pinion_point)) < 0.05
    assert float(high.force) == pytest.approx(float(low.force), rel=0.03)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(operating=gj.OperatingPoint(None, 500.0), effects=("impact",)), "impact' needs a torque"),
        (dict(operating=gj.OperatingPoint(1e6, 500.0), effects=("impact",), inertia=(-1.0, 2.0)), "inertia"),
        (dict(operating=gj.OperatingPoint(1e6, 500.0), effects=("impact",), inertia=(1.0, 2.0, 3.0)), "inertia"),
        (dict(operating=gj.OperatingPoint(1e6, 500.0), effects=("impact",), inertia=(float("nan"), 2.0)), "inertia"),
    ],
)
def test_bad_impact_input_is_rejected(seed_pair, kwargs, match):
    with pytest.raises(ValueError, match=match):
        gj.Scene(seed_pair, **kwargs)


@pytest.mark.parametrize("fit", [(0.0, 1.0), (1.0, 0.5), (0.1,)])
def test_bad_fit_range_is_rejected(fit):
    with pytest.raises(ValueError, match="impact_fit_range"):
        gj.Accuracy(impact_fit_range=fit)


#: The GA optimum of the seed 001 search before the continuous first contact: its gear tip
#: edge crosses the pinion's 0.5 mm, 24 um root relief, touching over ~1 mm of the face.
NARROW_EDGE = jnp.array([0.0243989, 0.0467365, 0.5, 0.5, 0.0244536, 19.0266364])


def test_first_contact_leaves_no_overlap_anywhere_on_the_face(seed_pair):
    """At the first contact found on 9 slices, the incoming pair's rigid offset on 401
    slices nowhere exceeds the loaded approach of the others (the searched maximum over the
    face is continuous); taking the best of the 9 slices left the edge 12 urad into the
    flank at 21 slices and found a later flank contact."""
    imp = impact(seed_pair, NARROW_EDGE, 1000.0)
    assert gj.enum_name(imp.result) == "successful"
    sc = gj.pipeline.prepare(scene(seed_pair, NARROW_EDGE, 1000.0))
    fine = eqx.filter_jit(gj.tooth_contact_analysis)(
        sc.pair, sc.depth, accuracy=ACC.replace(face_slices=401), pairs=sc.pairs,
        pinion_angles=jnp.asarray([imp.pinion_angle]))
    column = list(sc.pairs).index(int(imp.pair_index))
    offsets = jnp.where(fine.valid[0, column], fine.slice_te[0, column], -jnp.inf)
    assert float(jnp.max(offsets) - imp.loaded_te) <= 1e-9
    assert imp.regime == ImpactRegime.edge


def test_first_contact_search_is_a_root_in_a_few_newton_steps(seed_pair):
    """The safeguarded Newton search stops at a root of the gap H (|H| within the
    tolerance) after a few evaluations, at the angle a tight bisection of the same H on the
    same grid bracket finds, for a flank (surface) and a tip-edge first contact."""
    from gearjax.impact import search

    for y, torque, regime in ((PAPER, 400.0, "surface"), (PLAIN, 1000.0, "edge")):
        s = scene(seed_pair, y, torque)
        sim = gj.simulate(s)
        imp = sim.impact
        assert imp.regime_name == regime
        assert 2 <= int(imp.search_steps) <= 6
        pair = s.pair.resolve()
        ctx = search.SearchContext(pair, s.depth, jnp.asarray(s.operating.torque), s.contact_model, s.pairs)
        found, column, lower, upper, _, _ = search.bracket(sim.tca, sim.ltca)
        assert bool(found) and int(jnp.asarray(s.pairs)[column]) == int(imp.pair_index)

        @jax.jit
        def offsets(phi1, column=column, ctx=ctx):
            contact, _ = search.evaluate(ctx, column, phi1)
            return jnp.stack([contact.te, contact.lte])

        def gap(phi1):
            te, lte = offsets(phi1)
            return te - lte

        root = float(imp.pinion_angle)
        assert float(lower) < root < float(upper)
        assert abs(float(gap(jnp.asarray(root)))) <= ACC.newton_atol
        # the rates at the root: the touching offset's from the envelope theorem and the
        # loaded TE's from a central difference at a smaller step, against wider differences
        # (Richardson's extrapolation of steps d and d/2: a plain difference at d = 1e-5
        # carries a truncation error of 1.2e-5 of the loaded TE's rate)
        def central(d):
            return (np.asarray(offsets(jnp.asarray(root + d))) - np.asarray(offsets(jnp.asarray(root - d)))) / (2 * d)

        d = 1e-5
        rates = (4.0 * central(d / 2) - central(d)) / 3.0
        assert rates == pytest.approx([float(imp.te_slope), float(imp.lte_slope)], rel=1e-5)
        assert float(gap(lower)) < 0.0 <= float(gap(upper))
        lo, hi = float(lower), float(upper)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if float(gap(jnp.asarray(mid))) < 0.0 else (lo, mid)
        assert root == pytest.approx(hi, abs=1e-10)


def test_first_contact_tangents_follow_the_root(seed_pair):
    """The search's custom JVP (implicit function theorem; the rates' own change along the
    angle included) against
    central differences of searches re-run at nearby torques, on a flank and a tip-edge
    first contact: the root, the loaded TE there and both rates."""
    from gearjax.impact import search as fc

    pair = seed_pair.resolve()
    model = scene(seed_pair, PAPER, 400.0).contact_model

    def search(torque_Nmm, depth, bracket):
        ctx = fc.SearchContext(pair, depth, torque_Nmm, model, (-2, -1, 0, 1, 2))
        r = fc.first_contact(ctx, *bracket[1:], bracket[0])
        return jnp.stack([r.pinion_angle, r.contact.lte, r.contact.te_slope, r.contact.lte_slope])

    # one program: the differences use the primal output of the JVP program
    tangent = jax.jit(lambda t, depth, bracket: jax.jvp(lambda t: search(t, depth, bracket), (t,), (jnp.ones_like(t),)))
    for y, torque in ((PAPER, 400.0), (PLAIN, 1000.0)):
        s = scene(seed_pair, y, torque)
        sim = gj.simulate(s)
        bracket = fc.bracket(sim.tca, sim.ltca)
        t = jnp.asarray(s.operating.torque)
        values, tangents = tangent(t, s.depth, bracket)
        # the custom JVP's primal is the search that `simulate` ran; the loaded TE's rate is
        # a central difference at h (`rate_step`, 1.3e-6 rad), and the two programs round
        # the loaded TE, computed from angles of the order of the angular pitch p, apart by
        # up to about eps p at each end: the rates may differ by 2 eps p / (2 h)
        ran = [sim.impact.pinion_angle, sim.impact.loaded_te, sim.impact.te_slope, sim.impact.lte_slope]
        ran = np.array([float(x) for x in ran])
        assert np.asarray(values)[:3] == pytest.approx(ran[:3], rel=1e-10)
        rounding = float(np.finfo(np.float64).eps) * float(pair.angular_pitch(0)) / fc.rate_step(pair, jnp.float64)
        assert float(values[3]) == pytest.approx(ran[3], abs=rounding)
        # truncation error ~1e-5 relative at h = 1e-3 T, ~1e-7 at 1e-4 T (the root is
        # converged far below that); the loaded TE's rate carries its rounding (~1e-7 of
        # itself) divided by the step (2e-4), so its difference is checked to 1e-2
        h = 1e-4 * t
        fd = (np.asarray(tangent(t + h, s.depth, bracket)[0]) - np.asarray(tangent(t - h, s.depth, bracket)[0])) / (2 * float(h))
        assert np.all(np.abs(fd) > 0.0)
        assert np.asarray(tangents)[:3] == pytest.approx(fd[:3], rel=1e-6)
        assert float(tangents[3]) == pytest.approx(fd[3], rel=1e-2)


@pytest.mark.slow
def test_notebook_05_runs_in_this_process_with_its_programs(seed_pair):
    """Notebook 05 (impact of the seed pair against load and speed, the regime map) runs
    here rather than in a kernel (`_notebooks.py`): its scenes are this file's (`scene`),
    so its `simulate` program is the one this file has compiled."""
    from _notebooks import execute_in_process

    ns = execute_in_process("05_mesh_in_impact.ipynb")
    assert ns["acc"] == ACC
    np.testing.assert_array_equal(np.asarray(ns["paper"]), np.asarray(PAPER))
    assert [r.regime_name for r in ns["std"]] == [impact(seed_pair, PLAIN, t).regime_name for t in ns["loads"]]
    assert float(ns["mod"][-1].force) == pytest.approx(float(impact(seed_pair, PAPER, 1600.0).force), rel=1e-12)


def test_seed001_reproduction_sets_gearjax_beside_table4(seed_pair):
    """`gearjax.papers.seed001.reproduce` (`gearjax reproduce seed001`): the seed's Table 4
    beside gearjax's forces, at this module's accuracy (its program is this module's)."""
    from gearjax.papers.seed001 import TABLE4_IMPACT_FORCE, reproduce, summary

    out = reproduce(ACC, trajectory_loads_Nm=(1000.0,), transition=False)
    assert [row["torque_Nm"] for row in out["table4"]] == list(TABLE4_IMPACT_FORCE)
    direct = impact(seed_pair, PAPER, 1000.0)
    row = out["table4"][1]
    assert row["modified"]["force_N"] == pytest.approx(float(direct.force), rel=1e-12)
    assert row["modified"]["regime"] == direct.regime_name
    # the unmodified pair strikes with the tip edge at every load, its force growing with it
    standard = [r["standard"] for r in out["table4"]]
    assert all(r["regime"] == "edge" and r["converged"] for r in standard)
    assert standard[0]["force_N"] < standard[1]["force_N"] < standard[2]["force_N"]
    assert out["trajectory"]["modified"][0]["force_N"] == pytest.approx(row["modified"]["force_N"], rel=1e-12)
    speed = out["speed"]
    assert speed["force_ratio_5000_over_2500"] == pytest.approx(speed["predicted_2_pow_2n_over_n_plus_1"], rel=1e-9)
    assert out["check"] is None and out["transition_torque_Nm"] is None
    text = summary(out)
    assert "not checked against a finer setting" in text and "261.0 mm" in text
    assert f"{standard[1]['force_N']:7.0f} N" in text


def test_both_branches_of_the_regime_switch_and_their_tangents(seed_pair):
    """`impact_branches` on both sides of the switch of the paper's design (near 521 N·m at
    this accuracy; both branches step between 522.0 and 522.4 N·m, where the local
    stiffness fit's coefficient steps by 0.3 %, and past 524 N·m, where the loaded pairs'
    rate does: the points stay clear of both): the switching function's sign is the regime `simulate` finds, the branch
    that strikes gives its force, both branches exist on both sides, and the tangents of
    F_flank, F_edge and s along one direction (torque and the pinion's root relief
    together: implicit derivatives of each branch's search) match central differences."""
    from gearjax import pipeline
    from gearjax.optimize.space import modification_from_design

    base = pipeline.prepare(scene(seed_pair, PAPER, 517.0))

    def branches(t):
        # t: N·m from 517 along the direction (1 N·m, 0.001 µm of root relief) per unit
        y = PAPER.at[0].add(1e-6 * t)
        s = eqx.tree_at(lambda s: (s.modification, s.operating.torque), base,
                        (modification_from_design(y), base.operating.torque + 1e3 * t))
        pair = s.pair.resolve()
        tca = pipeline.unloaded(s, pair)
        ltca = pipeline.loaded(s, pair, tca, s.operating.torque)
        both = pipeline.branches(s, pair, tca, ltca, s.operating.torque, s.operating.speed)
        codes = jnp.stack([both.flank.result._value, both.edge.result._value])
        return jnp.stack([both.flank.force, both.edge.force, both.switch]), codes

    tangent = jax.jit(lambda t: jax.jvp(branches, (t,), (jnp.ones_like(t),), has_aux=True))
    h = 0.05
    for t, regime in ((0.0, "surface"), (6.5, "edge")):
        t = jnp.asarray(t, float)
        values, d_values, codes = tangent(t)
        assert np.all(np.asarray(codes) == 0), "both branches' searches succeed"
        flank, edge, switch = (float(v) for v in values)
        y = PAPER.at[0].add(1e-6 * float(t))
        hit = impact(seed_pair, y, 517.0 + float(t))
        assert hit.regime_name == regime
        assert (switch >= 0.0) == (regime == "surface")
        assert float(hit.force) == pytest.approx(flank if switch >= 0.0 else edge, rel=1e-6)
        fd = (np.asarray(tangent(t + h)[0]) - np.asarray(tangent(t - h)[0])) / (2 * h)
        assert np.all(np.abs(fd) > 0.0)
        assert np.asarray(d_values) == pytest.approx(fd, rel=2e-3)
