r"""Loaded contact of point-contact flanks: tooth compliance of a sampled tooth section and
the load sharing of tooth pairs that each touch at one point.

**Tooth compliance** (energy method; Yang & Lin 1987, Tian 2004, as `tooth_stiffness` for
the involute tooth, here for any symmetric tooth given by samples of its half thickness
$h(x)$ along its centre line $x$, from the root section $x_r$ to the load point $x_F$). A
normal load $F$ at the angle $\gamma$ to the tooth's transverse direction, applied at the
distance $y_F$ from the centre line, bends, shears and compresses the tooth; per unit face
width, with the section area $A = 2h$ and moment of inertia $I = (2h)^3/12$,

$$c_t = \int_{x_r}^{x_F}\Big[\frac{\big((x_F - x)\cos\gamma - y_F\sin\gamma\big)^2}{EI}
+ \frac{1.2\cos^2\gamma}{GA} + \frac{\sin^2\gamma}{EA}\Big]dx$$

(mm²/N; $G = E/(2(1+\nu))$, the involute tooth's convention), by the trapezoidal rule on
the samples.

**A point load on a tooth of finite face width.** Along the face the tooth is taken as
the Winkler foundation with a shear layer of `SliceCompliance` (Ajmi & Velex 2005), in its
continuous form $w/c_t - \lambda^2 w''/c_t = q$ on the face $|s| \le b/2$ with free ends
($w' = 0$): a point load spreads with the decay length $\lambda$, and its deflection under
the load at $z$ is the Green's function there,

$$\frac{w}{F} = \frac{c_t}{\lambda}\,\frac{\cosh\frac{b/2 + z}{\lambda}\,
\cosh\frac{b/2 - z}{\lambda}}{\sinh\frac{b}{\lambda}}$$

(mm/N): $c_t/(2\lambda)$ far from the ends, twice that at a face end, as the slices'
tridiagonal model gives for the involute tooth.

**Load sharing.** Each tooth pair $k$ in mesh touches at one point with the rigid normal
gap $e_k$ (mm, from the TCA) and carries $F_k \ge 0$ with the approach
$c_kF_k + h_kF_k^{2/3}$ (linear tooth compliance $c_k$, Hertz coefficient $h_k$,
`hertz_point`). A lag $\Theta$ of the gear moves every contact along its normal by
$m_k\Theta$ ($m_k$, mm: the TCA's $r_{a2}|n_t|$), so
$c_kF_k + h_kF_k^{2/3} = \max(m_k\Theta - e_k, 0)$ and the torque on the gear is
$\sum_k m_kF_k = T$. Each $F_k(\Theta)$ is increasing and convex, so is the torque: $\Theta$
by Newton's method from above (monotone), then two steps on the traced inputs so that its
first and second derivatives are the implicit function's (`_numerics.second_order_root`;
the impact differentiates rates along the pinion angle once more). The mesh stiffness follows as
$dT/d\Theta = \sum_k m_k^2\,dF_k/d\delta_k$.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .._custom_types import Array, ArrayLike, Float
from .._numerics import second_order_root

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
    e_plane = youngs_modulus
    g_plane = youngs_modulus / (2.0 * (1.0 + poisson_ratio))
    area = 2.0 * h
    inertia = area**3 / 12.0
    cos, sin = jnp.cos(load_angle), jnp.sin(load_angle)
    moment_arm = (x[..., -1:] - x) * cos - load_offset * sin
    integrand = moment_arm**2 / (e_plane * inertia) + 1.2 * cos**2 / (g_plane * area) + sin**2 / (e_plane * area)
    return jnp.sum(0.5 * (integrand[..., 1:] + integrand[..., :-1]) * jnp.diff(x, axis=-1), axis=-1)


def point_load_compliance(section: ArrayLike, decay_length: ArrayLike, z: ArrayLike, face_width: ArrayLike) -> Array:
    """Deflection per unit point load (mm/N) at the axial position `z` (mm, 0 mid-face) of a
    tooth of `face_width` $b$ (mm) whose compliance per unit face width is `section` (mm²/N),
    spread along the face with `decay_length` $\\lambda$ (mm): the module's Green's function,
    as $\\frac{c_t}{2\\lambda}(1 + e^{-2a})(1 + e^{-2c})/(1 - e^{-2(a + c)})$ with
    $a, c = (b/2 \\pm z)/\\lambda$ (no overflow for any $b/\\lambda$); `z` is clipped to the
    face."""
    half = 0.5 * face_width
    z = jnp.clip(z, -half, half)
    a, c = (half + z) / decay_length, (half - z) / decay_length
    ends = (1.0 + jnp.exp(-2.0 * a)) * (1.0 + jnp.exp(-2.0 * c)) / (1.0 - jnp.exp(-2.0 * (a + c)))
    return section / (2.0 * decay_length) * ends


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


def pair_loads(rotation: ArrayLike, gaps: ArrayLike, arms: ArrayLike, linear: ArrayLike, hertz: ArrayLike) -> Array:
    r"""Loads $F_k$ (N) of the pairs at the gear's lag $\Theta$ (rad; shape (..., 1) against
    the pairs' (..., pair)): normal gaps $e_k$ (mm; `inf` for a pair out of mesh), arms
    $m_k$ (mm: the normal displacement of the pair's contact per radian of lag), linear
    compliances $c_k$ (mm/N) and Hertz coefficients $h_k$ (mm/N^(2/3))."""
    gaps = jnp.asarray(gaps, float)
    finite = jnp.isfinite(gaps)
    closing = jnp.where(finite, arms * rotation - jnp.where(finite, gaps, 0.0), 0.0)
    return _pair_load(closing, linear, hertz)


def _residual_and_slope(rotation, torque, gaps, arms, linear, hertz):
    r"""$\sum_k m_kF_k - T$ and its derivative $\sum_k m_k^2\,dF_k/d\delta_k$, with
    $dF/d\delta = 1/(c + \tfrac23 hF^{-1/3})$ (0 out of contact)."""
    loads = pair_loads(rotation[..., None], gaps, arms, linear, hertz)
    s = jnp.cbrt(loads)
    safe = jnp.where(s > 0.0, s, 1.0)
    rate = jnp.where(s > 0.0, safe / (linear * safe + 2.0 / 3.0 * hertz), 0.0)
    return jnp.sum(arms * loads, axis=-1) - torque, jnp.sum(arms**2 * rate, axis=-1)


def shared_rotation(torque: ArrayLike, gaps: ArrayLike, arms: ArrayLike, linear: ArrayLike, hertz: ArrayLike) -> Array:
    r"""The gear's lag $\Theta$ (rad) at which the pairs carry the torque $T$ together:
    $\sum_k m_kF_k(m_k\Theta - e_k) = T$.

    Args:
        torque: $T$ (N·mm) about the gear's axis, $\ge 0$.
        gaps: $e_k$ (mm), shape (..., pair); `inf` for pairs out of mesh (at least one
            finite, and 0 at the binding pair of the rigid TCA).
        arms: $m_k$ (mm), $> 0$.
        linear: $c_k$ (mm/N), $> 0$.
        hertz: $h_k$ (mm/N^(2/3)), $> 0$.

    Returns:
        $\Theta$ (rad): $\min_k e_k/m_k$ at zero torque (the rigid contact), growing with $T$.
    """
    gaps = jnp.asarray(gaps, float)
    lowest = jax.lax.stop_gradient(jnp.min(gaps / arms, axis=-1))

    def newton(theta, *args):
        value, slope = _residual_and_slope(theta, *args)
        step = value / jnp.where(slope > 0.0, slope, 1.0)
        return jnp.maximum(jnp.where(slope > 0.0, theta - step, theta), lowest)

    fixed = jax.lax.stop_gradient((torque, gaps, arms, linear, hertz))
    t, _, m, c, h = fixed
    # above the root: the binding pair alone carrying the whole torque on the shortest arm
    # (Newton on a convex increasing function converges monotonically from there)
    m_min = jnp.min(m, axis=-1)
    load = t / m_min
    theta = lowest + (jnp.max(c, axis=-1) * load + jnp.max(h, axis=-1) * jnp.cbrt(load) ** 2) / m_min
    theta, _ = jax.lax.scan(lambda th, _: (newton(th, *fixed), None), theta, None, length=APPROACH_STEPS)
    theta = jax.lax.stop_gradient(theta)

    def step(theta):  # a Newton step on the traced inputs; no pair loaded (zero torque): the rigid contact
        value, slope = _residual_and_slope(theta, torque, gaps, arms, linear, hertz)
        return jnp.where(slope > 0.0, theta - value / jnp.where(slope > 0.0, slope, 1.0), jnp.min(gaps / arms, axis=-1))

    return second_order_root(theta, step)


def share_load(torque: ArrayLike, gaps: ArrayLike, arms: ArrayLike, linear: ArrayLike,
               hertz: ArrayLike) -> tuple[Array, Float[Array, "..."]]:
    r"""`shared_rotation` and the pairs' loads $F_k$ (N) there ($\sum_k m_kF_k = T$)."""
    rotation = shared_rotation(torque, gaps, arms, linear, hertz)
    return rotation, pair_loads(rotation[..., None], gaps, arms, linear, hertz)
