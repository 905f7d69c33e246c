r"""The involute of a circle: the transverse tooth profile of involute gears (mm, rad)."""

from __future__ import annotations

import jax.numpy as jnp

from .._custom_types import ArrayLike
from .._numerics import involute, safe_arccos


def involute_point(base_radius: ArrayLike, base_angle: ArrayLike, roll_length: ArrayLike):
    r"""Counter-clockwise-facing involute of a circle (mm).

    $P(s) = r_b(\cos\theta, \sin\theta) + s(-\sin\theta, \cos\theta)$ with
    $\theta = \theta_0 - s/r_b$: the string unwinds clockwise from the base point at polar
    angle `base_angle` $\theta_0$; the outward normal is $(-\sin\theta, \cos\theta)$.
    """
    theta = base_angle - roll_length / base_radius
    c, s = jnp.cos(theta), jnp.sin(theta)
    return jnp.stack([base_radius * c - roll_length * s, base_radius * s + roll_length * c], -1)


def half_tooth_angle(teeth, shift, pressure_angle_t, pressure_angle_n, radius, base_radius):
    r"""Half the transverse tooth thickness angle at `radius` (rad):
    $\psi = \pi/(2z) + 2x\tan\alpha_n/z + \operatorname{inv}\alpha_t - \operatorname{inv}\alpha_r$,
    $\cos\alpha_r = r_b/r$."""
    alpha_r = safe_arccos(base_radius / radius)
    return (
        jnp.pi / (2 * teeth)
        + 2 * shift * jnp.tan(pressure_angle_n) / teeth
        + involute(pressure_angle_t)
        - involute(alpha_r)
    )
