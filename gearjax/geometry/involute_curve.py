r"""The involute of a circle: the transverse tooth profile of involute gears (mm, rad)."""

from __future__ import annotations

import jax.numpy as jnp

from .._custom_types import ArrayLike
from .._numerics import as_float, involute, safe_arccos


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


def involute_tangent(base_radius: ArrayLike, base_angle: ArrayLike, roll_length: ArrayLike):
    r"""`involute_point` $P$ and its derivative $\mathrm{d}P/\mathrm{d}s = (s/r_b)(\cos\theta,
    \sin\theta)$, in closed form."""
    theta = base_angle - roll_length / base_radius
    c, s = jnp.cos(theta), jnp.sin(theta)
    point = jnp.stack([base_radius * c - roll_length * s, base_radius * s + roll_length * c], -1)
    return point, (roll_length / base_radius)[..., None] * jnp.stack([c, s], -1)


def involute_normal(base_radius: ArrayLike, base_angle: ArrayLike, roll_length: ArrayLike):
    r"""Outward unit normal $(-\sin\theta, \cos\theta)$ of `involute_point`, defined down to
    the base circle."""
    theta = base_angle - roll_length / base_radius
    return jnp.stack([-jnp.sin(theta), jnp.cos(theta)], -1)


def slice_frame(gear: int, working_pressure_angle, base_radius, roll_length, slice_rotation):
    r"""$e_r(\psi)$, $n(\psi) = (-\sin\psi, \cos\psi)$ (2,) at the polar angle of the
    involute's base point of `gear` (0 pinion, 1 gear) turned into a transverse slice,
    $\psi = \operatorname{inv}\alpha_{wt} - s/r_b \pm \Phi$, plus $\pi$ on the gear (the
    half base thickness cancels against the placement).

    The $\pi$ is applied exactly, as a change of sign, not added to the angle: in float32
    the sum would keep the rest only to an ulp of $\pi$ (2.4e-7 rad, 0.04 µm at a 170 mm
    base radius)."""
    sense = 1.0 if gear == 0 else -1.0
    psi = involute(working_pressure_angle) - roll_length / base_radius + sense * as_float(slice_rotation)
    c, s = jnp.cos(psi), jnp.sin(psi)
    if gear == 1:
        c, s = -c, -s
    return jnp.stack([c, s], -1), jnp.stack([-s, c], -1)
