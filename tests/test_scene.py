"""Scene composition: only the requested stages are compiled; precision option; no retrace."""

import dataclasses

import jax
import numpy as np
import pytest

import gearjax.pipeline
from gearjax import (
    Accuracy,
    FlankModification,
    InvoluteGearPair,
    MeshErrors,
    OperatingPoint,
    Scene,
    simulate,
)
from gearjax.papers.seed001 import paper_optimum
from gearjax.pipeline import program_text
from gearjax.scene import stack_scenes

TINY = Accuracy(positions_per_pitch=4, face_slices=3)


@pytest.mark.parametrize("effects", [(), ("ltca",), ("impact",)], ids=["rigid", "loaded", "impact"])
def test_unmodified_scene_compiles_no_modification_or_error_term(seed_pair, effects):
    """Rigid, loaded and impact scenes: the program of the bare pair has no relief or error
    term (in none of its stages: TCA, LTCA, first-contact search), the modified pair's
    program has both."""
    operating = OperatingPoint(torque=1.0e6, speed=500.0) if effects else OperatingPoint()
    bare = program_text(Scene(seed_pair, operating=operating, effects=effects, accuracy=TINY))
    assert "stage_tca" in bare and ("stage_ltca" in bare) == bool(effects) and ("stage_impact" in bare) == ("impact" in effects)
    assert "term_modification" not in bare and "term_errors" not in bare
    full = program_text(Scene(seed_pair, paper_optimum(), errors=MeshErrors(pitch_deviation=0.001), operating=operating,
                              effects=effects, accuracy=TINY))
    assert "term_modification" in full and "term_errors" in full


def test_rigid_scene_has_no_loaded_stages(seed_pair):
    text = program_text(Scene(seed_pair, accuracy=TINY))
    assert "stage_ltca" not in text and "stage_impact" not in text


def test_loaded_scene_builds_the_ltca_stage(seed_pair):
    scene = Scene(seed_pair, operating=OperatingPoint(torque=1.0e5), accuracy=TINY)
    assert scene.effects == frozenset({"ltca"})
    text = program_text(scene)
    assert "stage_tca" in text and "stage_ltca" in text


def test_simulate_does_not_retrace_for_new_values(seed_pair, monkeypatch):
    calls = []
    original = gearjax.pipeline.tooth_contact_analysis

    def counting(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    jax.clear_caches()
    monkeypatch.setattr(gearjax.pipeline, "tooth_contact_analysis", counting)
    for amount in (0.004, 0.009):
        scene = Scene(seed_pair, FlankModification(tip_relief=amount, tip_relief_length=4.0), accuracy=TINY)
        simulate(scene).tca.transmission_error.block_until_ready()
    assert len(calls) == 1


def test_float32_option_agrees_with_float64(seed_pair):
    mod = FlankModification(root_relief=0.02, tip_relief=0.02, root_relief_length=8.0,
                            tip_relief_length=8.0, crowning=0.015, unmodified_length=2.0)
    acc = Accuracy(positions_per_pitch=8, face_slices=7)
    r64 = simulate(Scene(seed_pair, mod, accuracy=acc)).tca
    r32 = simulate(Scene(seed_pair, mod, accuracy=acc.replace(dtype="float32", newton_rtol=1e-5, newton_atol=1e-5))).tca
    assert r32.transmission_error.dtype == np.float32
    te64 = np.asarray(r64.transmission_error) * float(seed_pair.base_radius[1]) * 1e3
    te32 = np.asarray(r32.transmission_error, dtype=float) * float(seed_pair.base_radius[1]) * 1e3
    assert np.ptp(te64) > 1.0  # a TE of several um is resolved...
    np.testing.assert_allclose(te32, te64, atol=0.05)  # ...to 0.05 um in float32


def test_scene_window_covers_all_pairs_in_contact(spur_pair):
    scene = Scene(spur_pair, accuracy=Accuracy(positions_per_pitch=8, face_slices=3))
    tca = simulate(scene).tca
    in_contact = np.asarray(tca.in_contact(1e-9)).any(-1)
    # the outermost pairs of the window are margin for edge contacts: never in flank contact
    assert not in_contact[:, 0].any() and not in_contact[:, -1].any()
    assert in_contact.any(0).sum() >= 2


def test_stacked_designs_run_batched_and_match_single_runs():
    scenes = [
        Scene(InvoluteGearPair((29, 71), 5.0, 20.0, helix, 42.0), FlankModification(tip_relief=0.01, tip_relief_length=t), accuracy=TINY)
        for helix, t in ((27.5, 4.0), (20.0, 6.0), (12.0, 3.0))
    ]
    batch = stack_scenes(scenes)
    out = jax.vmap(lambda s: simulate(s).tca.transmission_error)(batch)
    assert out.shape == (3, TINY.positions_per_pitch)
    single = [np.asarray(simulate(dataclasses.replace(s, pairs=batch.pairs)).tca.transmission_error) for s in scenes]
    np.testing.assert_allclose(np.asarray(out), np.stack(single), rtol=1e-9, atol=1e-14)


def test_stacking_refuses_mixed_structures(seed_pair):
    with pytest.raises(ValueError, match="share one structure"):
        stack_scenes([Scene(seed_pair, accuracy=TINY), Scene(seed_pair, paper_optimum(), accuracy=TINY)])


def test_an_accuracy_spec_names_a_preset_and_its_grid():
    fine = Accuracy.from_spec("default@64x41")
    assert (fine.positions_per_pitch, fine.face_slices) == (64, 41)
    assert fine.replace(positions_per_pitch=32, face_slices=21) == Accuracy.from_spec("default")
    check = Accuracy.from_spec("reference@128x161", finer=True)
    assert check == Accuracy.preset("reference").finer(161, 128) and check.contact_max_steps == 320
    for bad in ("default@", "default@64", "default@64x", "default@ax41", "default@\u00b2x41"):
        with pytest.raises(ValueError, match="PRESET@PxS"):
            Accuracy.from_spec(bad)
    with pytest.raises(ValueError, match="accuracy preset"):
        Accuracy.from_spec("medium@64x41")
