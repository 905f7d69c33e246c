r"""Seeds 000/003: the four meshing-impact states of double-circular-arc gears, a closed-form
model. Imports the core; nothing in the core imports it.

**The four meshing-impact states** (seed section 3.1, `four_state_impact`): concave or convex
driving tooth × $t_1 < t_2$ or $t_1 > t_2$. Each state is the same computation on
state-specific points: find the rotation $\varphi$ at which an arc of radius
$\rho_{AV} = (\rho_a + \rho_f)/2$ about one gear's arc centre $A$ (on its pitch circle)
reaches the mate's edge point $B$ at depth $h_{jf}$ ("reverse method"), then the impact
radius is the distance from the pitch point to the line $AB$ (formula 15) and
$v_s = PE\,(\omega_1 + \omega_2)$ (formula 4), with the pinion speed in rad/s (the seed's rpm only
through `speed_rpm=`). The four states run as one batched function
(the state is an array index), differentiable through the root by the implicit function
theorem. Repairs of the printed formulas (each cited again where it is applied):

* (10): the angle defined by the arccos is called $a$ and then used as $\alpha$ in
  $\gamma = \alpha - \delta$; it is the same angle (not the 24° pressure angle).
* (12): the left side is $|AB|^2$, so the right side is $\rho_{AV}^2$, not $\rho_{AV}$ (11).
* (22): $r$ in $l_\tau$ is the convex arc radius $\rho_a m_n$.
* (23): $\Delta$ is missing, so the printed state would not depend on the pitch error
  (contradicting the seed's conclusion 3); the gear's edge point is turned back by
  $\Delta/R_2$: $B$ at angle $\theta + \varphi_2 - \Delta/R_2$ (the other sign gives no contact
  at all), and the condition $|AB| = \rho_{AV}$ (absent) is the one of the other states.
* (25): the line through $A$ and $B$ meets $x = 0$ at $y_A - x_A(y_B - y_A)/(x_B - x_A)$; the
  printed sign of the second term is wrong.
* (26): $P'E = |Y_{P'}|\cos 24°$ takes the line $AB$ at exactly the pressure angle; the
  exact distance (formula 15) is reported beside it (`exact_radius`).

The rack values $\rho_f = 1.41$ and $h_{jf} = 0.20$ are the recalled GB/T 12759 values
(`gearjax.geometry.double_arc.GBT12759Rack`); states 0 and 1 reproduce the seed's velocities with them,
and jointly solving those two states for $(\rho_f, h_{jf})$ gives (1.4098, 0.2000): the
comparison for states 0 and 1 is therefore a consistency check of the recalled rack, not an
independent reproduction. States 2 and 3 are independent of that back-calculation.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx

from .._custom_types import Array, ArrayLike
from .._numerics import as_float
from .._validate import check_range
from ..geometry.double_arc import DoubleArcGearPair
from ..units import rpm_to_rad_per_s


#: States of seed section 3.1, in the order of Tables 1–2's columns per tooth kind.
STATES = (
    "concave driving, t1 < t2",  # 3.1.1
    "concave driving, t1 > t2",  # 3.1.2
    "convex driving, t1 < t2",  # 3.1.3
    "convex driving, t1 > t2",  # 3.1.4
)
#: Impact velocities of the seed's tables for the four states (mm/s) and the radii they
#: imply, PE = v_s/(omega_1 + omega_2) at 200 rpm, i = 1 (mm).
SEED_VELOCITIES = (61.92, 81.57, 36.33, 60.01)
#: The seed's pinion speed as it prints it (rpm) and in the engine's unit (rad/s).
SEED_SPEED_RPM = 200.0
SEED_PINION_SPEED = SEED_SPEED_RPM * (2.0 * math.pi / 60.0)
#: The seed's pitch-circle error $\Delta$ (mm).
SEED_PITCH_CIRCLE_ERROR = 0.1


class FourStateResult(eqx.Module):
    r"""Impact radius and velocity of the four states (arrays over the state axis).

    Attributes:
        rotation: the root $\varphi$ of the reverse method (rad).
        radius: impact radius $PE$ / $P'E$ as the seed computes it (mm): formula (15), and
            formula (26) for state 3.
        exact_radius: the exact point–line distance (15) for every state (mm).
        velocity: $v_s = $ `radius` $(\omega_1 + \omega_2)$ (mm/s).
        start_point: $B$ (states 0, 1) or $A$ (states 2, 3), the impact start point, in the
            state's frame (mm).
    """

    rotation: Array
    radius: Array
    exact_radius: Array
    velocity: Array
    start_point: Array


def _distance(p, a, b):
    """Formula (15): distance from `p` to the line through `a` and `b`."""
    d = b - a
    return jnp.abs(d[0] * (p[1] - a[1]) - d[1] * (p[0] - a[0])) / jnp.sqrt(d[0] ** 2 + d[1] ** 2)


def _law_of_cosines(r, h, side):
    """Angle at the centre between radius `r` and radius `r - h` whose ends are `side` apart."""
    return jnp.arccos((r**2 + (r - h) ** 2 - side**2) / (2.0 * r * (r - h)))


def _state_points(state, phi, g):
    """The points $A$, $B$ and the reference point $P$ of every state at rotation `phi`;
    `g` holds the geometry. One function of the state index (selected, not branched)."""
    r1, r2, i, rho, h, hk, delta = g["r1"], g["r2"], g["i"], g["rho"], g["h_jf"], g["h_k"], g["delta"]
    d1 = delta / r1
    pitch = jnp.stack([-r1 * jnp.sin(phi), r1 * jnp.cos(phi)])
    # 3.1.1, formulas (9)-(10) [repair: the arccos angle a is the "alpha" of gamma = alpha - delta]
    g0 = _law_of_cosines(r1, h, rho) - d1
    a0 = jnp.stack([-(r1 + r2) * jnp.sin(phi) + r2 * jnp.sin(phi + phi / i), (r1 + r2) * jnp.cos(phi) - r2 * jnp.cos(phi + phi / i)])
    b0 = (r1 - h) * jnp.stack([jnp.sin(g0), jnp.cos(g0)])
    # 3.1.2, formulas (17)-(20): P' is where the line from C through B meets x = 0
    g1 = _law_of_cosines(r1, hk, rho) - phi - d1
    a1 = jnp.stack([-r2 * jnp.sin(phi / i), (r1 + r2) - r2 * jnp.cos(phi / i)])
    b1 = (r1 - h) * jnp.stack([jnp.sin(g1), jnp.cos(g1)])
    c1 = r1 * jnp.stack([-jnp.sin(d1 + phi), jnp.cos(d1 + phi)])
    p1 = jnp.stack([jnp.zeros_like(phi), c1[1] - (b1[1] - c1[1]) / (b1[0] - c1[0]) * c1[0]])
    # 3.1.3, formulas (21)-(22) [repair: r in l_tau is the convex radius rho_a m_n]
    theta = _law_of_cosines(r2, h, rho)
    rj, ra, s1 = g["r_j"], g["rho_a"], g["sin_delta1"]
    l_tau = jnp.sqrt(2 * rj**2 - 2 * rj**2 * jnp.cos(jnp.arcsin(((ra + rj) * s1 + h) / rj) - jnp.arcsin((ra + rj) * s1 / rj)))
    tau = _law_of_cosines(r2, h, l_tau)
    g2 = (theta + tau) * i - d1
    a2 = jnp.stack([-(r1 + r2) * jnp.sin(phi) + (r2 - h) * jnp.sin(phi + phi / i + tau), (r1 + r2) * jnp.cos(phi) - (r2 - h) * jnp.cos(phi + phi / i + tau)])
    b2 = r1 * jnp.stack([jnp.sin(g2), jnp.cos(g2)])
    # 3.1.4, formulas (23)-(24) [repair: B turned back by Delta/R2, which the print lost]
    a3 = jnp.stack([r1 * jnp.sin(phi), r1 * jnp.cos(phi) - r1])
    g3 = theta + phi / i - delta / r2
    b3 = jnp.stack([(r2 - h) * jnp.sin(g3), r2 - (r2 - h) * jnp.cos(g3)])
    p3 = jnp.zeros(2, dtype=a3.dtype)
    pick = lambda *xs: jnp.stack(xs)[state]  # noqa: E731
    return pick(a0, a1, a2, a3), pick(b0, b1, b2, b3), pick(pitch, p1, pitch, p3)


def _residual(phi, args):
    r"""Formulas (11)/(12), (18), (21) and the repaired (23): $|AB|^2 - \rho_{AV}^2$ [repair
    of (12): squared radius]."""
    state, g = args
    a, b, _ = _state_points(state, phi, g)
    return jnp.sum((a - b) ** 2) - g["rho"] ** 2


def _root(state, g):
    """The reverse method's rotation: the smallest positive root (states 0, 1, 3: the gear
    rolls back until it meets the edge), the root of smallest magnitude for state 2; found
    on a grid of [-0.4, 0.4] rad and polished by Newton (implicit gradients)."""
    grid = jnp.linspace(-0.4, 0.4, 1601)
    values = jax.vmap(lambda p: _residual(p, (state, jax.lax.stop_gradient(g))))(grid)
    change = (values[:-1] * values[1:] < 0) & jnp.isfinite(values[:-1]) & jnp.isfinite(values[1:])
    left, right = grid[:-1], grid[1:]
    root = left - values[:-1] * (right - left) / (values[1:] - values[:-1])
    score = jnp.where(state == 2, jnp.abs(root), jnp.where(root > 0, root, jnp.inf))
    start = root[jnp.argmin(jnp.where(change, score, jnp.inf))]
    sol = optx.root_find(_residual, optx.Newton(rtol=1e-13, atol=1e-13), start, args=(state, g), max_steps=50, throw=False)
    return sol.value


def four_state_geometry(pair: DoubleArcGearPair, pitch_circle_error: ArrayLike) -> dict:
    r"""Inputs of the four-state model for a `DoubleArcGearPair` (mm): pitch radii, ratio,
    $\rho_{AV}$, $h_{jf}$, $h_k$, $r_j$, $\rho_a$, $\sin\delta_1$ and the pitch-circle error
    $\Delta = \Delta_\alpha\tan\beta$ (formula 10)."""
    check_range("pitch_circle_error", pitch_circle_error, 0.0, None, low_inclusive=False, unit="mm")
    rack = pair.rack
    m = pair.normal_module
    radii = pair.pitch_radius
    return {
        "r1": radii[..., 0], "r2": radii[..., 1], "i": jnp.asarray(pair.teeth[1] / pair.teeth[0], dtype=m.dtype),
        "rho": 0.5 * (rack.convex_radius + rack.concave_radius) * m, "h_jf": rack.concave_junction_depth * m,
        "h_k": rack.contact_height * m, "r_j": rack.transition_radius * m, "rho_a": rack.convex_radius * m,
        "sin_delta1": jnp.asarray(math.sin(math.radians(rack.convex_process_angle_deg)), dtype=m.dtype),
        "delta": as_float(pitch_circle_error),
    }


def four_state_impact(
    pair: DoubleArcGearPair,
    pitch_circle_error: ArrayLike,
    speed: ArrayLike | None = None,
    *,
    speed_rpm: ArrayLike | None = None,
    states=(0, 1, 2, 3),
) -> FourStateResult:
    r"""Seed 000/003's impact radius and velocity for the given states (module docstring):
    one function of the state index, `vmap`-ed over `states`.

    Args:
        pair: the double-circular-arc pair.
        pitch_circle_error: $\Delta > 0$ (mm), the magnitude; its sign is the state's
            ($t_1 < t_2$ or $t_1 > t_2$).
        speed: pinion speed $\omega_1$ (rad/s, the engine's unit); $\omega_2 = \omega_1/i$.
        speed_rpm: the pinion speed in rev/min instead (the seed's unit); give exactly one of
            `speed` and `speed_rpm`.
        states: indices into `STATES`.
    """
    if (speed is None) == (speed_rpm is None):
        raise ValueError("give exactly one of speed (rad/s) and speed_rpm (rev/min); got "
                         f"speed={speed!r}, speed_rpm={speed_rpm!r}")
    if speed is None:
        check_range("speed_rpm", speed_rpm, 0.0, None, low_inclusive=False, unit="rpm")
        omega1 = rpm_to_rad_per_s(as_float(speed_rpm))
    else:
        check_range("speed", speed, 0.0, None, low_inclusive=False, unit="rad/s")
        omega1 = as_float(speed)
    g = four_state_geometry(pair, pitch_circle_error)
    omega = omega1 * (1.0 + 1.0 / g["i"])

    def one(state):
        phi = _root(state, g)
        a, b, p = _state_points(state, phi, g)
        exact = _distance(p, a, b)
        # (26) for state 3: |Y_P'| cos 24 deg with Y_P' on the repaired line (25)
        y_p = a[1] - a[0] * (b[1] - a[1]) / (b[0] - a[0])
        seed = jnp.where(state == 3, jnp.abs(y_p) * math.cos(math.radians(pair.rack.pressure_angle_deg)), exact)
        start = jnp.where(state < 2, b, a)
        return phi, seed, exact, start

    phi, radius, exact, start = jax.vmap(one)(jnp.asarray(states))
    return FourStateResult(rotation=phi, radius=radius, exact_radius=exact, velocity=radius * omega, start_point=start)
