"""The loaded contact of a double-circular-arc pair through the stage chain: a scene file
with a torque, run by `gearjax run --no-cache` and by `simulate` (one compiled program:
`simulate`'s, which the command compiles without its program cache), its slice layout
against its own point contacts, the scene's checks (`ToothSectionCompliance.min_face_slices`,
float64), and the loaded TE's derivatives (a second program: the forward derivative in Δα);
the impact is `test_point_impact`'s."""

from __future__ import annotations

import json

import numpy as np
import pytest

import gearjax as gj
from gearjax.cli import main
from gearjax.io.scene_file import SceneFileError, scene_from_dict
from gearjax.papers.double_arc import SEED_CASE, seed_scene_file

from _cases import run_scene_file

SCENE = seed_scene_file(torque_Nm=100.0)


def _pair():
    return gj.DoubleArcGearPair(SEED_CASE["teeth"], SEED_CASE["normal_module"], SEED_CASE["helix_angle_deg"],
                                SEED_CASE["face_width"], 0.0)


@pytest.fixture(scope="module")
def loaded(tmp_path_factory):
    return run_scene_file(SCENE, tmp_path_factory.mktemp("dca"))


def test_the_command_line_runs_a_loaded_scene(loaded):
    scene, result, out = loaded
    assert isinstance(scene.compliance, gj.ToothSectionCompliance) and scene.effects == frozenset({"ltca"})
    lt = out["ltca"]
    assert lt["compliance"] == "ToothSectionCompliance" and lt["converged"] and lt["result"] == "successful"
    assert lt["lte_peak_to_peak_um"] == pytest.approx(float(result.ltca.lte_peak_to_peak_line) * 1e3, rel=1e-9)
    major, minor = lt["contact_ellipse_semi_axes_mm"]
    assert major > minor > 0.0
    assert lt["max_pair_load_N"] == pytest.approx(float(np.max(result.ltca.point_contact.loads)), rel=1e-12)


def test_each_pair_loads_the_slice_nearest_its_contact(loaded):
    """The slice layout holds each pair's point load once, at the face slice nearest the
    contact's axial position, and the loads carry the torque."""
    scene, result, _ = loaded
    ltca, point = result.ltca, result.ltca.point_contact
    loads = np.asarray(ltca.loads)
    assert ((loads > 0).sum(axis=-1) <= 1).all()
    np.testing.assert_allclose(loads.sum(axis=-1), np.asarray(point.loads), rtol=0, atol=0)
    on = np.asarray(point.loads) > 0
    nearest = np.argmin(np.abs(np.asarray(point.axial_position)[..., None] - np.asarray(ltca.slice_z)), axis=-1)
    np.testing.assert_array_equal(np.argmax(loads, axis=-1)[on], nearest[on])
    pair = scene.pair
    gear_torque = float(scene.operating.torque) * pair.teeth[1] / pair.teeth[0]
    np.testing.assert_allclose(np.sum(np.asarray(point.arms * point.loads), axis=-1), gear_torque, rtol=1e-9)
    assert (np.asarray(ltca.pressure)[loads > 0] > 0).all() and (np.asarray(ltca.pressure)[loads == 0] == 0).all()


def test_the_rotation_rate_is_the_inverse_mesh_stiffness(loaded):
    """dΘ/dT1 by forward differentiation through the load sharing equals (z2/z1) over the
    pairs' summed stiffness Σ m_k² dF_k/dδ_k: two separate computations."""
    scene, result, _ = loaded
    ratio = scene.pair.teeth[1] / scene.pair.teeth[0]
    np.testing.assert_allclose(result.ltca.rotation_rate, ratio / result.ltca.point_contact.mesh_stiffness, rtol=1e-8)
    np.testing.assert_allclose(result.ltca.transmission_error, result.tca.transmission_error - result.ltca.rotation,
                               rtol=0, atol=1e-15)


def test_the_lte_derivatives_in_torque_and_axial_pitch_error_match_finite_differences(loaded):
    """dLTE/dT1 (the program's own forward derivative through the load sharing, minus
    `rotation_rate`) and dLTE/dΔα (`jax.jvp` through the TCA and the load sharing) against
    central differences of the fixture's program, at 100 N·m and Δα = 50 µm (off Δα = 0,
    where the TE, the largest of the pairs', has a kink); steps 0.1 % of the torque, 0.1 µm."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    scene, _, _ = loaded

    def lte(torque, error):
        s = eqx.tree_at(lambda s: (s.operating.torque, s.pair.axial_pitch_error), scene, (torque, error))
        return gj.simulate(s, throw=False).ltca  # outside a jit: the fixture's program (leaves)

    torque, error = jnp.asarray(scene.operating.torque), scene.pair.axial_pitch_error + 0.05  # not weak-typed
    h_torque, h_error = 1e-3 * torque, 1e-4
    d_torque = (lte(torque + h_torque, error).transmission_error
                - lte(torque - h_torque, error).transmission_error) / (2 * h_torque)
    d_error = (lte(torque, error + h_error).transmission_error
               - lte(torque, error - h_error).transmission_error) / (2 * h_error)
    here = lte(torque, error)
    assert gj.enum_name(here.result) == "successful" and np.all(np.asarray(here.converged))
    scale = np.max(np.abs(np.asarray(d_torque)))
    np.testing.assert_allclose(-np.asarray(here.rotation_rate), np.asarray(d_torque), rtol=0, atol=1e-5 * scale)
    _, tangent = eqx.filter_jit(
        lambda e: jax.jvp(lambda e: lte(torque, e).transmission_error, (e,), (jnp.ones_like(e),)))(error)
    scale = np.max(np.abs(np.asarray(d_error)))
    assert scale > 1e-4  # rad/mm: the error tilts the TE
    np.testing.assert_allclose(np.asarray(tangent), np.asarray(d_error), rtol=0, atol=1e-5 * scale)


def test_the_scene_refuses_coarse_slices_float32_and_line_compliance():
    pair = _pair()
    torque = gj.OperatingPoint(torque=1.0e5)
    with pytest.raises(ValueError, match=r"accuracy.face_slices must be at least 21 .*ToothSectionCompliance.*got 9"):
        gj.Scene(pair, operating=torque, accuracy="fast")
    rigid = gj.Scene(pair, accuracy="fast")
    assert rigid.effects == frozenset()  # the rigid TCA needs no more slices, a load sweep does
    with pytest.raises(ValueError, match=r"accuracy.face_slices must be at least 21"):
        gj.load_sweep(rigid, torques_Nm=[100.0])
    with pytest.raises(ValueError, match=r"accuracy.dtype must be 'float64' .*ToothSectionCompliance.*got 'float32'"):
        gj.Scene(pair, operating=torque, accuracy=gj.Accuracy.preset("default").replace(dtype="float32"))
    with pytest.raises(ValueError, match="models the teeth of AbstractInvolutePair only"):
        gj.Scene(pair, operating=torque, compliance=gj.SliceCompliance())
    with pytest.raises(ValueError, match="coupling_length"):
        gj.ToothSectionCompliance(coupling_length=0.0)
    import tomllib

    data = tomllib.loads(SCENE)
    assert scene_from_dict(data).compliance == gj.ToothSectionCompliance()
    assert scene_from_dict(dict(data, ltca={"coupling_length_mn": 2.0})).compliance.coupling_length == 2.0
    with pytest.raises((SceneFileError, ValueError), match=r"\[ltca\] hertz: applies to compliance = 'slice' only"):
        scene_from_dict(dict(data, ltca={"hertz": "linear"}))


@pytest.mark.parametrize("error_um", [50.0, -50.0])
def test_the_axial_pitch_errors_loaded_effect_is_the_rigid_one_at_light_load(loaded, error_um):
    """An axial pitch error Δα changes the loaded TE at 1 N·m as it changes the rigid TE,
    with the same sign: the pairs' lag at that load is an order smaller than the change; at
    100 N·m the load sharing makes the loaded TE's peak-to-peak smaller than the rigid one. Same program as the fixture's
    (Δα and the torque are array leaves; the pair window is the fixture's)."""
    scene, _, _ = loaded

    def run(error_mm, torque):
        pair = gj.DoubleArcGearPair(SEED_CASE["teeth"], SEED_CASE["normal_module"], SEED_CASE["helix_angle_deg"],
                                    SEED_CASE["face_width"], error_mm)
        result = gj.simulate(gj.Scene(pair, operating=gj.OperatingPoint(torque=torque), pairs=scene.pairs))
        radius = float(result.ltca.action_radius[1]) * 1e3  # µm per rad
        return (np.asarray(result.tca.transmission_error) * radius, np.asarray(result.ltca.transmission_error) * radius,
                np.asarray(result.ltca.rotation) * radius)

    te0, lte0, lag0 = run(0.0, 1.0e3)
    te, lte, lag = run(error_um * 1e-3, 1.0e3)
    rigid, loaded_change = te - te0, lte - lte0
    deflection = max(np.max(lag0), np.max(lag))
    assert np.ptp(rigid) > 1.0  # µm: the error matters for the rigid TE
    assert deflection < 0.1 * np.max(np.abs(rigid))
    assert np.sign(np.mean(loaded_change)) == np.sign(np.mean(rigid)) != 0
    te_heavy, lte_heavy, _ = run(error_um * 1e-3, 1.0e5)
    assert np.ptp(lte_heavy) < np.ptp(te_heavy)


def test_reproduce_dca_json(loaded, capsys):
    """`gearjax reproduce dca --json`: formula (27) and Tables 1–2 as the seed prints them,
    and our meshing stiffness beside the paper's row, with formula (7)'s forces scaling as
    the square root of the stiffness. At `--accuracy default` it reuses the module
    fixture's loaded program (the seed pair at 100 N·m, the same scene structure); the
    command's own default is the converged 64 × 41 grid, which the validation page checks."""
    assert main(["reproduce", "dca", "--json", "--no-cache", "--accuracy", "default"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "accuracy 'default' (32 positions per pitch, 21 face slices)" in out["mesh_stiffness_setting"]
    for v in out["formula_27_mm"].values():
        assert round(v["gearjax"], 2) == pytest.approx(v["paper"], abs=1e-9)
    for t in ("table1", "table2"):
        for paper, ours in zip(out["tables_paper_units"][t]["paper"], out["tables_paper_units"][t]["gearjax"]):
            assert ours == pytest.approx(paper, rel=3e-4)
    ours, paper = out["mesh_stiffness_N_per_mm"], out["paper_mesh_stiffness_N_per_mm"]
    assert paper == [1.8084e6, 7.685e5, 1.771e6, 7.1088e5]
    assert len(ours) == 4 and all(np.isfinite(ours)) and min(ours) > 0
    for t in ("table1", "table2"):
        with_ours, seed = out["tables_with_our_stiffness_paper_units"][t]["gearjax"], out["tables_paper_units"][t]["gearjax"]
        np.testing.assert_allclose(np.asarray(with_ours) / np.asarray(seed), np.sqrt(np.asarray(ours) / np.asarray(paper)),
                                   rtol=1e-12)


@pytest.mark.parametrize("argv, message", [
    (["reproduce", "dca", "--accuracy", "fine"], "--accuracy: accuracy preset must be one of"),
    (["reproduce", "dca", "--accuracy", "default@64"], "--accuracy: accuracy must be PRESET or PRESET@PxS"),
    (["reproduce", "curvilinear", "--accuracy", "default"], "--accuracy applies to `reproduce dca` and `reproduce seed001` only"),
    (["reproduce", "seed001", "--accuracy", "default@x"], "--accuracy: accuracy must be PRESET or PRESET@PxS"),
    (["reproduce", "seed001", "--check-slices", "-1"], "--check-slices: must be in [0, 10000]; got -1"),
    (["reproduce", "dca", "--check-slices", "41"], "--check-slices applies to `reproduce seed001` only"),
])
def test_reproduce_refuses_a_bad_accuracy_before_any_work(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_the_meshing_stiffness_is_the_meshs_at_each_hand_over(loaded):
    """`meshing_stiffness`: one hand-over of each kind per zone and cycle, at angles inside
    the cycle's pitch; K there lies within the range of the mesh stiffness seen along that
    zone's pairs' normals over the cycle (dT2/dΘ / m_k² of its loaded pairs), up to 5 % for the
    linear extrapolation over one grid step."""
    from gearjax.papers.double_arc import SEED_TORQUE, seed_pair
    from gearjax.papers.meshing_stiffness import STIFFNESS_COLUMNS, meshing_stiffness

    _, result, _ = loaded
    k = meshing_stiffness(seed_pair(), SEED_TORQUE)
    np.testing.assert_array_equal(k.events, [1, 1, 1, 1])
    angle = np.asarray(result.tca.pinion_angle)
    pitch = 2 * np.pi / 24
    assert (np.asarray(k.pinion_angle) >= angle[0] - 1e-12).all() and (np.asarray(k.pinion_angle) < angle[0] + pitch).all()
    point = result.ltca.point_contact
    seen = np.asarray(point.mesh_stiffness)[:, None] / np.asarray(point.arms) ** 2
    loaded_pairs = np.asarray(point.loads) > 0
    zone = np.asarray(result.tca.pair_zone)
    for value, (z, _) in zip(np.asarray(k.stiffness), STIFFNESS_COLUMNS):
        along = seen[loaded_pairs & (zone == z)[None, :]]
        assert along.min() * 0.95 <= value <= along.max() * 1.05
