"""OperatingPoint: engine units (N·mm, rad/s) or the usual ones (N·m, rpm), each given once."""

import math

import jax
import pytest

from gearjax import OperatingPoint
from gearjax.io.scene_file import parse_scene


def test_usual_units_give_the_engine_values():
    op = OperatingPoint(torque_Nm=250.0, speed_rpm=60.0)
    assert float(op.torque) == 250.0e3  # 1 N·m = 1000 N·mm
    assert float(op.speed) == pytest.approx(2 * math.pi, rel=1e-15)  # 60 rpm = 1 rev/s
    same = OperatingPoint(2.5e5, 2 * math.pi)
    assert float(same.torque) == float(op.torque)
    assert float(same.speed) == pytest.approx(float(op.speed), rel=1e-15)
    # the forms mix: torque in N·m, speed in rad/s
    mixed = OperatingPoint(speed=10.0, torque_Nm=1.0)
    assert (float(mixed.torque), float(mixed.speed)) == (1000.0, 10.0)


def test_defaults_are_unloaded_and_at_rest():
    op = OperatingPoint()
    assert op.torque is None and float(op.speed) == 0.0
    assert OperatingPoint(speed_rpm=100.0).torque is None


def test_conversion_is_differentiable():
    """Inside grad the inputs are tracers (not range-checked); d T / d T_Nm = 1000 N·mm/(N·m)
    and d omega / d n = 2 pi / 60 rad/s per rpm."""
    assert float(jax.grad(lambda t: OperatingPoint(torque_Nm=t).torque)(100.0)) == pytest.approx(1000.0, rel=1e-15)
    assert float(jax.grad(lambda n: OperatingPoint(speed_rpm=n).speed)(100.0)) == pytest.approx(math.pi / 30, rel=1e-15)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(torque=1.0e5, torque_Nm=100.0), r"either torque \(N·mm\) or torque_Nm \(N·m\)"),
        (dict(speed=10.0, speed_rpm=100.0), r"either speed \(rad/s\) or speed_rpm \(rev/min\)"),
        (dict(torque=-5.0), r"^torque must be in \[0, 1e\+12\] N·mm; got -5 N·mm"),
        (dict(torque_Nm=-1.0), r"^torque_Nm must be in \[0, 1e\+09\] N·m; got -1 N·m"),
        (dict(torque_Nm=float("nan")), r"^torque_Nm must be a finite number"),
        (dict(speed=-1.0), r"^speed must be in \[0, 1e\+06\] rad/s"),
        (dict(speed_rpm=-3.0), r"^speed_rpm must be in \[0, 9\.5493e\+06\] rpm; got -3 rpm"),
        (dict(speed_rpm=float("inf")), r"^speed_rpm must be a finite number"),
    ],
)
def test_bad_operating_points_name_the_argument_given(kwargs, match):
    with pytest.raises(ValueError, match=match):
        OperatingPoint(**kwargs)


def test_scene_file_operating_section_is_in_usual_units():
    scene, _ = parse_scene(
        "[pair]\nteeth = [29, 71]\nnormal_module = 5.0\n[operating]\ntorque_Nm = 400.0\nspeed_rpm = 3000.0\n"
    )
    assert float(scene.operating.torque) == 4.0e5
    assert float(scene.operating.speed) == pytest.approx(100 * math.pi, rel=1e-15)  # 50 rev/s
