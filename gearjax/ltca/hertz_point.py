r"""Hertz point contact: the contact ellipse, pressure and approach of two curved bodies.

Two bodies touching at a point, with the gap near it $h = Ax^2 + By^2$ ($0 < A \le B$,
the relative curvatures, mm⁻¹, in the principal directions $x$, $y$), pressed together by a
normal load $P$ (N), touch over an ellipse of semi-axes $a \ge b$ (mm; $a$ along $x$) under
the pressure $p = p_0\sqrt{1 - x^2/a^2 - y^2/b^2}$. With $e^2 = 1 - b^2/a^2$ and the complete
elliptic integrals $K(e)$, $E(e)$ (Johnson, *Contact Mechanics*, 1985, §3.7 and §4.2):

$$\frac BA = \frac{E(e)/(1-e^2) - K(e)}{K(e) - E(e)},\qquad
a^3 = \frac{3P}{2\pi E^*}\,\frac{K(e) - E(e)}{e^2A},\qquad b = a\sqrt{1-e^2},$$

$$p_0 = \frac{3P}{2\pi ab},\qquad \delta = \frac{p_0\,b\,K(e)}{E^*},\qquad
\frac{1}{E^*} = \frac{1-\nu_1^2}{E_1} + \frac{1-\nu_2^2}{E_2}.$$

The shape $e$ depends on $B/A$ only, so the approach–load law is $\delta = c\,P^{2/3}$
(exponent $n = 3/2$ in $P = K\delta^n$). At $A = B = 1/(2R)$ (a sphere of radius $R$ on a
plane, or two crossed cylinders of radius $R$) it is the circle $a^3 = 3PR/(4E^*)$,
$\delta = a^2/R$.

The elliptic integrals come from the arithmetic–geometric mean (Abramowitz & Stegun
17.6), in a form without cancellation as $e \to 0$, so the circle is exact; $e$ from
$B/A$ by Newton's method on $\ln(b/a)$ from Hamrock & Brewe's estimate
$a/b \approx 1.0339\,(B/A)^{0.636}$ (J. Lubr. Technol. 105, 1983), then two steps on the
traced inputs, so that first and second derivatives are the implicit function's
(`_numerics.second_order_root`).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, ArrayLike, Float
from .._numerics import second_order_root

#: Iterations of the arithmetic–geometric mean (quadratic convergence: 7 reach double
#: precision for $b/a \ge 10^{-6}$).
AGM_STEPS = 7
#: Newton steps on $\ln(b/a)$ from Hamrock and Brewe's estimate (6 % off at $B/A = 100$).
NEWTON_STEPS = 8


def _elliptic_terms(m):
    """$K(m)$ and the sums $S = \\sum_{n\\ge1} 2^{n-1}c_n^2/m$ of the AGM ($m = e^2$), from which
    $(K - E)/m = K(1/2 + S)$ and $(E - (1-m)K)/m = K(1/2 - S)$ without cancellation."""
    a = jnp.ones_like(m)
    b = jnp.sqrt(1.0 - m)
    t = jnp.ones_like(m)  # c_n^2 / m, c_0^2 = m
    total = jnp.zeros_like(m)
    for n in range(1, AGM_STEPS + 1):
        a, b = 0.5 * (a + b), jnp.sqrt(a * b)
        t = m * t * t / (16.0 * a * a) if n > 1 else m / (16.0 * a * a)  # c_n = c_{n-1}^2 / (4 a_n)
        total = total + 2.0 ** (n - 1) * t
    return jnp.pi / (2.0 * a), total


def elliptic_integrals(m: ArrayLike) -> tuple[Array, Array]:
    """Complete elliptic integrals of the first and second kind, $K(m)$ and $E(m)$, of the
    parameter $m = e^2 \\in [0, 1)$."""
    m = jnp.asarray(m, float)
    k, s = _elliptic_terms(m)
    return k, k * (1.0 - m * (0.5 + s))


def _log_ratio(curvature_ratio, log_kappa):
    """$\\ln$ of the ratio $B/A$ that the ellipse $b/a = e^{\\ln\\kappa}$ carries, minus
    $\\ln(B/A)$ (the residual of the shape equation)."""
    kappa2 = jnp.exp(2.0 * log_kappa)
    m = 1.0 - kappa2
    _, s = _elliptic_terms(m)
    return jnp.log(0.5 - s) - jnp.log(kappa2 * (0.5 + s)) - jnp.log(curvature_ratio)


def _newton(log_kappa, curvature_ratio):
    value, slope = jax.value_and_grad(_log_ratio, argnums=1)(curvature_ratio, log_kappa)
    return jnp.minimum(log_kappa - value / slope, 0.0)


_newton_step = jnp.vectorize(_newton)


def ellipse_ratio(curvature_ratio: ArrayLike) -> Array:
    r"""$\kappa = b/a \in (0, 1]$ of the contact ellipse for $B/A \ge 1$."""
    ratio = jnp.maximum(jnp.asarray(curvature_ratio, float), 1.0)
    fixed = jax.lax.stop_gradient(ratio)
    log_kappa = -jnp.log(1.0339) - 0.636 * jnp.log(fixed)
    for _ in range(NEWTON_STEPS):
        log_kappa = _newton_step(log_kappa, fixed)
    return jnp.exp(second_order_root(jax.lax.stop_gradient(log_kappa), lambda k: _newton_step(k, ratio)))


class HertzPointContact(eqx.Module):
    """The Hertz contact of one load on one point contact (mm, N, MPa).

    Attributes:
        semi_major: $a$ (mm), along the direction of the smaller relative curvature $A$.
        semi_minor: $b$ (mm).
        max_pressure: $p_0$ (MPa).
        approach: $\\delta$ (mm), the normal approach of distant points of the two bodies.
        approach_coefficient: $c$ in $\\delta = cP^{2/3}$ (mm/N^(2/3)).
    """

    semi_major: Float[Array, "..."]
    semi_minor: Float[Array, "..."]
    max_pressure: Float[Array, "..."]
    approach: Float[Array, "..."]
    approach_coefficient: Float[Array, "..."]


def effective_modulus(youngs_modulus: ArrayLike, poisson_ratio: ArrayLike,
                      youngs_modulus_2: ArrayLike | None = None, poisson_ratio_2: ArrayLike | None = None) -> Array:
    """$E^*$ (MPa) of two bodies, $1/E^* = (1-\\nu_1^2)/E_1 + (1-\\nu_2^2)/E_2$; the same
    material for both when the second is not given."""
    e2 = youngs_modulus if youngs_modulus_2 is None else youngs_modulus_2
    nu2 = poisson_ratio if poisson_ratio_2 is None else poisson_ratio_2
    return 1.0 / ((1.0 - poisson_ratio**2) / youngs_modulus + (1.0 - nu2**2) / e2)


def hertz_point_contact(load: ArrayLike, curvature_a: ArrayLike, curvature_b: ArrayLike,
                        modulus: ArrayLike) -> HertzPointContact:
    """The contact ellipse, peak pressure and approach of a normal load.

    Args:
        load: $P$ (N), $\\ge 0$.
        curvature_a, curvature_b: the relative curvatures $A$, $B$ (mm⁻¹) of the gap
            $h = Ax^2 + By^2$, both $> 0$, in either order (half the principal relative
            curvatures: $A = B = 1/(2R)$ for a sphere of radius $R$ on a plane).
        modulus: $E^*$ (MPa), `effective_modulus`.

    Returns:
        `HertzPointContact`; broadcast over the inputs.
    """
    load = jnp.asarray(load, float)
    small = jnp.minimum(curvature_a, curvature_b)
    large = jnp.maximum(curvature_a, curvature_b)
    kappa = ellipse_ratio(large / small)
    m = 1.0 - kappa**2
    k, s = _elliptic_terms(m)
    k_minus_e_over_m = k * (0.5 + s)
    # a^3 = 3 P (K - E) / (2 pi E* e^2 A): per unit load^(1/3)
    a_unit = (3.0 * k_minus_e_over_m / (2.0 * jnp.pi * modulus * small)) ** (1.0 / 3.0)
    b_unit = a_unit * kappa
    # delta = p0 b K / E* with p0 = 3 P / (2 pi a b): delta = 3 P K / (2 pi a E*)
    coefficient = 3.0 * k / (2.0 * jnp.pi * a_unit * modulus)
    scale = jnp.where(load > 0.0, jnp.where(load > 0.0, load, 1.0) ** (1.0 / 3.0), 0.0)
    a, b = a_unit * scale, b_unit * scale
    safe = jnp.where(load > 0.0, a * b, 1.0)
    p0 = jnp.where(load > 0.0, 3.0 * load / (2.0 * jnp.pi * safe), 0.0)
    return HertzPointContact(a, b, p0, coefficient * scale**2, coefficient)


def relative_curvatures(surface_1, parameters_1: ArrayLike, surface_2, parameters_2: ArrayLike,
                        normal: ArrayLike) -> tuple[Array, Array, Array]:
    r"""The relative curvatures $A \le B$ (mm⁻¹) of two parametric surfaces touching at a point,
    and the direction of $A$ (the contact ellipse's major axis).

    Each surface is a function `(p0, p1) -> point` (mm, a common frame); `normal` is the
    common unit normal pointing out of body 1 into body 2. In an orthonormal basis $E$ of
    the tangent plane each surface's height along the normal is $\frac12 x^T L x$, with
    $L = E^TJ^{+T}HJ^{+}E$ ($J$ the surface's Jacobian, $H_{ij} = r_{,ij}\cdot n$); the gap
    is $h = \frac12 x^T(L_2 - L_1)x$, so $A$, $B$ are the eigenvalues of $(L_2 - L_1)/2$.

    Returns:
        (A, B, direction): curvatures (mm⁻¹) and the unit tangent vector of $A$ (3,).
    """
    n = jnp.asarray(normal, float)
    n = n / jnp.linalg.norm(n)
    # an orthonormal tangent basis: the axis least aligned with n, made orthogonal to it
    axis = jnp.eye(3)[jnp.argmin(jnp.abs(n))]
    e1 = axis - jnp.dot(axis, n) * n
    e1 = e1 / jnp.linalg.norm(e1)
    basis = jnp.stack([e1, jnp.cross(n, e1)], axis=1)  # (3, 2)

    def height_form(surface, p):
        f = lambda q: surface(q[0], q[1])  # noqa: E731
        p = jnp.asarray(p, float)
        jac = jax.jacfwd(f)(p)  # (3, 2)
        hess = jnp.einsum("kij,k->ij", jax.hessian(f)(p), n)
        to_params = jnp.linalg.pinv(jac) @ basis  # tangent coordinates -> parameter steps
        return to_params.T @ hess @ to_params

    half = 0.5 * (height_form(surface_2, parameters_2) - height_form(surface_1, parameters_1))
    mean = 0.5 * (half[0, 0] + half[1, 1])
    diff, off = half[0, 0] - half[1, 1], half[0, 1]
    squared = 0.25 * diff**2 + off**2
    round_ = squared <= 0.0  # a circle: every direction is principal (guarded for gradients)
    radius = jnp.where(round_, 0.0, jnp.sqrt(jnp.where(round_, 1.0, squared)))
    small, large = mean - radius, mean + radius
    # eigenvector of the smaller eigenvalue
    angle = 0.5 * jnp.arctan2(jnp.where(round_, 0.0, 2.0 * off), jnp.where(round_, 1.0, diff)) + 0.5 * jnp.pi
    direction = basis @ jnp.stack([jnp.cos(angle), jnp.sin(angle)])
    return small, large, direction
