"""The sweeps' axes: torques and speeds given in engine or usual units, checked."""

from __future__ import annotations

import numpy as np

from .._numerics import as_float
from .._validate import check_range
from ..operating import _MAX_SPEED
from ..units import rpm_to_rad_per_s


def _one_of(
    engine_name: str, engine_value, usual_name: str, usual_value, unit: str, usual_unit: str, factor: float = 1000.0
):
    """The argument given in exactly one of its two forms, as (name, value, unit, factor to
    engine units); `factor` converts the usual unit (default N·m to N·mm)."""
    if (engine_value is None) == (usual_value is None):
        got = "both" if engine_value is not None else "neither"
        raise ValueError(f"give exactly one of {engine_name} ({unit}) and {usual_name} ({usual_unit}); got {got}")
    if engine_value is not None:
        return engine_name, engine_value, unit, 1.0
    return usual_name, usual_value, usual_unit, factor


def _axis(engine_name, engine_value, usual_name, usual_value, unit, usual_unit, *, factor, largest, what):
    """A checked sweep axis in engine units: a non-empty 1-D array of finite values in
    [0, largest] (engine units), given in exactly one of its two forms."""
    name, values, given_unit, to_engine = _one_of(
        engine_name, engine_value, usual_name, usual_value, unit, usual_unit, factor
    )
    shape = np.shape(values)
    if len(shape) != 1 or shape[0] == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array of {what} ({given_unit}); got shape {shape}")
    check_range(name, values, 0.0, largest / to_engine, unit=given_unit)
    return as_float(values) * to_engine


def _torques(torques, torques_Nm):
    return _axis("torques", torques, "torques_Nm", torques_Nm, "N·mm", "N·m",
                 factor=1000.0, largest=1e12, what="pinion torques")


def _speeds(speeds, speeds_rpm):
    return _axis("speeds", speeds, "speeds_rpm", speeds_rpm, "rad/s", "rpm",
                 factor=float(rpm_to_rad_per_s(1.0)), largest=_MAX_SPEED, what="pinion speeds")
