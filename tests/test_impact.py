"""Mesh-in impact: first contact under load, velocity, local stiffness, energy-method force."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gearjax as gj
from gearjax._solution import RESULTS, enum_name
from gearjax.impact import ImpactRegime
from gearjax.impact.closed_form import edge_contact_closed_form
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
        operating=gj.OperatingPoint.from_nm_rpm(torque_Nm, speed_rpm),
        effects=("impact",),
        accuracy=ACC,
        pairs=(-2, -1, 0, 1, 2),
    )


def impact(pair, y, torque_Nm, speed_rpm=RPM):
    return gj.simulate(scene(pair, y, torque_Nm, speed_rpm)).impact


def test_zero_load_gives_zero_velocity_and_force(seed_pair):
    imp = impact(seed_pair, PLAIN, 0.0)
    assert bool(imp.result == RESULTS.successful)
    assert abs(float(imp.velocity)) < 1e-6  # mm/s: tangential engagement of perfect flanks
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
    assert float(imp.kinetic_energy) == pytest.approx(kinetic, rel=1e-12)
    assert float(imp.force) == pytest.approx(k * delta**n, rel=1e-12)
    # the fitted law is the least-squares line through the computed curve in log-log, and
    # follows it to the reported error
    forces, approaches = np.asarray(imp.stiffness.forces), np.asarray(imp.stiffness.approaches)
    slope, intercept = np.polyfit(np.log(approaches), np.log(forces), 1)
    assert n == pytest.approx(slope, rel=1e-10)
    assert k == pytest.approx(math.exp(intercept), rel=1e-9)
    assert float(imp.stiffness.fit_error) == pytest.approx(np.max(np.abs(k * approaches**n / forces - 1)), rel=1e-9)
    assert float(imp.stiffness.fit_error) < 0.1


def test_velocity_from_kinematics_equals_the_gap_closing_rate(seed_pair):
    for y, t in ((PLAIN, 1000.0), (PAPER, 400.0)):
        imp = impact(seed_pair, y, t)
        assert float(imp.velocity) > 0.0
        assert float(imp.velocity) == pytest.approx(float(imp.gap_closing_velocity), rel=1e-6)
        # the normal is a unit vector and v_n is its projection
        assert float(jnp.linalg.norm(imp.normal)) == pytest.approx(1.0, abs=1e-12)
        assert float(jnp.dot(imp.relative_velocity, imp.normal)) == pytest.approx(float(imp.velocity), rel=1e-12)


def test_equivalent_mass_reduces_to_the_seed_form_on_the_line_of_action(seed_pair):
    imp = impact(seed_pair, PLAIN, 1000.0)
    j1, j2 = (float(v) for v in imp.inertia)
    rb1, rb2 = (float(v) for v in seed_pair.base_radius)
    hub1, hub2 = 0.5 * float(seed_pair.root_radius[0]), 0.5 * float(seed_pair.root_radius[1])
    rho_b = 7.85e-9 * 42.0
    assert j1 == pytest.approx(math.pi * rho_b * (rb1**4 - hub1**4) / 2, rel=1e-12)
    assert j2 == pytest.approx(math.pi * rho_b * (rb2**4 - hub2**4) / 2, rel=1e-12)
    assert float(imp.seed_mass) == pytest.approx(j1 * j2 / (j1 * rb2**2 + j2 * rb1**2), rel=1e-12)
    # our arms are the normal's moment arms; on the line of action they would be
    # r_bi cos(beta_b), which makes m_eq = seed form / cos^2(beta_b)
    cb = float(jnp.cos(seed_pair.base_helix_angle))
    m_line = 1.0 / ((rb1 * cb) ** 2 / j1 + (rb2 * cb) ** 2 / j2)
    assert m_line == pytest.approx(float(imp.seed_mass) / cb**2, rel=1e-12)
    assert float(imp.mass) == pytest.approx(1.0 / (float(imp.pinion_arm) ** 2 / j1 + float(imp.gear_arm) ** 2 / j2), rel=1e-12)


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
    below, above = regime_transition(base, 4.0e5, 1.6e6, tolerance=1e-4)
    low, high = impact(seed_pair, PAPER, below / 1e3), impact(seed_pair, PAPER, above / 1e3)
    assert (low.regime_name, high.regime_name) == ("surface", "edge")
    # at the switch the flank contact has reached the gear's tip edge...
    tip = float(seed_pair.tip_roll_length[1])
    assert tip - float(low.gear_parameter) < 0.05
    # ...so the strike point and the force are continuous across it
    assert float(jnp.linalg.norm(low.pinion_point - high.pinion_point)) < 0.05
    assert float(high.force) == pytest.approx(float(low.force), rel=0.03)


def test_grad_and_vmap_on_both_sides_of_the_switch(seed_pair):
    """value_and_grad of the force, vmapped over torques with surface (400 N m) and edge
    (1600 N m) contact, against single runs and central differences; the batched regime
    and contact kind are enumerations that name the two sides."""

    def force_and_codes(y, torque, speed):
        s = gj.Scene(
            seed_pair,
            gj.FlankModification.from_vector(y),
            operating=gj.OperatingPoint(torque, speed),
            effects=("impact",),
            accuracy=ACC,
            pairs=(-2, -1, 0, 1, 2),
        )
        imp = gj.simulate(s).impact
        return imp.force, (imp.regime, imp.kind, imp.result)

    def force(y, torque, speed):
        return force_and_codes(y, torque, speed)[0]

    speed = RPM * 2 * math.pi / 60
    torques = jnp.array([4.0e5, 1.6e6])
    grad_fn = jax.value_and_grad(force_and_codes, argnums=(0, 1, 2), has_aux=True)
    (values, (regime, kind, result)), grads = eqx.filter_jit(jax.vmap(grad_fn, (None, 0, None)))(
        PAPER, torques, jnp.asarray(speed)
    )
    np.testing.assert_array_equal(np.asarray(regime == ImpactRegime.edge), [False, True])
    assert enum_name(regime).tolist() == ["surface", "edge"]
    assert enum_name(kind).tolist() == ["flank", "gear_tip_edge"]
    assert enum_name(result).tolist() == ["successful", "successful"]
    primal = eqx.filter_jit(force)
    for i, torque in enumerate(torques):
        assert float(values[i]) == pytest.approx(float(primal(PAPER, torque, jnp.asarray(speed))), rel=1e-9)
        checks = [(grads[1][i], lambda h: primal(PAPER, torque + h, jnp.asarray(speed)), 1e-4 * torque),
                  (grads[2][i], lambda h: primal(PAPER, torque, jnp.asarray(speed) + h), 1e-4 * speed)]
        for j in range(6):
            e = jnp.zeros(6).at[j].set(1.0)
            checks.append((grads[0][i, j], lambda h, e=e: primal(PAPER + h * e, torque, jnp.asarray(speed)), 1e-4 * PAPER[j]))
        for ad, f, h in checks:
            fd = (float(f(h)) - float(f(-h))) / (2 * float(h))
            assert np.isfinite(float(ad))
            assert float(ad) == pytest.approx(fd, rel=1e-2, abs=1e-3 * abs(float(values[i])) / float(h) * 1e-4)


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
