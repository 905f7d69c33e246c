"""Numerically safe primitives with finite gradients at their singular points.

Every guard uses the double-`where` pattern (jax-md `safe_mask`, optax `numerics`): the
unsafe branch is fed a harmless value, so neither the value nor the gradient of the
discarded branch can become NaN. `maximum(x, eps)` is never used for this, because its
gradient is zero (or NaN) exactly where it matters.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import optimistix as optx

from ._custom_types import ArrayLike
from ._solution import ADJOINT


def as_float(x: ArrayLike) -> jax.Array:
    """`x` as an array of JAX's default float dtype (float64 once x64 is enabled)."""
    return jnp.asarray(x, dtype=jnp.result_type(float))


def safe_sqrt(x: ArrayLike) -> jax.Array:
    r"""$\sqrt{x}$ for $x > 0$ and $0$ otherwise, with a zero (not NaN) gradient at $x \le 0$."""
    x = jnp.asarray(x)
    positive = x > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def safe_norm(v: ArrayLike, axis: int = -1) -> jax.Array:
    """Euclidean norm along `axis`; zero vector gives norm 0 and gradient 0."""
    return safe_sqrt(jnp.sum(jnp.square(v), axis=axis))


def safe_divide(num: ArrayLike, den: ArrayLike, fallback: ArrayLike = 0.0) -> jax.Array:
    """`num / den` where `den != 0`, else `fallback`; finite gradients everywhere."""
    den = jnp.asarray(den)
    nonzero = den != 0
    return jnp.where(nonzero, num / jnp.where(nonzero, den, 1.0), fallback)


def safe_arccos(x: ArrayLike) -> jax.Array:
    """`arccos` clipped to [-1, 1] with a finite gradient at (and beyond) the ends."""
    x = jnp.asarray(x)
    inside = jnp.abs(x) < 1
    return jnp.where(inside, jnp.arccos(jnp.where(inside, x, 0.0)), jnp.where(x >= 1, 0.0, jnp.pi))


def safe_arcsin(x: ArrayLike) -> jax.Array:
    """`arcsin` clipped to [-1, 1] with a finite gradient at (and beyond) the ends."""
    x = jnp.asarray(x)
    inside = jnp.abs(x) < 1
    return jnp.where(inside, jnp.arcsin(jnp.where(inside, x, 0.0)), jnp.sign(x) * jnp.pi / 2)


def involute(angle: ArrayLike) -> jax.Array:
    r"""Involute function $\operatorname{inv}\alpha = \tan\alpha - \alpha$ (rad)."""
    angle = jnp.asarray(angle)
    return jnp.tan(angle) - angle


def _inverse_involute_residual(angle, target):
    return involute(angle) - target


def inverse_involute(value: ArrayLike) -> jax.Array:
    r"""Angle $\alpha \in [0, \pi/2)$ with $\operatorname{inv}\alpha$ = `value` (rad).

    Newton iteration (optimistix) from the series start $\alpha_0 = q - \tfrac{2}{15} q^3$,
    $q = (3v)^{1/3}$ (from $\operatorname{inv}\alpha = \alpha^3/3 + 2\alpha^5/15 + \dots$),
    differentiable through the implicit adjoint.
    """
    value = jnp.asarray(value)
    q = jnp.cbrt(3.0 * jnp.maximum(value, 0.0))
    start = q - (2.0 / 15.0) * q**3
    solver = optx.Newton(rtol=1e-14, atol=1e-14)
    sol = optx.root_find(
        _inverse_involute_residual, solver, start, args=value, max_steps=32, throw=False, adjoint=ADJOINT
    )
    return sol.value


def cross2(a: ArrayLike, b: ArrayLike) -> jax.Array:
    """z-component of the cross product of two planar vectors (last axis of size 2)."""
    a = jnp.asarray(a)
    b = jnp.asarray(b)
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def rotate2(angle: ArrayLike, v: ArrayLike) -> jax.Array:
    """Rotate planar vector(s) `v` counter-clockwise by `angle` (rad)."""
    c, s = jnp.cos(angle), jnp.sin(angle)
    v = jnp.asarray(v)
    return jnp.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


def perp2(v: ArrayLike) -> jax.Array:
    """Planar vector rotated by +90 degrees: (x, y) -> (-y, x)."""
    v = jnp.asarray(v)
    return jnp.stack([-v[..., 1], v[..., 0]], axis=-1)


def smooth_max(x: ArrayLike, axis: int, sharpness: float | None) -> jax.Array:
    r"""Maximum along `axis`; with a finite `sharpness` $k$ the log-sum-exp
    $\tfrac1k \log \sum e^{k x}$, which is smooth and exceeds the hard max by at most
    $\log(n)/k$. `sharpness=None` is the hard maximum. Entries equal to `-inf` drop out."""
    x = jnp.asarray(x)
    if sharpness is None:
        return jnp.max(x, axis=axis)
    return jax.nn.logsumexp(sharpness * x, axis=axis) / sharpness


def second_order_root(root: ArrayLike, step) -> jax.Array:
    r"""A root $x^*$ of $f(x, p) = 0$ found without derivatives, carrying the implicit
    function's first and second derivatives in $p$: `step(x)` is one Newton step
    $N(x) = x - f/f_x$ on the traced $p$, taken from `root` (its derivatives are dropped).
    One step from the root gives $x'$ exactly ($N_x = 0$ there) but misses the
    $f_{xx}x'^2$ term of $x''$; two steps give $x''$ as well. The value is the first
    step's, bit for bit ($a + (b - a) = b$ for $a, b$ within a factor of two; equal values,
    infinite ones included, add nothing)."""
    once = step(jax.lax.stop_gradient(root))
    twice = step(once)
    return twice + jax.lax.stop_gradient(jnp.where(once == twice, 0.0, once - twice))
