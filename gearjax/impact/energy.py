r"""Inertia, equivalent mass and the energy method of seed 001.

Units: mm, N, s, t (tonne), so inertia is in t·mm², mass in t, energy in N·mm.

* Gear inertia as a solid disc between hub and base radius (seed 001):
  $J_i = \tfrac{\pi\rho b}{2}(r_{bi}^4 - r_{hi}^4)$.
* Equivalent mass for a normal impulse at M: a normal impulse $P$ changes the gears'
  angular velocities by $Pp/J_1$ and $Pq/J_2$, where $p = (\mathbf r_1\times\mathbf n)_z$
  and $q$ are the moment arms of the common normal about each axis, so the normal
  relative velocity changes by $P(p^2/J_1 + q^2/J_2)$ and
  $m_{eq} = 1/(p^2/J_1 + q^2/J_2)$. On the line of action of a helical pair
  $p = r_{b1}\cos\beta_b$, $q = r_{b2}\cos\beta_b$; seed 001's
  $m_{eq} = J_1J_2/(J_1r_{b2}^2 + J_2r_{b1}^2)$ uses $r_{bi}$ (no $\cos\beta_b$) and is
  kept as a cross-check (`base_radius_equivalent_mass`).
* Energy method: all kinetic energy $\tfrac12 m_{eq}v_n^2$ goes into the strain energy
  $\int_0^{\delta_s}K_s\delta^n\,\mathrm d\delta = K_s\delta_s^{n+1}/(n+1)$, so
  $\delta_s = ((n+1)m_{eq}v_n^2/(2K_s))^{1/(n+1)}$ and
  $F_s = K_s\delta_s^n = (\tfrac{n+1}{2}m_{eq}v_n^2)^{n/(n+1)}K_s^{1/(n+1)}$.
"""

from __future__ import annotations

import math

import jax.numpy as jnp

from .._custom_types import Array


def gear_inertia(density, face_width, base_radius, hub_radius) -> Array:
    """$J = \\pi\\rho b(r_b^4 - r_h^4)/2$ (t·mm²), elementwise over the two gears."""
    return 0.5 * math.pi * density * face_width * (base_radius**4 - hub_radius**4)


def equivalent_mass(inertia, pinion_arm, gear_arm) -> Array:
    """$m_{eq} = 1/(p^2/J_1 + q^2/J_2)$ (t) for moment arms $p$, $q$ (mm) of the normal."""
    return 1.0 / (pinion_arm**2 / inertia[..., 0] + gear_arm**2 / inertia[..., 1])


def base_radius_equivalent_mass(inertia, base_radius) -> Array:
    """$m_{eq} = J_1J_2/(J_1r_{b2}^2 + J_2r_{b1}^2)$ (t): the base radii as the normal's
    arms, without $\\cos\\beta_b$ (the mesh-in impact paper's form, seed 001)."""
    j1, j2 = inertia[..., 0], inertia[..., 1]
    return j1 * j2 / (j1 * base_radius[..., 1] ** 2 + j2 * base_radius[..., 0] ** 2)


def impact_force(mass, velocity, coefficient, exponent) -> tuple[Array, Array]:
    """Energy-method peak force $F_s$ (N) and approach $\\delta_s$ (mm).

    Args:
        mass: $m_{eq}$ (t).
        velocity: normal approach velocity $v_n$ (mm/s); a receding contact ($v_n \\le 0$)
            has no impact.
        coefficient, exponent: $K_s$ (N/mm$^n$) and $n$ of $F = K_s\\delta^n$.
    """
    v = jnp.maximum(velocity, 0.0)
    energy = 0.5 * mass * v * v
    moving = energy > 0
    safe = jnp.where(moving, energy, 1.0)
    approach = ((exponent + 1.0) * safe / coefficient) ** (1.0 / (exponent + 1.0))
    approach = jnp.where(moving, approach, 0.0)
    force = jnp.where(moving, coefficient * jnp.where(moving, approach, 1.0) ** exponent, 0.0)
    return force, approach
