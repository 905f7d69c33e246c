"""Bad input is rejected with a ValueError naming the parameter, before any computation."""

import math

import pytest

from gearjax import (
    Accuracy,
    FlankModification,
    InvoluteGearPair,
    Material,
    MeshErrors,
    OperatingPoint,
    Scene,
)

GOOD = dict(teeth=(29, 71), normal_module=5.0, pressure_angle_deg=20.0, helix_angle_deg=27.5, face_width=42.0)


def pair(**changes):
    return InvoluteGearPair(**{**GOOD, **changes})


@pytest.mark.parametrize(
    "changes, name",
    [
        (dict(teeth=(4, 71)), "teeth[0]"),
        (dict(teeth=(29, 3)), "teeth[1]"),
        (dict(teeth=(29.5, 71)), "teeth[0]"),
        (dict(teeth=(29,)), "teeth"),
        (dict(normal_module=0.0), "normal_module"),
        (dict(normal_module=-2.0), "normal_module"),
        (dict(normal_module=float("nan")), "normal_module"),
        (dict(helix_angle_deg=45.0), "helix_angle_deg"),
        (dict(helix_angle_deg=-5.0), "helix_angle_deg"),
        (dict(pressure_angle_deg=50.0), "pressure_angle_deg"),
        (dict(face_width=0.0), "face_width"),
        (dict(face_width=float("inf")), "face_width"),
        (dict(profile_shift=(float("nan"), 0.0)), "profile_shift"),
        (dict(hand="up"), "hand"),
        (dict(addendum_coefficient=0.1), "addendum_coefficient"),
    ],
)
def test_pair_parameter_ranges(changes, name):
    with pytest.raises(ValueError, match=re_escape(name)):
        pair(**changes)


def re_escape(text):
    import re

    return re.escape(text)


def test_undercut_is_rejected_with_the_shift_that_avoids_it():
    with pytest.raises(ValueError, match=r"profile_shift\[0\] gives an undercut pinion.*>= 0\.\d+"):
        InvoluteGearPair((9, 40), 4.0, 20.0, 0.0, 20.0)


def test_pointed_tip_is_rejected():
    with pytest.raises(ValueError, match="pointed pinion tip"):
        InvoluteGearPair((12, 40), 4.0, 20.0, 0.0, 20.0, profile_shift=(1.2, 0.0))


def test_contact_ratio_below_one_is_rejected():
    with pytest.raises(ValueError, match="contact ratio"):
        InvoluteGearPair((20, 30), 4.0, 20.0, 0.0, 20.0, addendum_coefficient=0.4,
                         dedendum_coefficient=0.8)


def test_inconsistent_centre_distance_says_what_would_be_consistent():
    with pytest.raises(ValueError, match=r"center_distance=261\.0000 mm is inconsistent.*a = 281\.8455 mm.*x1 \+ x2 = -2\.87"):
        pair(center_distance=261.0)


def test_consistent_centre_distance_is_accepted():
    p = pair(center_distance=281.8454867165856)
    assert float(p.center_distance) == pytest.approx(281.8454867, abs=1e-6)


def test_tip_interference_is_rejected():
    # a gear whose addendum (1.2 m) exceeds the depth of the rack that generated the
    # pinion's involute (1.25 - 0.38 (1 - sin 20 deg) = 1.0 m) reaches below that involute
    with pytest.raises(ValueError, match="tip interference"):
        InvoluteGearPair((25, 80), 4.0, 20.0, 0.0, 20.0,
                         addendum_coefficient=(1.0, 1.2), dedendum_coefficient=(1.25, 1.45))


def test_missing_tip_clearance_is_rejected():
    with pytest.raises(ValueError, match="tip clearance"):
        # large positive shifts without tip shortening: a - a0 < (x1 + x2) m_n
        InvoluteGearPair((30, 40), 4.0, 20.0, 0.0, 20.0, profile_shift=(1.0, 1.0))


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(root_relief=-0.001), "root_relief (y1)"),
        (dict(tip_relief=-1e-3), "tip_relief (y2)"),
        (dict(root_relief_length=0.0), "root_relief_length (y3)"),
        (dict(tip_relief_length=-1.0), "tip_relief_length (y4)"),
        (dict(crowning=float("nan")), "crowning (y5)"),
        (dict(unmodified_length=-1.0), "unmodified_length (y6)"),
    ],
)
def test_modification_ranges(kwargs, name):
    with pytest.raises(ValueError, match=re_escape(name)):
        FlankModification(**kwargs)


def test_relief_length_beyond_the_flank_is_rejected(seed_pair):
    # the seed pair's active flank is 23.79 mm of roll length
    with pytest.raises(ValueError, match=r"modification\.tip_relief_length \(y4\) must be in \(0, 23\.79"):
        Scene(seed_pair, FlankModification(tip_relief=0.01, tip_relief_length=30.0))


def test_unmodified_length_beyond_face_width_is_rejected(seed_pair):
    with pytest.raises(ValueError, match=r"unmodified_length \(y6\) must be in \[0, 42"):
        Scene(seed_pair, FlankModification(crowning=0.01, unmodified_length=50.0))


@pytest.mark.parametrize(
    "factory, name",
    [
        (lambda: OperatingPoint(torque=-5.0), "torque"),
        (lambda: OperatingPoint(torque_Nm=-1.0), "torque_Nm"),
        (lambda: OperatingPoint(torque_Nm=100.0, speed_rpm=float("nan")), "speed_rpm"),
        (lambda: Material(youngs_modulus=0.0), "youngs_modulus"),
        (lambda: Material(poisson_ratio=0.6), "poisson_ratio"),
        (lambda: MeshErrors(misalignment=float("inf")), "misalignment"),
        (lambda: Accuracy(face_slices=0), "face_slices"),
        (lambda: Accuracy(tca_method="guess"), "tca_method"),
        (lambda: Accuracy.preset("sloppy"), "accuracy preset"),
    ],
)
def test_other_inputs(factory, name):
    with pytest.raises(ValueError, match=re_escape(name)):
        factory()


def test_scene_effects_are_checked(seed_pair):
    with pytest.raises(ValueError, match="effects"):
        Scene(seed_pair, effects=("vibration",))
    with pytest.raises(ValueError, match="needs a torque"):
        Scene(seed_pair, effects=("impact",))


def test_float64_request_without_x64_is_explained(seed_pair, monkeypatch):
    import gearjax.pipeline

    scene = Scene(seed_pair)
    monkeypatch.setattr(gearjax.pipeline, "_x64_enabled", lambda: False)
    with pytest.raises(ValueError, match="jax_enable_x64"):
        gearjax.pipeline.prepare(scene)


def test_batched_inputs_are_checked_elementwise():
    with pytest.raises(ValueError, match="normal_module"):
        InvoluteGearPair((29, 71), [5.0, -1.0], 20.0, 27.5, 42.0)
    ok = InvoluteGearPair((29, 71), [5.0, 4.0], 20.0, [27.5, 20.0], 42.0)
    assert ok.normal_module.shape == (2,)
    assert math.isfinite(float(ok.center_distance[1]))
