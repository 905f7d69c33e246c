r"""Refinement of the binding slice value between slices.

Over the slice midpoints the maximum of the slice values $g(z)$ is refined by one Newton
step on $g'(z) = 0$ from the best slice: exact for the parabolic gaps of crowned flanks and
parabolic reliefs, whose parabolas peak at their start points.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .._custom_types import Array
from .._numerics import safe_divide


def peak_correction(residual, y, z, lead_correction, half_width, limits) -> Array:
    """Rise of the slice value $g(z)$ from the best slice to the peak between slices.

    One Newton step on $g'(z) = 0$ from the best slice $z^*$: $t = -g'/g''$, clipped to
    half a slice width and to the stretch on which the contact's parameters stay on the
    active flanks (so it never extrapolates past the end of a contact line), rise
    $g't + \\tfrac12 g''t^2 \\ge 0$. Exact for the parabolic ($C^1$) reliefs and
    crowning, whose parabolas peak at their start points; zero on a plateau
    ($g' = g'' = 0$) and wherever $g$ is not concave.

    The derivatives of the solution $y(z)$ of $F(y, z) = 0$ follow from the implicit
    function theorem on the explicit residual (no second trace of the Newton solver):
    $y' = -J^{-1}F_z$, $y'' = -J^{-1}\\,\\mathrm{d}^2F(y + t y', z + t)/\\mathrm{d}t^2$.
    """
    # J and F_z from one forward pass over (y, z): the residual is traced once for both.
    jac, f_z = jax.jacfwd(residual, (0, 1))(y, z)
    # A dense 3x3 solve: differentiable to any order and free of lineax's error checks
    # (host callbacks, which would keep the program out of the compilation cache).
    dy = -jnp.linalg.solve(jac, f_z)

    def along(t):
        return residual(y + t * dy, z + t)

    def first(t):
        return jax.jvp(along, (t,), (jnp.ones_like(t),))[1]

    zero = jnp.zeros_like(z)
    second = jax.jvp(first, (zero,), (jnp.ones_like(zero),))[1]
    d2y = -jnp.linalg.solve(jac, second)
    _, lc1 = jax.jvp(lead_correction, (z,), (jnp.ones_like(z),))
    lc2 = jax.jvp(lambda zz: jax.jvp(lead_correction, (zz,), (jnp.ones_like(zz),))[1], (z,), (jnp.ones_like(z),))[1]
    low, high = _room(y[:2], dy[:2], limits, half_width)
    return _newton_rise(dy[2] + lc1, d2y[2] + lc2, low, high)


def explicit_peak_correction(value, params, z, half_width, limits) -> Array:
    """`peak_correction` for an explicit slice value $g(z)$ with contact parameters
    `params(z)` (plane-of-action path)."""

    def first(zz):
        return jax.jvp(value, (zz,), (jnp.ones_like(zz),))[1]

    d1, d2 = jax.jvp(first, (z,), (jnp.ones_like(z),))
    u, du = jax.jvp(params, (z,), (jnp.ones_like(z),))
    low, high = _room(u, du, limits, half_width)
    return _newton_rise(d1, d2, low, high)


def _room(u, rate, limits, half_width):
    """Largest steps (down, up) in $z$ before a parameter moving at `rate` leaves its
    limits, capped at `half_width`."""
    lo = jnp.stack([limits[0][0], limits[1][0]])
    hi = jnp.stack([limits[0][1], limits[1][1]])
    up = jnp.where(rate > 0, safe_divide(hi - u, rate, jnp.inf), jnp.where(rate < 0, safe_divide(lo - u, rate, jnp.inf), jnp.inf))
    down = jnp.where(rate > 0, safe_divide(u - lo, rate, jnp.inf), jnp.where(rate < 0, safe_divide(u - hi, rate, jnp.inf), jnp.inf))
    return jnp.clip(jnp.min(down), 0.0, half_width), jnp.clip(jnp.min(up), 0.0, half_width)


def _newton_rise(d1, d2, low, high) -> Array:
    concave = d2 < 0
    step = jnp.clip(safe_divide(-d1, jnp.where(concave, d2, -1.0)), -low, high)
    rise = d1 * step + 0.5 * d2 * step**2
    return jnp.where(concave & jnp.isfinite(rise), jnp.maximum(rise, 0.0), 0.0)
