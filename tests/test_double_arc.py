"""Double-circular-arc gears (GB/T 12759): axial meshing facts (27)-(28) and the impact force
formula (7) against seed 000/003's Tables 1 and 2 (gearjax.papers.double_arc), the rack, the
generated surfaces and the four-state impact model."""

import math

import jax.numpy as jnp
import pytest

from gearjax.geometry.double_arc import GBT12759Rack
from gearjax.impact.energy import impact_force as energy_impact_force
from gearjax.impact.energy import base_radius_equivalent_mass
from gearjax.papers.double_arc import SEED_TABLES, axial_meshing, formula7_impact_force, seed_tables


def test_formula_27_reproduces_the_seed_case():
    facts = axial_meshing(4.0, 15.0, 55.0)
    # the seed prints 48.55 / 41.85 / 6.70 / 6.45 mm
    assert round(float(facts.axial_pitch), 2) == 48.55
    assert round(float(facts.convex_to_concave), 2) == 41.85
    assert round(float(facts.concave_to_convex), 2) == 6.70
    assert round(float(facts.face_excess), 2) == 6.45
    assert bool(facts.condition_28)  # the case with three meshing points
    assert float(facts.axial_pitch) == pytest.approx(math.pi * 4.0 / math.sin(math.radians(15.0)), rel=1e-14)


def test_contact_height_of_the_rack():
    assert GBT12759Rack().contact_height == pytest.approx(0.545, abs=1e-4)


@pytest.mark.parametrize("table", ["table1", "table2"])
def test_formula_7_reproduces_tables_1_and_2_in_paper_units(table):
    out = seed_tables(paper_units=True)
    for paper, ours in zip(out[table]["paper"], out[table]["gearjax"]):
        assert float(f"{ours:.4g}") == pytest.approx(paper, rel=1e-3)  # four significant digits
        assert ours == pytest.approx(paper, rel=3e-4)


def test_consistent_units_are_sqrt_1000_smaller():
    paper = seed_tables(paper_units=True)
    si = seed_tables(paper_units=False)
    for table in ("table1", "table2"):
        for p, s in zip(paper[table]["gearjax"], si[table]["gearjax"]):
            assert p / s == pytest.approx(math.sqrt(1000.0), rel=1e-12)
    assert paper["inertia"] == pytest.approx(1000.0 * si["inertia"], rel=1e-14)  # kg mm^2 vs t mm^2


def test_tables_default_to_newtons():
    """Without `paper_units` the forces are in N: the seed's printed numbers over sqrt(1000)."""
    si = seed_tables()
    assert si["units"] == "N"
    for table in ("table1", "table2"):
        for paper, ours in zip(SEED_TABLES[table]["force"], si[table]["gearjax"]):
            assert ours == pytest.approx(paper / math.sqrt(1000.0), rel=3e-4)


def test_force_grows_as_the_square_root_of_stiffness_over_points():
    f1 = float(formula7_impact_force(50.0, 1e6, 3, [1e-3, 2e-3], [40.0, 60.0]))
    f2 = float(formula7_impact_force(50.0, 4e6, 3, [1e-3, 2e-3], [40.0, 60.0]))
    f3 = float(formula7_impact_force(50.0, 1e6, 12, [1e-3, 2e-3], [40.0, 60.0]))
    assert f2 == pytest.approx(2 * f1, rel=1e-12) and f3 == pytest.approx(f1 / 2, rel=1e-12)


def test_formula_7_is_the_energy_method_for_a_linear_contact():
    """With one meshing point and alpha = 0, formula (7) is the energy balance of a linear
    spring, 1/2 m v^2 = 1/2 F^2/K, i.e. `gearjax.impact.energy.impact_force` with n = 1."""
    inertia, radii = jnp.asarray([3e-3, 7e-3]), jnp.asarray([40.0, 65.0])
    ours = formula7_impact_force(50.0, 2e5, 1, inertia, radii, 0.0)
    force, _ = energy_impact_force(base_radius_equivalent_mass(inertia, radii), 50.0, 2e5, 1.0)
    assert float(ours) == pytest.approx(float(force), rel=1e-12)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: axial_meshing(0.0, 15.0, 55.0), "normal_module"),
        (lambda: axial_meshing(4.0, 0.0, 55.0), "helix_angle_deg"),
        (lambda: axial_meshing(4.0, 15.0, -1.0), "face_width"),
        (lambda: formula7_impact_force(-1.0, 1e6, 3, [1.0, 1.0], [1.0, 1.0]), "velocity"),
        (lambda: formula7_impact_force(1.0, 1e6, 0, [1.0, 1.0], [1.0, 1.0]), "meshing_points"),
        (lambda: formula7_impact_force(1.0, float("nan"), 3, [1.0, 1.0], [1.0, 1.0]), "stiffness"),
    ],
)
def test_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()


# ---------------------------------------------------------------- rack, surfaces, four states
import equinox as eqx
import jax
import numpy as np
import optimistix as optx

from gearjax.geometry.depth import FlankDepth
from gearjax.geometry.double_arc import DoubleArcGearPair
from gearjax.papers.four_state import SEED_VELOCITIES, four_state_impact
from gearjax.tca._slice import solve_slice
from gearjax.tca._slice_problem import make_problem

SEED_PAIR = DoubleArcGearPair((24, 24), 4.0, 15.0, 55.0)


def test_recalled_rack_values_satisfy_the_exact_relations():
    residuals = GBT12759Rack().relation_residuals()
    assert len(residuals) == 6
    for name, value in residuals.items():
        assert abs(value) < 1.5e-4, name
    # a wrong recalled value would show: rho_f = 1.42 breaks x_f and l_f by ~4e-3
    bad = GBT12759Rack(concave_radius=1.42).relation_residuals()
    assert abs(bad["x_f = rho_f sin(alpha) - h_k"]) > 3e-3


@pytest.mark.parametrize("zone", [0, 1])
def test_working_arcs_meet_at_the_contact_instant(zone):
    """Pinion and gear contact points of each zone coincide, with opposite normals, at the
    zone's contact instant (to the rounding of the recalled rack, 5e-5 m_n)."""
    pair = SEED_PAIR.contact_zones()[zone]
    a0 = pair.contact_instant()
    u1, u2 = pair.contact_guess(a0)
    x1 = pair.flank_point(0, u1, 0.0, a0)
    x2 = pair.flank_point(1, u2, 0.0, a0)  # z1 = z2: the gear turns by the same angle
    assert float(jnp.linalg.norm(x1 - x2)) < 1e-3
    n1 = pair.profile_normal(0, u1)
    n2 = pair.profile_normal(1, u2)
    # normals in the fixed frame: pinion turned by a0, gear by -a0 (its own sense)
    from gearjax._numerics import rotate2

    assert float(jnp.dot(rotate2(a0, n1), rotate2(-a0, n2))) == pytest.approx(-1.0, abs=1e-9)
    # the generated contact point: (R +- h_k, -/+ h_k cos(beta) cot(alpha)) in the generation
    # frame, i.e. r^2 = (R +- h_k)^2 + (h_k cos(beta) cot(alpha))^2
    r = float(jnp.linalg.norm(x1[:2]))
    hk = GBT12759Rack().contact_height * 4.0
    R = float(SEED_PAIR.pitch_radius[0])
    lateral = hk * math.cos(math.radians(15.0)) / math.tan(math.radians(24.0))
    expected = math.hypot(R + (hk if zone == 0 else -hk), lateral)
    assert r == pytest.approx(expected, abs=1e-3)


def test_zones_lie_q_TA_apart_along_the_face():
    """The concave zone's contact instant, turned into an axial shift by the lead, is
    formula (27)'s q_TA (or -q'_TA) to the accuracy of the transverse generation."""
    a0 = float(SEED_PAIR.contact_zones()[1].contact_instant())
    shift = -a0 * float(SEED_PAIR.pitch_radius[0]) / math.tan(math.radians(15.0))
    facts = axial_meshing(4.0, 15.0, 55.0)
    assert shift == pytest.approx(float(facts.convex_to_concave), abs=0.1)


@pytest.mark.parametrize("zone", [0, 1])
def test_a_zone_given_by_an_array_index_is_the_zone_given_by_its_int(zone):
    """`contact_zone` with an integer array (as `vmap` over the zones passes it) selects
    every zone-dependent quantity of the zone given by a Python int, exactly."""
    fixed, traced = SEED_PAIR.contact_zone(zone), SEED_PAIR.contact_zone(jnp.asarray(zone))
    for gear in (0, 1):
        for name in ("profile_limits", "parameter_domain"):
            assert jnp.array_equal(jnp.stack(getattr(fixed, name)(gear)), jnp.stack(getattr(traced, name)(gear))), name
        u = jnp.linspace(*fixed.profile_limits(gear), 7)
        assert jnp.all(jnp.isfinite(fixed.profile(gear, u)))
        assert jnp.array_equal(fixed.profile(gear, u), traced.profile(gear, u))
        assert jnp.array_equal(fixed.parameter_at_radius(gear, 50.0), traced.parameter_at_radius(gear, 50.0))
    assert jnp.array_equal(fixed.contact_instant(), traced.contact_instant())
    assert jnp.array_equal(jnp.stack(fixed.contact_guess(0.01)), jnp.stack(traced.contact_guess(0.01)))


def test_both_zones_in_one_analysis_are_each_zones_own():
    """Given the window, the TCA analyses both zones in one `vmap` over the zone index: the
    merged result of each zone analysed alone, to the solves' rounding."""
    from gearjax import Accuracy
    from gearjax.tca import pair_window, tooth_contact_analysis
    from gearjax.tca.result import merge_zones

    acc = Accuracy(positions_per_pitch=8, face_slices=5)
    window = pair_window(SEED_PAIR)
    together = eqx.filter_jit(tooth_contact_analysis)(SEED_PAIR, accuracy=acc, pairs=window)
    alone = merge_zones([eqx.filter_jit(tooth_contact_analysis)(z, accuracy=acc, pairs=window)
                         for z in SEED_PAIR.contact_zones()])
    assert np.array_equal(np.asarray(together.valid), np.asarray(alone.valid)) and np.asarray(alone.valid).any()
    assert np.array_equal(np.asarray(together.pair_zone), np.asarray(alone.pair_zone))
    np.testing.assert_allclose(together.transmission_error, alone.transmission_error, rtol=0, atol=1e-14)
    valid = np.asarray(alone.valid)
    for name in ("slice_te", "pinion_parameter", "gear_parameter"):
        np.testing.assert_allclose(np.asarray(getattr(together, name))[valid], np.asarray(getattr(alone, name))[valid],
                                   rtol=1e-11, atol=1e-13, err_msg=name)


def test_slice_contact_of_the_convex_zone():
    pair = SEED_PAIR.contact_zones()[0]
    solver = optx.Newton(rtol=1e-10, atol=1e-12)
    at = solve_slice(make_problem(pair, FlankDepth(), 0, 0.0, 0.0), solver, 40)
    assert bool(at.valid) and int(at.kind) == 0
    assert abs(float(at.offset)) < 2e-5  # interference of the recalled rack's rounding
    for angle in (-0.02, 0.02):
        off = solve_slice(make_problem(pair, FlankDepth(), 0, 0.0, angle), solver, 40)
        assert float(off.offset) < float(at.offset) - 1e-4  # the slice separates away from the instant


def test_four_states_reproduce_the_seed_velocities():
    # the seed's 200 rpm in the engine's rad/s
    result = four_state_impact(SEED_PAIR, 0.1, 200.0 * 2.0 * math.pi / 60.0)
    # 81.57 is reproduced to 5e-4 (h_jf = 0.19997 from the recalled delta_2, not 0.2)
    for ours, paper in zip(np.asarray(result.velocity), SEED_VELOCITIES):
        assert ours == pytest.approx(paper, rel=1e-3)
    # the seed's own unit on request
    rpm = four_state_impact(SEED_PAIR, 0.1, speed_rpm=200.0)
    assert np.asarray(rpm.velocity) == pytest.approx(np.asarray(result.velocity), rel=1e-14)
    # one batched function: a subset of states gives the same numbers
    sub = four_state_impact(SEED_PAIR, 0.1, speed_rpm=200.0, states=(3, 0))
    assert np.asarray(sub.velocity) == pytest.approx(np.asarray(result.velocity)[[3, 0]], rel=1e-12)
    # formula (26)'s cos(24 deg) is not the exact distance for state 3
    assert float(result.exact_radius[3]) > float(result.radius[3]) * 1.02


def test_four_states_gradient_matches_finite_differences():
    def total(delta):
        return jnp.sum(four_state_impact(SEED_PAIR, delta, speed_rpm=200.0).velocity * jnp.arange(1.0, 5.0))

    grad = float(jax.grad(total)(0.1))
    h = 1e-6
    fd = (float(total(0.1 + h)) - float(total(0.1 - h))) / (2 * h)
    assert grad == pytest.approx(fd, rel=1e-6)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(face_width=40.0), "face_width"),
        (dict(teeth=(8, 24)), "teeth"),
        (dict(helix_angle_deg=2.0), "helix_angle_deg"),
        (dict(axial_pitch_error=5.0), "axial_pitch_error"),
        (dict(normal_module=float("nan")), "normal_module"),
    ],
)
def test_bad_double_arc_input(kwargs, match):
    args = dict(teeth=(24, 24), normal_module=4.0, helix_angle_deg=15.0, face_width=55.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        DoubleArcGearPair(**args)
    with pytest.raises(ValueError, match="pitch_circle_error"):
        four_state_impact(SEED_PAIR, -0.1, 20.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(), "exactly one of speed"),
        (dict(speed=20.0, speed_rpm=200.0), "exactly one of speed"),
        (dict(speed=-1.0), "speed"),
        (dict(speed_rpm=0.0), "speed_rpm"),
    ],
)
def test_four_state_speed_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        four_state_impact(SEED_PAIR, 0.1, **kwargs)


def test_double_arc_scene_file_and_its_stages():
    from gearjax.scene import OperatingPoint, Scene
    from gearjax.io.scene_file import SceneFileError, scene_from_dict

    data = {"pair": {"family": "double_circular_arc", "teeth": [24, 24], "normal_module": 4.0,
                     "helix_angle_deg": 15.0, "face_width": 55.0, "axial_pitch_error_um": -50.0}}
    scene = scene_from_dict(data)
    assert isinstance(scene.pair, DoubleArcGearPair)
    assert float(scene.pair.axial_pitch_error) == pytest.approx(-0.05)
    assert scene.pairs == (-2, -1, 0, 1, 2, 3)  # union of the two zones' windows
    bad = {"pair": dict(data["pair"], pressure_angle_deg=20.0)}
    with pytest.raises((SceneFileError, ValueError), match="pressure_angle_deg"):
        scene_from_dict(bad)
    # the pair has both stages; a zone alone has neither (the loaded contact spans both zones)
    assert Scene(SEED_PAIR, operating=OperatingPoint(torque=100.0), effects=("impact",)).effects == {"ltca", "impact"}
    with pytest.raises(ValueError, match="not available for DoubleArcZone.*load the DoubleArcGearPair"):
        Scene(SEED_PAIR.contact_zones()[1], operating=OperatingPoint(torque=100.0), effects=("impact",))
