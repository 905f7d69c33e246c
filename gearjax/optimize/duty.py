"""The duty cycle of the objective: loads, their time shares and the speed at each load,
checked and converted to the engine's units (N·mm, rad/s) before any work."""

from __future__ import annotations

import numpy as np

from .._validate import check_range
from ..scene import Scene


def _loads(scene: Scene, torques, torques_Nm) -> np.ndarray:
    """The load spectrum (N·mm) from `torques` (N·mm) or `torques_Nm`, default the scene's."""
    if torques is not None and torques_Nm is not None:
        raise ValueError("give the loads once: torques (N·mm) or torques_Nm (N·m)")
    if torques is None and torques_Nm is None:
        torques, name, unit, factor = [float(scene.operating.torque)], "torques", "N·mm", 1.0
    elif torques is not None:
        name, unit, factor = "torques", "N·mm", 1.0
    else:
        torques, name, unit, factor = torques_Nm, "torques_Nm", "N·m", 1000.0
    values = np.asarray(torques, dtype=float)
    if values.ndim != 1 or values.size == 0:
        raise ValueError(f"{name} must be a non-empty list of pinion torques ({unit}); got {torques!r}")
    check_range(name, values, 0.0, 1e12 / factor, low_inclusive=False, unit=unit)
    return values * factor


def _weights(weights, count: int) -> np.ndarray:
    """The loads' time shares, normalised to sum 1 (default equal)."""
    if weights is None:
        return np.full(count, 1.0 / count)
    w = np.asarray(weights, dtype=float)
    if w.shape != (count,):
        raise ValueError(f"load weights must hold one weight per load ({count}); got {list(np.atleast_1d(w))}")
    check_range("load weights", w, 0.0, None)
    if not w.sum() > 0.0:
        raise ValueError(f"load weights must sum to a positive number; got {list(w)}")
    return w / w.sum()


def _speeds(scene: Scene, speeds, speeds_rpm, count: int) -> np.ndarray:
    """The pinion speed at each load (rad/s) from `speeds` (rad/s) or `speeds_rpm`, one per
    load or one for all; default the scene's."""
    if speeds is not None and speeds_rpm is not None:
        raise ValueError("give the speeds once: speeds (rad/s) or speeds_rpm (rpm)")
    if speeds is None and speeds_rpm is None:
        return np.full(count, float(scene.operating.speed))
    name, unit, value = ("speeds", "rad/s", speeds) if speeds is not None else ("speeds_rpm", "rpm", speeds_rpm)
    values = np.atleast_1d(np.asarray(value, dtype=float))
    if values.ndim != 1 or values.size not in (1, count):
        raise ValueError(f"{name} must hold one pinion speed ({unit}) per load ({count}) or one for all; got {value!r}")
    factor = 1.0 if speeds is not None else 2.0 * np.pi / 60.0  # rad/s per given unit
    check_range(name, values, 0.0, 1e6 / factor, unit=unit)
    values = values * factor
    return np.broadcast_to(values, (count,)).copy()
