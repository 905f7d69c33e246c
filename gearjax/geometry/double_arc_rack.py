r"""GB/T 12759-1991 basic rack of double-circular-arc gears (seeds 000 and 003), and the
closed-form envelope of its arcs (`generated_point`, see `double_arc.py`).

**Basic rack** (normal section, multiples of $m_n$; frame: $\xi$ along the pitch line, $\eta$
towards the rack tooth tip, origin on the tooth centre line; the *left* flank $\xi < 0$ is
listed, the right one is its mirror). Each tooth has a convex addendum arc, a transition arc,
a concave dedendum arc and a root arc:

| segment | centre | radius | range |
|---|---|---|---|
| convex | $O_a = (l_a, x_a)$ | $\rho_a$ | $O_a + \rho_a(-\cos t, \sin t)$, $t \in [\delta_1, t_\text{tip}]$ |
| transition | $O_a + (\rho_a + r_j)(-\cos\delta_1, \sin\delta_1)$ | $r_j$ | $A_1 \to F_1$ |
| concave | $O_f = (-\pi/2 - l_f, x_f)$ | $\rho_f$ | $O_f + \rho_f(\cos t, -\sin t)$, $t \in [\delta_2, t_G]$ |
| root | $(-\pi/2, -h_f + r_g)$ | $r_g$ | $G \to$ space centre |

The contact points are at $t = \alpha$ on both working arcs, $h_k = \rho_a\sin\alpha + x_a$
above and $\rho_f\sin\alpha - x_f = h_k$ below the pitch line.

Sources of the rack values (see `GBT12759Rack`): $\alpha$, $\rho_a$, $l_a$, $x_a$ ($e_a$), $j$
and $h_k$ are quoted in seeds 000/003 and reproduce their formula (27) (tested). No copy of
the standard's table was available offline; the concave-arc, transition and root values of
the row $m_n$ > 3–6 mm are **recalled** from the table as reprinted in Chinese handbooks
(机械设计手册, chapter 圆弧圆柱齿轮传动; Shao, *Double Circular Arc Gear*, 1994 = seed ref. [1])
and checked two ways (tests/test_double_arc.py): (1) they satisfy the rack's exact
relations to 1e-4 ($x_f = \rho_f\sin\alpha - h_k$, $l_f = l_a + (\rho_f - \rho_a)\cos\alpha -
j/2$, the heights $h_{ja} = 0.16$, $h_{jf} = 0.20$ of $A_1$ and $F_1$, $r_j$ tangent to the
convex arc at $A_1$ through $F_1$, $r_g$ tangent to the concave arc with its bottom at
$-h_f$); (2) seed 000/003's own impact velocities for $m_n = 4$ imply $\rho_f = 1.41$,
$h_{jf} = 0.20$ (`gearjax.papers.double_arc`). Check them against the standard before relying
on other module rows.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import Array
from .._numerics import rotate2

CONVEX, CONCAVE = 0, 1


def by_arc(arc, convex, concave):
    """`convex` or `concave` (pytrees of one structure) for the arc index `arc`: chosen in
    Python for an int, selected elementwise for an array (a traced zone index: both contact
    zones of a pair analysed in one `vmap`)."""
    if isinstance(arc, int):
        return convex if arc == CONVEX else concave
    return jax.tree_util.tree_map(lambda a, b: jnp.where(arc == CONVEX, a, b), convex, concave)


def _dms(degrees: int, minutes: int, seconds: int) -> float:
    return degrees + minutes / 60.0 + seconds / 3600.0


class GBT12759Rack(eqx.Module):
    """GB/T 12759-1991 basic rack, multiples of $m_n$ (row $m_n$ > 3–6 mm).

    Sources: `pressure_angle_deg`, `convex_radius`, `convex_centre_offset`,
    `convex_centre_shift`, `backlash`: quoted in seeds 000/003 (they reproduce formula 27).
    All others: recalled from the standard's table 1 as reprinted in handbooks, not checked
    against a copy; verified only through the exact relations of the rack
    (`relation_residuals`) and the seed's velocities (module docstring).
    """

    pressure_angle_deg: float = eqx.field(static=True, default=24.0)  # alpha (seed)
    convex_radius: float = eqx.field(static=True, default=1.3)  # rho_a (seed)
    convex_centre_offset: float = eqx.field(static=True, default=0.6289)  # l_a (seed)
    convex_centre_shift: float = eqx.field(static=True, default=0.0163)  # x_a = e_a (seed)
    backlash: float = eqx.field(static=True, default=0.06)  # j (seed)
    concave_radius: float = eqx.field(static=True, default=1.41)  # rho_f (recalled; seed velocities)
    concave_centre_offset: float = eqx.field(static=True, default=0.6994)  # l_f (recalled)
    concave_centre_shift: float = eqx.field(static=True, default=0.0285)  # x_f = e_f (recalled)
    addendum: float = eqx.field(static=True, default=0.9)  # h_a (recalled)
    dedendum: float = eqx.field(static=True, default=1.1)  # h_f (recalled)
    convex_process_angle_deg: float = eqx.field(static=True, default=_dms(6, 20, 52))  # delta_1 (recalled)
    concave_process_angle_deg: float = eqx.field(static=True, default=_dms(9, 19, 30))  # delta_2 (recalled)
    transition_radius: float = eqx.field(static=True, default=0.5043)  # r_j (recalled)
    root_radius: float = eqx.field(static=True, default=0.4004)  # r_g (recalled)

    @property
    def alpha(self) -> float:
        return math.radians(self.pressure_angle_deg)

    @property
    def contact_height(self) -> float:
        """$h_k = \\rho_a\\sin\\alpha + e_a$ (multiples of $m_n$)."""
        return self.convex_radius * math.sin(self.alpha) + self.convex_centre_shift

    @property
    def convex_centre(self) -> tuple[float, float]:
        """$O_a = (l_a, x_a)$."""
        return (self.convex_centre_offset, self.convex_centre_shift)

    @property
    def concave_centre(self) -> tuple[float, float]:
        """$O_f = (-\\pi/2 - l_f, x_f)$."""
        return (-0.5 * math.pi - self.concave_centre_offset, self.concave_centre_shift)

    @property
    def convex_junction_height(self) -> float:
        """$h_{ja} = x_a + \\rho_a\\sin\\delta_1$: height of $A_1$ (convex/transition)."""
        return self.convex_centre_shift + self.convex_radius * math.sin(math.radians(self.convex_process_angle_deg))

    @property
    def concave_junction_depth(self) -> float:
        """$h_{jf} = \\rho_f\\sin\\delta_2 - x_f$: depth of $F_1$ (transition/concave), the
        seed's "concave tooth connection point high"."""
        return self.concave_radius * math.sin(math.radians(self.concave_process_angle_deg)) - self.concave_centre_shift

    @property
    def tip_angle(self) -> float:
        """$t_\\text{tip}$ of the convex arc at the tip line $\\eta = h_a$ (rad)."""
        return math.asin((self.addendum - self.convex_centre_shift) / self.convex_radius)

    @property
    def root_centre(self) -> tuple[float, float]:
        return (-0.5 * math.pi, -self.dedendum + self.root_radius)

    @property
    def root_junction_angle(self) -> float:
        """$t_G$ where the root arc touches the concave arc internally (rad)."""
        cx, cy = self.concave_centre
        gx, gy = self.root_centre
        return math.atan2(-(gy - cy), gx - cx)

    @property
    def transition_centre(self) -> tuple[float, float]:
        d1 = math.radians(self.convex_process_angle_deg)
        r = self.convex_radius + self.transition_radius
        return (self.convex_centre_offset - r * math.cos(d1), self.convex_centre_shift + r * math.sin(d1))

    def relation_residuals(self) -> dict[str, float]:
        """Residuals of the rack's exact relations (multiples of $m_n$); all ~1e-4 or less
        when the recalled values are consistent."""
        a = self.alpha
        hk = self.contact_height
        d2 = math.radians(self.concave_process_angle_deg)
        cx, cy = self.concave_centre
        f1 = (cx + self.concave_radius * math.cos(d2), cy - self.concave_radius * math.sin(d2))
        tx, ty = self.transition_centre
        gx, gy = self.root_centre
        return {
            "x_f = rho_f sin(alpha) - h_k": self.concave_centre_shift - (self.concave_radius * math.sin(a) - hk),
            "l_f = l_a + (rho_f - rho_a) cos(alpha) - j/2": self.concave_centre_offset
            - (self.convex_centre_offset + (self.concave_radius - self.convex_radius) * math.cos(a) - 0.5 * self.backlash),
            "h_ja = 0.16": self.convex_junction_height - 0.16,
            "h_jf = 0.20": self.concave_junction_depth - 0.20,
            "r_j through F1": math.hypot(f1[0] - tx, f1[1] - ty) - self.transition_radius,
            "r_g tangent to the concave arc": math.hypot(gx - cx, gy - cy) - (self.concave_radius - self.root_radius),
        }

    def flank(self, samples: int = 40) -> np.ndarray:
        """Left flank of the normal-section rack from the tip to the space centre, (n, 2),
        multiples of $m_n$ (for drawings)."""
        a, c = self.convex_centre, self.concave_centre
        d1 = math.radians(self.convex_process_angle_deg)
        d2 = math.radians(self.concave_process_angle_deg)
        t = np.linspace(self.tip_angle, d1, samples)
        convex = np.stack([a[0] - self.convex_radius * np.cos(t), a[1] + self.convex_radius * np.sin(t)], -1)
        tx, ty = self.transition_centre
        f1 = np.array([c[0] + self.concave_radius * math.cos(d2), c[1] - self.concave_radius * math.sin(d2)])
        start = math.atan2(convex[-1, 1] - ty, convex[-1, 0] - tx)
        end = math.atan2(f1[1] - ty, f1[0] - tx)
        s = np.linspace(start, end, samples)
        transition = np.stack([tx + self.transition_radius * np.cos(s), ty + self.transition_radius * np.sin(s)], -1)
        t = np.linspace(d2, self.root_junction_angle, samples)
        concave = np.stack([c[0] + self.concave_radius * np.cos(t), c[1] - self.concave_radius * np.sin(t)], -1)
        gx, gy = self.root_centre
        s = np.linspace(math.atan2(concave[-1, 1] - gy, concave[-1, 0] - gx), -0.5 * math.pi, samples)
        root = np.stack([gx + self.root_radius * np.cos(s), gy + self.root_radius * np.sin(s)], -1)
        tip = np.array([[0.0, self.addendum]])
        return np.concatenate([tip, convex, transition, concave, root])


def generated_point(centre, radius, theta, pitch_radius, helix_angle) -> tuple[Array, Array]:
    """Envelope of a rack arc (module docstring): the gear-frame point generated by the
    rack point of polar angle `theta` (rad) on the arc of `centre` (mm, normal section) and
    `radius` (mm), and the pitch-point position $\\xi_I$ (mm, transverse) on the rack."""
    cb = jnp.cos(helix_angle)
    cot = jnp.cos(theta) / jnp.sin(theta)
    p_xi = (centre[0] + radius * jnp.cos(theta)) / cb
    p_eta = centre[1] + radius * jnp.sin(theta)
    xi_pitch = p_xi - p_eta * cb * cot
    plane = jnp.stack([pitch_radius + p_eta, -p_eta * cb * cot], -1)
    return rotate2(-xi_pitch / pitch_radius, plane), xi_pitch
