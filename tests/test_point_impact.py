"""The mesh-in impact of a double-circular-arc pair on its point-contact loaded model: a
scene file with a torque, a speed and `effects = ["impact"]`, run by `gearjax run
--no-cache` and by `simulate` (one compiled program, as in `test_point_ltca`), one first
contact per contact zone."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import gearjax as gj
from gearjax._solution import RESULTS
from gearjax.impact.search import SearchContext, evaluate
from gearjax.io.report import summary
from gearjax.papers.double_arc import SEED_CASE, seed_scene_file
from gearjax.pipeline import check_codes

from _cases import run_scene_file
from _notebooks import execute_in_process

SCENE = seed_scene_file(torque_Nm=100.0, speed_rpm=200.0, analysis={"effects": ["impact"]})


@pytest.fixture(scope="module")
def struck(tmp_path_factory):
    return run_scene_file(SCENE, tmp_path_factory.mktemp("dca_impact"))


def test_the_command_line_reports_each_zones_impact(struck):
    scene, result, out = struck
    zones = out["impact"]["zones"]
    assert [z["zone"] for z in zones] == list(scene.pair.zone_names) == ["convex driving tooth", "concave driving tooth"]
    imp = result.impact
    assert imp.force.shape == (2,)
    for z, entry in enumerate(zones):
        assert entry["result"] == "successful" and entry["converged"]
        assert entry["force_N"] == pytest.approx(float(imp.force[z]), rel=1e-12) and entry["force_N"] > 0.0
        assert entry["velocity_mm_per_s"] > 0.0
        # the point contact travels along the face: the incoming pair's enters at a face end
        assert abs(entry["face_position_mm"]) == pytest.approx(SEED_CASE["face_width"] / 2, abs=1e-9)
    text = summary(out)
    assert "Mesh-in impact, convex driving tooth" in text and "Mesh-in impact, concave driving tooth" in text


def test_each_zones_force_is_the_energy_balance_of_the_points_own_law(struck):
    """The energy method on the fitted power law F = K δ^n against the exact law it fits,
    δ = cF + hF^(2/3) (c, h recovered from two of the fit's points): ½ m v² equals
    c F²/2 + (2/5) h F^(5/3) at the peak force up to the fit's error; the exponent lies
    between the teeth's bending (1) and Hertz (3/2); and the normal velocity from the
    kinematics at the located point is the closing rate of the gap (the first contact is a
    face end here, a slice of the TCA: no interpolation between them)."""
    _, result, _ = struck
    imp = result.impact
    assert (imp.result == RESULTS.successful).all()
    for z in range(2):
        forces, approaches = np.asarray(imp.stiffness.forces[z]), np.asarray(imp.stiffness.approaches[z])
        (c, h), *_ = np.linalg.lstsq(np.stack([forces, forces ** (2 / 3)], axis=1), approaches, rcond=None)
        assert c > 0 and h > 0
        np.testing.assert_allclose(c * forces + h * forces ** (2 / 3), approaches, rtol=1e-10)
        energy = float(imp.kinetic_energy[z])
        lo, hi = 0.0, 1e6
        for _ in range(200):  # the work c F²/2 + (2/5) h F^(5/3) grows with F: bisection
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if c * mid**2 / 2 + 0.4 * h * mid ** (5 / 3) < energy else (lo, mid)
        assert float(imp.force[z]) == pytest.approx(lo, rel=float(imp.stiffness.fit_error[z]))
        assert 1.0 < float(imp.stiffness.exponent[z]) < 1.5
    np.testing.assert_allclose(np.asarray(imp.velocity), np.asarray(imp.gap_closing_velocity), rtol=1e-6)


@eqx.filter_jit
def _gap(ctx, column, phi1):
    """H at one pinion angle (rad): one program for every scene of the seed pair and column."""
    contact, _ = evaluate(ctx, column, phi1)
    return contact.gap


def _gaps(scene, imp):
    """Per zone, H of the zone's incoming pair as a function of the pinion angle."""
    ctx = SearchContext(scene.pair.resolve(), scene.depth, jnp.asarray(scene.operating.torque), scene.contact_model,
                        scene.pairs)
    columns = [z * len(scene.pairs) + scene.pairs.index(int(imp.pair_index[z])) for z in range(2)]
    return [lambda phi1, c=c: float(_gap(ctx, jnp.asarray(c), phi1)) for c in columns]


def test_each_zones_first_contact_is_the_root_of_its_gap(struck):
    """At the first contact the zone's incoming pair's located peak meets the loaded TE of the
    others (H = 0 to the search's tolerance), and a little earlier it is clear (H < 0)."""
    scene, result, _ = struck
    imp = result.impact
    for z, gap in enumerate(_gaps(scene, imp)):
        root = imp.pinion_angle[z]
        assert abs(gap(root)) < 1e-9  # rad
        assert gap(root - 2e-4) < 0.0


def test_a_gap_that_jumps_across_zero_is_reported_as_a_jump(struck):
    """At Δ_α = +0.373 mm (a pitch-circle error of 0.1 mm) the rigid TE tilts by about
    2 000 µrad per pitch and drops by about 690 µrad at the convex tooth's hand-over
    (notebook 02): that zone's gap H jumps across zero, with no root. The search
    stops there with `first_contact_jump`, once its bracket has halved from the grid step to
    the tolerance (so within `impact_max_steps`); H on either side of the located angle is
    far from zero, of opposite signs."""
    scene, _, _ = struck
    # the fixture's program: Δ_α is a leaf (kept strongly typed)
    tilted = eqx.tree_at(lambda s: s.pair.axial_pitch_error, scene, scene.pair.axial_pitch_error + 0.3732)
    imp = gj.simulate(tilted, throw=False).impact
    jumped = np.asarray(imp.result == RESULTS.first_contact_jump)
    assert jumped[0]
    # found by the bracket's halving: at most its bits above atol, the first point and both ends more
    _, atol = scene.accuracy.newton_tolerances(np.float64)
    grid_step = 2.0 * np.pi / scene.pair.teeth[0] / scene.accuracy.positions_per_pitch
    bisections = int(np.ceil(np.log2(grid_step / atol)))
    assert (np.asarray(imp.search_steps)[jumped] <= bisections + 3).all(), (imp.search_steps, bisections)
    assert bisections + 3 < scene.accuracy.impact_max_steps
    for z, gap in enumerate(_gaps(tilted, imp)):
        if jumped[z]:
            root = imp.pinion_angle[z]
            assert gap(root - 1e-8) < -1e-6 and gap(root + 1e-8) > 1e-6  # rad
    with pytest.raises(gj.SimulationError, match="first_contact_jump"):
        check_codes({"impact": imp.result})


def test_notebook_02_runs(struck):
    """Notebook 02 top to bottom on its coarse grid (its cells assert what they show); its
    loaded section builds in Python the scene this file reads from a scene file, and gets
    the same strikes at 100 N·m and Δα = 0."""
    _, result, _ = struck
    namespace = execute_in_process("02_double_circular_arc.ipynb")
    np.testing.assert_allclose(namespace["values"][0.0, 100.0][2:], np.asarray(result.impact.force), rtol=1e-12)


def test_impact_studies_that_keep_one_impact_refuse_a_pair_of_two_zones():
    """The sweeps, the regime transition and the optimiser keep one impact per design, load
    and speed: they refuse a pair whose zones strike each on their own, before any work."""
    import tomllib

    from gearjax.io.scene_file import scene_from_dict
    from gearjax.optimize import Objective
    from gearjax.sweep.run import run_impact_sweep

    scene = scene_from_dict(tomllib.loads(SCENE))
    match = "needs a pair of one contact zone; DoubleArcGearPair has 2"
    with pytest.raises(ValueError, match=match):
        gj.impact_sweep(scene, torques_Nm=[100.0], speeds_rpm=[200.0])
    with pytest.raises(ValueError, match=match):
        run_impact_sweep(scene, [100.0], [200.0])
    with pytest.raises(ValueError, match=match):
        gj.design_sweep([scene], torques_Nm=[100.0], speeds_rpm=[200.0])
    with pytest.raises(ValueError, match=match):
        gj.regime_transition(scene, low_Nm=10.0, high_Nm=200.0)
    with pytest.raises(ValueError, match=match):
        Objective.create(scene)
