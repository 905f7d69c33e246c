"""Units and materials.

The engine computes in one consistent set: **mm, N, s, tonne (t), rad**. Stress is then in
MPa (N/mm^2), stiffness in N/mm, density in t/mm^3 (steel 7.85e-9), inertia in t·mm^2 and
energy in N·mm. Constructors take angles in degrees only through arguments whose names say
so (`..._deg`); presentation (CLI, plots, JSON) converts to micrometres, N·m and rpm.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp

from ._custom_types import ArrayLike
from ._numerics import as_float
from ._validate import check_range

#: micrometres per millimetre (engine lengths are mm).
UM_PER_MM = 1000.0
#: microradians per radian.
URAD_PER_RAD = 1.0e6


def deg(angle_rad: ArrayLike) -> jax.Array:
    """Radians to degrees."""
    return jnp.asarray(angle_rad) * (180.0 / math.pi)


def rad(angle_deg: ArrayLike) -> jax.Array:
    """Degrees to radians."""
    return jnp.asarray(angle_deg) * (math.pi / 180.0)


def rpm_to_rad_per_s(speed_rpm: ArrayLike) -> jax.Array:
    """Rotational speed: rev/min to rad/s."""
    return jnp.asarray(speed_rpm) * (2.0 * math.pi / 60.0)


def rad_per_s_to_rpm(speed: ArrayLike) -> jax.Array:
    return jnp.asarray(speed) * (60.0 / (2.0 * math.pi))


def newton_metre_to_newton_mm(torque_Nm: ArrayLike) -> jax.Array:
    """Torque: N·m to the engine's N·mm."""
    return jnp.asarray(torque_Nm) * 1000.0


class Material(eqx.Module):
    """Isotropic linear-elastic gear material.

    Attributes:
        youngs_modulus: E (MPa = N/mm^2).
        poisson_ratio: nu (-).
        density: rho (t/mm^3; steel 7.85e-9).
    """

    youngs_modulus: jax.Array
    poisson_ratio: jax.Array
    density: jax.Array

    def __init__(
        self,
        youngs_modulus: ArrayLike = 206000.0,
        poisson_ratio: ArrayLike = 0.3,
        density: ArrayLike = 7.85e-9,
    ):
        check_range("youngs_modulus", youngs_modulus, 0.0, None, low_inclusive=False, unit="MPa")
        check_range("poisson_ratio", poisson_ratio, 0.0, 0.5, high_inclusive=False)
        check_range("density", density, 0.0, None, low_inclusive=False, unit="t/mm^3")
        self.youngs_modulus = as_float(youngs_modulus)
        self.poisson_ratio = as_float(poisson_ratio)
        self.density = as_float(density)

    @property
    def shear_modulus(self) -> jax.Array:
        """G = E / (2 (1 + nu)) (MPa)."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))


#: Steel as in ISO 6336: E = 206 000 MPa, nu = 0.3, rho = 7.85e-9 t/mm^3.
def steel() -> Material:
    return Material()
