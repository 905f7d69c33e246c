"""Batched load sweep and the regime-transition bisection: units and argument checks."""

import numpy as np
import pytest

import gearjax.sweep
from gearjax import Accuracy, OperatingPoint, Scene, simulate
from gearjax.papers.seed001 import paper_optimum
from gearjax.sweep import load_sweep, regime_transition

TINY = Accuracy(positions_per_pitch=4, face_slices=3)


def test_load_sweep_matches_single_scenes_in_either_unit(seed_pair):
    """The vmapped sweep against one `simulate` per torque (a loop); N·m and N·mm inputs
    give the same torques, so the same numbers."""
    scene = Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=1.0), accuracy=TINY)
    torques_Nm = [0.0, 300.0, 1000.0]
    sweep = load_sweep(scene, torques_Nm=torques_Nm)
    again = load_sweep(scene, [0.0, 3.0e5, 1.0e6])
    np.testing.assert_array_equal(np.asarray(sweep.ltca.transmission_error), np.asarray(again.ltca.transmission_error))
    np.testing.assert_array_equal(np.asarray(sweep.ltca.torque), [0.0, 3.0e5, 1.0e6])
    np.testing.assert_allclose(np.asarray(sweep.torques_Nm), torques_Nm, rtol=1e-15)
    for i, t in enumerate(torques_Nm):
        single = simulate(Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=t), accuracy=TINY)).ltca
        np.testing.assert_allclose(
            np.asarray(sweep.ltca.transmission_error[i]), np.asarray(single.transmission_error), rtol=1e-9, atol=1e-15
        )


@pytest.fixture
def no_compute(monkeypatch):
    """Fail if a sweep gets as far as computing: the checks must come first."""

    def refuse(*args, **kwargs):
        raise AssertionError("computed before the arguments were checked")

    monkeypatch.setattr(gearjax.sweep, "_load_sweep", refuse)
    monkeypatch.setattr(gearjax.sweep, "simulate", refuse)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(), r"exactly one of torques \(N·mm\) and torques_Nm \(N·m\); got neither"),
        (dict(torques=[1.0], torques_Nm=[1.0]), r"exactly one of torques .* got both"),
        (dict(torques=[]), r"^torques must be a non-empty 1-D array of pinion torques \(N·mm\)"),
        (dict(torques_Nm=[[1.0, 2.0]]), r"^torques_Nm must be a non-empty 1-D array .*\(N·m\)"),
        (dict(torques_Nm=5.0), r"^torques_Nm must be a non-empty 1-D array"),
        (dict(torques=[1.0e5, -1.0]), r"^torques must be in \[0, 1e\+12\] N·mm; got -1 N·mm"),
        (dict(torques_Nm=[-2.0]), r"^torques_Nm must be in \[0, 1e\+09\] N·m; got -2 N·m"),
        (dict(torques_Nm=[100.0, float("nan")]), r"^torques_Nm must be a finite number"),
    ],
)
def test_load_sweep_rejects_bad_torques_before_computing(seed_pair, no_compute, kwargs, match):
    scene = Scene(seed_pair, accuracy=TINY)
    with pytest.raises(ValueError, match=match):
        load_sweep(scene, **kwargs)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(high=1.6e6), r"exactly one of low \(N·mm\) and low_Nm \(N·m\); got neither"),
        (dict(low=4.0e5, low_Nm=400.0, high=1.6e6), r"exactly one of low .* got both"),
        (dict(low_Nm=400.0, high=1.6e6, high_Nm=1600.0), r"exactly one of high .* got both"),
        (dict(low_Nm=-1.0, high_Nm=1600.0), r"^low_Nm must be in \[0, 1e\+09\] N·m"),
        (dict(low=4.0e5, high=float("inf")), r"^high must be a finite number"),
        (dict(low_Nm=[400.0], high_Nm=1600.0), r"^low_Nm must be a scalar torque \(N·m\)"),
        (dict(low_Nm=1600.0, high_Nm=400.0), r"^low_Nm must be below high_Nm"),
        (dict(low_Nm=400.0, high_Nm=1600.0, tolerance=0.0), r"^tolerance must be in \(0, 1\)"),
    ],
)
def test_regime_transition_rejects_bad_bounds_before_computing(seed_pair, no_compute, kwargs, match):
    scene = Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=400.0), effects=("impact",), accuracy=TINY)
    with pytest.raises(ValueError, match=match):
        regime_transition(scene, **kwargs)


def test_regime_transition_needs_the_impact_effect(seed_pair, no_compute):
    scene = Scene(seed_pair, operating=OperatingPoint(torque_Nm=400.0), accuracy=TINY)
    with pytest.raises(ValueError, match="effects including 'impact'"):
        regime_transition(scene, low_Nm=400.0, high_Nm=1600.0)
