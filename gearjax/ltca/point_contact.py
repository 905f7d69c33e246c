r"""Loaded contact of point-contact flanks: tooth compliance of a sampled tooth section and
the load sharing of tooth pairs that each touch at one point.

**Tooth compliance** (energy method; Yang & Lin 1987, Tian 2004, as `tooth_stiffness` for
the involute tooth, here for any symmetric tooth given by samples of its half thickness
$h(x)$ along its centre line $x$, from the root section $x_r$ to the load point $x_F$). A
normal load $F$ at the angle $\gamma$ to the tooth's transverse direction, applied at the
distance $y_F$ from the centre line, bends, shears and compresses the tooth; per unit face
width, with the section area $A = 2h$ and moment of inertia $I = (2h)^3/12$,

$$c_t = \int_{x_r}^{x_F}\Big[\frac{\big((x_F - x)\cos\gamma - y_F\sin\gamma\big)^2}{E'I}
+ \frac{1.2\cos^2\gamma}{G'A} + \frac{\sin^2\gamma}{E'A}\Big]dx$$

(mm²/N; plane strain, $E' = E/(1-\nu^2)$, $G' = E'/(2(1+\nu))$), by the trapezoidal rule on
the samples.

**A point load on a tooth of finite face width.** Along the face the tooth is taken as
the Winkler foundation with a shear layer of `SliceCompliance` (Ajmi & Velex 2005): a point
load spreads with the decay length $\lambda$, and its deflection is $c_t/(2\lambda)$ on an
infinite face (mm/N).

**Load sharing.** Each tooth pair $k$ in mesh touches at one point with the rigid normal
gap $e_k$ (mm, from the TCA) and carries $F_k \ge 0$ with the approach
$c_kF_k + h_kF_k^{2/3}$ (linear tooth compliance $c_k$, Hertz coefficient $h_k$,
`hertz_point`). All pairs share the rigid approach $Z$ of the gears, so
$c_kF_k + h_kF_k^{2/3} = \max(Z - e_k, 0)$ and $\sum_k F_k = P$. Each $F_k(Z)$ is monotone,
so is their sum: $Z$ by a safeguarded Newton iteration, the last step taken on the traced
inputs so that derivatives are the implicit function's.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .._custom_types import Array, ArrayLike, Float

#: Newton steps for one pair's load at a given approach, and for the shared approach.
LOAD_STEPS = 30
APPROACH_STEPS = 40


def section_compliance(x: ArrayLike, half_thickness: ArrayLike, load_offset: ArrayLike, load_angle: ArrayLike,
                       youngs_modulus: ArrayLike, poisson_ratio: ArrayLike) -> Array:
    """Bending, shear and compressive compliance $c_t$ (mm²/N, per unit face width) of a
    tooth sampled at centre-line positions `x` (mm, increasing from the root section to
    the load point, the last sample) with half thicknesses `half_thickness` (mm), for a
    normal load at `load_offset` $y_F$ (mm) from the centre line and `load_angle` $\\gamma$
    (rad) to the transverse direction. The formula is the module's."""
    x = jnp.asarray(x, float)
    h = jnp.asarray(half_thickness, float)
    e_plane = youngs_modulus / (1.0 - poisson_ratio**2)
    g_plane = e_plane / (2.0 * (1.0 + poisson_ratio))
    area = 2.0 * h
    inertia = area**3 / 12.0
    cos, sin = jnp.cos(load_angle), jnp.sin(load_angle)
    moment_arm = (x[..., -1:] - x) * cos - load_offset * sin
    integrand = moment_arm**2 / (e_plane * inertia) + 1.2 * cos**2 / (g_plane * area) + sin**2 / (e_plane * area)
    return jnp.sum(0.5 * (integrand[..., 1:] + integrand[..., :-1]) * jnp.diff(x, axis=-1), axis=-1)


def point_load_compliance(section: ArrayLike, decay_length: ArrayLike) -> Array:
    """Deflection per unit point load (mm/N) of a tooth whose compliance per unit face width
    is `section` (mm²/N), spread along the face with `decay_length` $\\lambda$ (mm):
    $c_t/(2\\lambda)$."""
    return section / (2.0 * decay_length)


def _pair_load(approach, linear, hertz):
    """$F \\ge 0$ with $cF + hF^{2/3} = \\delta$ ($\\delta \\ge 0$), by Newton on $s = F^{1/3}$:
    $cs^3 + hs^2 = \\delta$ is convex and increasing in $s \\ge 0$, so Newton from above
    converges monotonically."""
    touching = approach > 0.0
    safe = jnp.where(touching, approach, 1.0)
    # start above the root: the smaller of the roots of each term alone (both over-estimate)
    s = jnp.where(touching, jnp.minimum(jnp.cbrt(safe / linear), jnp.sqrt(safe / hertz)), 0.0)
    approach = jnp.where(touching, approach, 0.0)

    def step(s, _):
        f = linear * s**3 + hertz * s**2 - approach
        slope = 3.0 * linear * s**2 + 2.0 * hertz * s
        safe = jnp.where(slope > 0.0, slope, 1.0)
        return jnp.where(slope > 0.0, s - f / safe, 0.0), None

    s, _ = jax.lax.scan(step, s, None, length=LOAD_STEPS)
    return s**3


def pair_loads(approach: ArrayLike, gaps: ArrayLike, linear: ArrayLike, hertz: ArrayLike) -> Array:
    """Loads $F_k$ (N) of the pairs at the shared approach $Z$ (mm; shape (..., 1) against
    the pairs' (..., pair)): gaps $e_k$ (mm; `inf`
    for a pair out of mesh), linear compliances $c_k$ (mm/N) and Hertz coefficients $h_k$
    (mm/N^(2/3))."""
    gaps = jnp.asarray(gaps, float)
    finite = jnp.isfinite(gaps)
    closing = jnp.where(finite, approach - jnp.where(finite, gaps, 0.0), 0.0)
    return _pair_load(closing, linear, hertz)


def _total_slope(approach, gaps, linear, hertz):
    """$\\sum_k dF_k/dZ$ from $dF/d\\delta = 1/(c + \\tfrac23 hF^{-1/3})$ (0 out of contact)."""
    loads = pair_loads(approach[..., None], gaps, linear, hertz)
    s = jnp.cbrt(loads)
    safe = jnp.where(s > 0.0, s, 1.0)
    return jnp.sum(jnp.where(s > 0.0, safe / (linear * safe + 2.0 / 3.0 * hertz), 0.0), axis=-1)


def shared_approach(load: ArrayLike, gaps: ArrayLike, linear: ArrayLike, hertz: ArrayLike) -> Array:
    """The rigid approach $Z$ (mm) at which the pairs carry the normal load $P$ (N) together.

    Args:
        load: $P$ (N), $\\ge 0$.
        gaps: $e_k$ (mm), shape (pair,); `inf` for pairs out of mesh (at least one finite).
        linear: $c_k$ (mm/N), $> 0$.
        hertz: $h_k$ (mm/N^(2/3)), $> 0$.

    Returns:
        $Z$ (mm): $\\min_k e_k$ at zero load (the rigid TCA's contact), growing with $P$.
    """
    gaps = jnp.asarray(gaps, float)
    lowest = jax.lax.stop_gradient(jnp.min(gaps, axis=-1))

    def residual(z, p, e, c, h):
        return jnp.sum(pair_loads(z[..., None], e, c, h), axis=-1) - p

    def newton(z, p, e, c, h):
        slope = _total_slope(z, e, c, h)
        step = residual(z, p, e, c, h) / jnp.where(slope > 0.0, slope, 1.0)
        return jnp.maximum(jnp.where(slope > 0.0, z - step, z), lowest)

    fixed = jax.lax.stop_gradient((load, gaps, linear, hertz))
    # start above the root (the convex sum makes Newton monotone from there)
    z = lowest + jnp.max(fixed[2], axis=-1) * fixed[0] + jnp.max(fixed[3], axis=-1) * jnp.cbrt(fixed[0]) ** 2
    z, _ = jax.lax.scan(lambda z, _: (newton(z, *fixed), None), z, None, length=APPROACH_STEPS)
    z = jax.lax.stop_gradient(z)
    # one Newton step on the traced inputs: the implicit function's derivative at the root
    slope = _total_slope(z, gaps, linear, hertz)
    return z - residual(z, load, gaps, linear, hertz) / jnp.where(slope > 0.0, slope, 1.0)


def share_load(load: ArrayLike, gaps: ArrayLike, linear: ArrayLike, hertz: ArrayLike) -> tuple[Array, Float[Array, "..."]]:
    """`shared_approach` and the pairs' loads $F_k$ (N) there (they sum to $P$)."""
    approach = shared_approach(load, gaps, linear, hertz)
    return approach, pair_loads(approach[..., None], gaps, linear, hertz)
