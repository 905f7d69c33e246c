r"""Closed-form edge contact of unmodified involute gears (seed 001, Scenario 1).

An independent check of the general first-contact search. In a transverse section of an
unmodified pair whose gear lags its conjugate position by a constant angle $\varepsilon$
(rad of gear 2: LTE $= -\varepsilon$), the gear's tip corner meets the pinion flank before
the theoretical start of engagement A, off the line of action. Seed 001 writes this as an
arcsin/involute-function equation for $\Delta\varphi_{k2}$ ("reverse rotation" method); as
printed it mixes gear and pinion rotations (the $\Delta\varphi_{k2}/i$ term), so this module
implements the same geometry from first principles:

* frame: $O_1 = 0$, $O_2 = (a, 0)$, pitch point $P = (r_{w1}, 0)$, line of action
  $P + \lambda\mathbf n$ with $\mathbf n = (\sin\alpha_{wt}, \cos\alpha_{wt})$, along which
  the contact of a counter-clockwise driving pinion travels; the gear's tip corner at A:
  $\lambda_A = s_A - r_{w1}\sin\alpha_{wt}$, $s_A = a\sin\alpha_{wt} -
  \sqrt{r_{a2}^2 - r_{b2}^2}$ the pinion's roll length at A;
* the pinion turns by $\Delta$ (counter-clockwise) from A's position, the gear by
  $\Delta z_1/z_2 - \varepsilon$ (clockwise); the tip corner in the pinion's frame is
  $\mathbf A_1(\Delta) = R(-\Delta)\,[O_2 + R(-(\Delta z_1/z_2 - \varepsilon))(\mathbf A - O_2)]$;
* it lies on the pinion involute through A when its polar angle equals the involute's,
  $\theta(\mathbf A_1) = \theta(\mathbf A) - [\operatorname{inv}\arccos(r_{b1}/|\mathbf A_1|)
  - \operatorname{inv}\arccos(r_{b1}/|\mathbf A|)]$,

which is the seed's equation with both rotations written out. Its first root $\Delta^* < 0$
(the pinion angle before A at which the corner strikes) is found by a sign scan and
optimistix's Newton; $r^* = |\mathbf A_1(\Delta^*)|$ is the contact radius on the pinion.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx

from .._custom_types import Scalar
from .._numerics import involute, safe_arccos, safe_norm


class ClosedFormEdgeContact(eqx.Module):
    """Result of `edge_contact_closed_form`.

    Attributes:
        pinion_rotation: $\\Delta^*$, pinion angle from the theoretical start A (rad; < 0
            means before A).
        radius: contact radius on the pinion (mm).
        roll_length: the pinion involute's roll length there, $\\sqrt{r^{*2} - r_{b1}^2}$ (mm).
        converged: the Newton solve converged.
    """

    pinion_rotation: Scalar
    radius: Scalar
    roll_length: Scalar
    converged: jax.Array


def _rot(angle, v):
    c, s = jnp.cos(angle), jnp.sin(angle)
    return jnp.stack([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _corner(delta, args):
    a, ratio, lag, corner = args
    o2 = jnp.stack([a, jnp.zeros_like(a)])
    return _rot(-delta, o2 + _rot(-(delta * ratio - lag), corner - o2))


def _residual(delta, args):
    rb1, a, ratio, lag, corner = args
    p = _corner(delta, (a, ratio, lag, corner))
    r = safe_norm(p)
    polar = jnp.arctan2(p[1], p[0])
    target = jnp.arctan2(corner[1], corner[0]) - (
        involute(safe_arccos(rb1 / r)) - involute(safe_arccos(rb1 / safe_norm(corner)))
    )
    return polar - target


def edge_contact_closed_form(pair, lag, *, scan_points: int = 2001, rtol: float = 1e-12, atol: float = 1e-14) -> ClosedFormEdgeContact:
    """First contact of the gear's tip corner on the pinion flank at a constant gear lag.

    Args:
        pair: an `InvoluteGearPair` (transverse section; any helix angle).
        lag: $\\varepsilon \\ge 0$, the gear's lag behind its conjugate position (rad).
        scan_points: grid of the sign scan over one angular pitch before A.
        rtol, atol: Newton tolerances (rad).
    """
    rb1, rb2 = pair.base_radius[..., 0], pair.base_radius[..., 1]
    ra2 = pair.tip_radius[..., 1]
    a = pair.center_distance
    alpha = pair.working_pressure_angle
    rw1 = rb1 / jnp.cos(alpha)
    s_a = a * jnp.sin(alpha) - jnp.sqrt(ra2**2 - rb2**2)
    lam = s_a - rw1 * jnp.sin(alpha)
    corner = jnp.stack([rw1 + lam * jnp.sin(alpha), lam * jnp.cos(alpha)])
    ratio = pair.teeth[0] / pair.teeth[1]
    lag = jnp.asarray(lag, rb1.dtype)
    args = (rb1, a, ratio, lag, corner)
    # Scan from A backwards: the corner is inside the flank at A (residual of one sign) and
    # clear of it one pitch earlier; take the crossing nearest to A.
    pitch = 2 * jnp.pi / pair.teeth[0]
    grid = -pitch * jnp.linspace(0.0, 1.0, scan_points)
    values = jax.vmap(lambda d: _residual(d, args))(grid)
    change = jnp.sign(values[1:]) != jnp.sign(values[:-1])
    i = jnp.argmax(change)
    start = 0.5 * (grid[i] + grid[i + 1])
    sol = optx.root_find(_residual, optx.Newton(rtol=rtol, atol=atol), start, args=args, throw=False)
    delta = sol.value
    r = safe_norm(_corner(delta, (a, ratio, lag, corner)))
    return ClosedFormEdgeContact(
        pinion_rotation=delta,
        radius=r,
        roll_length=jnp.sqrt(r**2 - rb1**2),
        converged=sol.result == optx.RESULTS.successful,
    )
