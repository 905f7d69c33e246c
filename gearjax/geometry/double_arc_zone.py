r"""One contact zone of a double-circular-arc pair as a flank pair for the general TCA.

The pair's geometry and the zones' meaning: `double_arc.py`.
"""

from __future__ import annotations

from typing import ClassVar

import jax.numpy as jnp
import numpy as np

from .._custom_types import Array, ArrayLike, Float, Scalar
from .._numerics import as_float
from .._validate import is_concrete
from ._base import (
    AbstractFlankPair,
    AbstractGearPair,
    generic_profile_normal,
    generic_profile_tangent,
    generic_slice_point,
    generic_slice_point_tangent,
    generic_transverse_normal_fraction,
)
from .double_arc_rack import CONCAVE, CONVEX, by_arc

class DoubleArcZone(AbstractFlankPair):
    """The drive flanks of one contact zone of a `DoubleArcGearPair`: the pinion's convex
    addendum on the gear's concave dedendum (`zone` 0, convex driving tooth) or the
    pinion's concave dedendum on the gear's convex addendum (`zone` 1).

    Attributes:
        gears: the `DoubleArcGearPair` (typed by its base: the pair's module builds its
            zones, so this one does not import it).
        zone: 0 or 1; an integer array under `vmap` over the zones
            (`DoubleArcGearPair.contact_zone`).
    """

    gears: AbstractGearPair
    zone: int | Array

    #: Not conjugate: no plane-of-action fast path; edges are screened by the window only.
    conjugate_slices: ClassVar[bool] = False
    screen_edges: ClassVar[bool] = False
    linear_lead: ClassVar[bool] = True
    #: A zone alone has no loaded contact: the pair's loaded contact shares the torque
    #: between both zones' pairs (`gearjax.ltca.point_analysis`).
    supported_effects: ClassVar[frozenset[str]] = frozenset()
    effects_note: ClassVar[str] = "load the DoubleArcGearPair, whose loaded contact covers both zones"
    #: Half-width (rad of pinion rotation) of the window around the contact instant in
    #: which a slice of a tooth pair is analysed (~0.1 rad holds every slice whose gap is
    #: below ~1.5 mm of pitch-circle arc).
    contact_window: ClassVar[float] = 0.1

    def __check_init__(self):
        if is_concrete(self.zone) and not np.isin(np.asarray(self.zone), (CONVEX, CONCAVE)).all():
            raise ValueError(f"zone must be 0 (convex driving) or 1 (concave driving); got {self.zone!r}")

    @property
    def teeth(self) -> tuple[int, int]:
        return self.gears.teeth

    @property
    def face_width(self) -> Scalar:
        return self.gears.face_width

    @property
    def derived(self) -> dict[str, Array] | None:
        """The pair's resolved quantities (a zone has none of its own)."""
        return self.gears.derived

    def resolve(self) -> DoubleArcZone:
        return DoubleArcZone(self.gears.resolve(), self.zone)

    # The arcs have no closed-form flank in 3-D: the generic forms differentiate the
    # profile and lead.
    def profile_tangent(self, gear: int, u: ArrayLike):
        return generic_profile_tangent(self, gear, u)

    def profile_normal(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        return generic_profile_normal(self, gear, u)

    def transverse_normal_fraction(self, gear: int, u: ArrayLike, z: ArrayLike) -> Scalar:
        return generic_transverse_normal_fraction(self, gear, u, z)

    def slice_point(self, gear: int, u: ArrayLike, z: ArrayLike, slice_rotation: ArrayLike,
                    depth: ArrayLike = 0.0) -> Float[Array, "2"]:
        return generic_slice_point(self, gear, u, z, slice_rotation, depth)

    def slice_point_tangent(self, gear: int, u: ArrayLike, z: ArrayLike, slice_rotation: ArrayLike, depth=None):
        return generic_slice_point_tangent(self, gear, u, z, slice_rotation, depth)

    @property
    def center_distance(self) -> Scalar:
        return self.gears.center_distance

    @property
    def root_radius(self) -> Float[Array, "2"]:
        return self.gears.root_radius

    def geometry_report(self) -> dict[str, ArrayLike]:
        return self.gears.geometry_report()

    def arc(self, gear: int) -> int | Array:
        """Working arc of `gear` in this zone: CONVEX (0) or CONCAVE (1)."""
        return self.zone if gear == 0 else 1 - self.zone

    # ------------------------------------------------------------------ family interface
    def profile(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        return self.gears.arc_point(gear, self.arc(gear), u)

    def profile_limits(self, gear: int) -> tuple[Scalar, Scalar]:
        return self.gears.arc_limits(self.arc(gear))

    def parameter_domain(self, gear: int) -> tuple[Scalar, Scalar]:
        return self.gears.arc_domain(self.arc(gear))

    def lead_rotation(self, gear: int, z: ArrayLike) -> Scalar:
        return self.gears.lead_rotation(gear, z)

    def placement(self, gear: int) -> Scalar:
        return self.gears.placement(gear)

    def action_radius(self, gear: int) -> Scalar:
        return self.gears.action_radius(gear)

    def relief_coordinates(self, gear: int) -> tuple[Scalar, Scalar]:
        return self.profile_limits(gear)

    def contact_instant(self) -> Scalar:
        """Pinion slice rotation (rad) at which this zone's rack contact points meet on the
        common normal through the pitch point: 0 for the convex driving zone, and
        $(\\xi_{I,f} - \\xi_{I,a})/R_1$ for the concave one (the pitch-line points of the two
        contact normals differ, which is why the zones lie $q_{TA}$ apart along the face)."""
        gears = self.gears
        concave = (gears.pitch_point(CONCAVE) - gears.pitch_point(CONVEX)) / gears.pitch_radius[..., 0]
        return by_arc(self.arc(0), jnp.zeros_like(gears.normal_module), concave)

    def contact_guess(self, angle: ArrayLike) -> tuple[Scalar, Scalar]:
        """The rack contact points ($t = \\alpha$) within `contact_window` of the zone's
        `contact_instant`, far off the flanks beyond it (no contact of this tooth pair).

        Both racks generate their whole working arcs within a few milliradians of the
        instant, so the generated points are no guide; the slice tangency itself stays
        near the contact points for ~0.02 rad and reaches the arc ends by ~0.05 rad, so
        the contact points are the start for every slice of the window."""
        angle = as_float(angle)
        near = jnp.abs(angle - self.contact_instant()) < self.contact_window
        far = 1e3 * self.gears.normal_module
        u1 = self.gears.contact_parameter(self.arc(0))
        u2 = self.gears.contact_parameter(self.arc(1))
        return jnp.where(near, u1, u1 + far), jnp.where(near, u2, u2 + far)

    def parameter_at_radius(self, gear: int, radius: ArrayLike) -> Scalar:
        """From $r \\approx R + p_\\eta$: $\\sin\\theta = (r - R - C_\\eta)/\\rho$ on the arc."""
        gears = self.gears
        arc = self.arc(gear)
        centre, rho = gears._arc_data(arc)
        s = jnp.clip((as_float(radius) - gears.pitch_radius[..., gear] - centre[1]) / rho, -0.999, 0.999)
        t = by_arc(arc, jnp.arcsin(s), -jnp.arcsin(s))
        lo, hi = self.parameter_domain(gear)
        return jnp.clip(gears._u(arc, t), lo, hi)
