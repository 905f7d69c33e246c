r"""Double-circular-arc gears, GB/T 12759-1991 (seeds 000 and 003): basic rack and the
axial meshing facts of seed 003's formulas (27)–(28).

Only the rack constants that fix the contact points and the axial meshing quantities are
here; the generated tooth surfaces (convex addendum, concave dedendum, transition arcs)
and their TCA are not implemented yet.

Rack values (multiples of $m_n$) and their source:

* $\alpha = 24°$, $\rho_a = 1.3$, $l_a = 0.6289$, $e_a = 0.0163$ (the seed's name for the
  standard's $x_a$), $j = 0.06$: GB/T 12759-1991 table 1 as quoted in seeds 000/003 and
  DESIGN.md; they reproduce formula (27) for the seed case (tests/test_double_arc.py).
* $h_k = \rho_a\sin\alpha + e_a = 0.545$: the contact-point height, derived.
* The concave-arc, transition and fillet values ($\rho_f$, $l_f$, $e_f$, $h_a$, $h_f$,
  $h_{jf}$, $r_j$) are **not** included: no copy of the standard was available offline; values
  recalled from handbooks and back-calculated from the seed's velocities ($\rho_f = 1.41$,
  $h_{jf} = 0.20$ for $m_n$ 3–6) need checking against the standard first.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp

from .._custom_types import ArrayLike, Scalar
from .._numerics import as_float
from .._validate import check_range


class GBT12759Rack(eqx.Module):
    """Convex-tooth part of the GB/T 12759-1991 basic rack, as multiples of $m_n$ (see the
    module docstring for sources)."""

    pressure_angle_deg: float = eqx.field(static=True, default=24.0)
    convex_radius: float = eqx.field(static=True, default=1.3)  # rho_a
    convex_centre_offset: float = eqx.field(static=True, default=0.6289)  # l_a
    convex_centre_shift: float = eqx.field(static=True, default=0.0163)  # e_a (x_a)
    backlash: float = eqx.field(static=True, default=0.06)  # j

    @property
    def contact_height(self) -> float:
        """$h_k = \\rho_a\\sin\\alpha + e_a$ (multiples of $m_n$)."""
        return self.convex_radius * math.sin(math.radians(self.pressure_angle_deg)) + self.convex_centre_shift


class AxialMeshing(eqx.Module):
    """Seed 003, formulas (27)–(28) (mm).

    Attributes:
        axial_pitch: $P_x = \\pi m_n/\\sin\\beta$.
        convex_to_concave: $q_{TA}$, axial distance from the convex-flank contact point to
            the concave-flank contact point of the same tooth.
        concave_to_convex: $q'_{TA} = P_x - q_{TA}$ (to the neighbouring tooth).
        face_excess: $\\Delta b = b - P_x$.
        condition_28: $\\Delta b < P_x - q_{TA}$, the meshing case the seed analyses
            (three meshing points, $n = 3$).
    """

    axial_pitch: Scalar
    convex_to_concave: Scalar
    concave_to_convex: Scalar
    face_excess: Scalar
    condition_28: jnp.ndarray


def axial_meshing(normal_module: ArrayLike, helix_angle_deg: ArrayLike, face_width: ArrayLike, rack: GBT12759Rack = GBT12759Rack()) -> AxialMeshing:
    r"""Formula (27): $P_x = \pi m_n/\sin\beta$, $\Delta b = b - P_x$,

    $$q_{TA} = \frac{0.5\pi m_n - 0.5j + 2l_a + 2e_a\cot\alpha}{\sin\beta}
    - 2\Big(\rho_a + \frac{e_a}{\sin\alpha}\Big)\cos\alpha\sin\beta,$$

    $q'_{TA} = P_x - q_{TA}$; formula (28) is the case $\Delta b < P_x - q_{TA}$.
    """
    check_range("normal_module", normal_module, 0.0, 100.0, low_inclusive=False, unit="mm")
    check_range("helix_angle_deg", helix_angle_deg, 0.0, 45.0, low_inclusive=False, high_inclusive=False, unit="deg")
    check_range("face_width", face_width, 0.0, None, low_inclusive=False, unit="mm")
    m = as_float(normal_module)
    beta = as_float(helix_angle_deg) * (math.pi / 180.0)
    b = as_float(face_width)
    alpha = math.radians(rack.pressure_angle_deg)
    la, ea, ra, j = (m * v for v in (rack.convex_centre_offset, rack.convex_centre_shift, rack.convex_radius, rack.backlash))
    px = math.pi * m / jnp.sin(beta)
    q = (0.5 * math.pi * m - 0.5 * j + 2 * la + 2 * ea / math.tan(alpha)) / jnp.sin(beta) - 2 * (
        ra + ea / math.sin(alpha)
    ) * math.cos(alpha) * jnp.sin(beta)
    excess = b - px
    return AxialMeshing(px, q, px - q, excess, excess < px - q)
