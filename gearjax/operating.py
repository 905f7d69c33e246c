"""`OperatingPoint`: the pinion's torque and speed, in engine units or the usual ones."""

from __future__ import annotations

import equinox as eqx
import numpy as np

from ._custom_types import ArrayLike, Scalar
from ._numerics import as_float
from ._validate import check_range
from .units import newton_metre_to_newton_mm, rpm_to_rad_per_s

#: Largest accepted pinion torque (N·mm) and speed (rad/s): far beyond any gear, they only
#: catch unit slips by orders of magnitude.
_MAX_TORQUE = 1e12
_MAX_SPEED = 1e6
#: The same limits in the scene file's units (N·m, rpm).
MAX_TORQUE_NM = _MAX_TORQUE / 1000.0
MAX_SPEED_RPM = _MAX_SPEED * 60.0 / (2.0 * np.pi)


class OperatingPoint(eqx.Module):
    """Load and speed of the pinion, stored in engine units.

    Give each quantity once, in the engine's unit or in the usual one:

    * torque: `torque` (N·mm) or `torque_Nm` (N·m, $T = 1000\\,T_\\text{Nm}$); neither for
      an unloaded (rigid) scene;
    * speed: `speed` (rad/s) or `speed_rpm` (rev/min, $\\omega = 2\\pi n/60$); neither for
      zero speed.

    `OperatingPoint(1.0e6, 523.6)` and `OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0)`
    are the same point. Concrete inputs are checked (ValueError naming the argument given
    and its range in that argument's unit); traced inputs (inside `jit`, `grad`, `vmap`) are
    not.

    Attributes:
        torque: pinion torque (N·mm), or None for an unloaded (rigid) scene.
        speed: pinion speed (rad/s).
    """

    torque: Scalar | None
    speed: Scalar

    def __init__(
        self,
        torque: ArrayLike | None = None,
        speed: ArrayLike | None = None,
        *,
        torque_Nm: ArrayLike | None = None,
        speed_rpm: ArrayLike | None = None,
    ):
        if torque is not None and torque_Nm is not None:
            raise ValueError("give the torque once: either torque (N·mm) or torque_Nm (N·m), not both")
        if speed is not None and speed_rpm is not None:
            raise ValueError("give the speed once: either speed (rad/s) or speed_rpm (rev/min), not both")
        if torque_Nm is not None:
            check_range("torque_Nm", torque_Nm, 0.0, MAX_TORQUE_NM, unit="N·m")
            torque = newton_metre_to_newton_mm(as_float(torque_Nm))
        elif torque is not None:
            check_range("torque", torque, 0.0, _MAX_TORQUE, unit="N·mm")
            torque = as_float(torque)
        if speed_rpm is not None:
            check_range("speed_rpm", speed_rpm, 0.0, MAX_SPEED_RPM, unit="rpm")
            speed = rpm_to_rad_per_s(as_float(speed_rpm))
        else:
            speed = 0.0 if speed is None else speed
            check_range("speed", speed, 0.0, _MAX_SPEED, unit="rad/s")
            speed = as_float(speed)
        self.torque = torque
        self.speed = speed
