r"""Involute curvilinear-tooth cylindrical gears (seed 002).

Every transverse section is an involute spur profile; along the face the sections are
displaced along the base circle so that the tooth trace is a circular arc of radius $R_t$
in the pitch plane. Seed 002's surface (its formulas 5 and 7) is

$$x = R_b(\sin\theta_t - \varphi\cos\theta_t),\quad y = R_b(\cos\theta_t + \varphi\sin\theta_t),
\quad z = h,\qquad \varphi = \frac{R_b\theta_t + \sqrt{R_t^2 - h^2} - R_t}{R_b},$$

i.e. the section at $z = h$ is the involute turned by $-d(h)/R_b$ with the lead displacement

$$d(h) = R_t - \sqrt{R_t^2 - h^2} = \frac{h^2}{R_t + \sqrt{R_t^2 - h^2}}\quad(\text{the second
form has no cancellation as } R_t\to\infty),\qquad |h| \le b/2 < R_t .$$

Pinion and gear get the same displacement $d$ along their base circles (convex and concave
arcs of the same radius), so each section pair is conjugate and the contact is a line: on
the plane of action, at roll length $s_1 = r_{b1}(\tan\alpha_{wt} + \varphi_1) - d(z)$ — an arc
of radius $R_t$, of length $L = 2R_t\arcsin(b/2R_t)$ when the whole face is in mesh (seed
002, eq. 18), which tends to $b$ as $R_t\to\infty$ (spur gear) and to $\pi b/2$ as
$R_t\to b/2$. The flank normal leans by the local trace angle: $|n_t| =
1/\sqrt{1 + d'(z)^2} = \sqrt{R_t^2 - z^2}/R_t$.
"""

from __future__ import annotations

from typing import ClassVar

import jax.numpy as jnp

from .._custom_types import ArrayLike, Scalar
from .._numerics import as_float
from .._validate import check_range, is_concrete
from ._base import SceneFileSpec
from .involute_checks import SECTION_SCENE_KEYS
from .involute_section import AbstractInvolutePair


class CurvilinearGearPair(AbstractInvolutePair):
    """External involute curvilinear-tooth (arc tooth trace) cylindrical gear pair.

    >>> pair = CurvilinearGearPair((20, 30), normal_module=2.0, pressure_angle_deg=20.0,
    ...                            face_width=20.0, tooth_trace_radius=12.0)

    The sections are spur involutes: the module is the normal (= transverse) module, and
    the helix angle is zero.

    Attributes (besides those of `AbstractInvolutePair`):
        tooth_trace_radius: $R_t > b/2$, radius of the circular tooth trace (mm).
    """

    #: The lead is curved: the TCA refines the peak between slices for flank contacts only.
    linear_lead: ClassVar[bool] = False
    scene_file: ClassVar[SceneFileSpec] = SceneFileSpec(
        "curvilinear", "involute curvilinear-tooth gear pair",
        {**SECTION_SCENE_KEYS, "tooth_trace_radius": ("tooth_trace_radius", "number", "mm", 1.0)},
    )

    tooth_trace_radius: Scalar

    def __init__(
        self,
        teeth: tuple[int, int],
        normal_module: ArrayLike,
        pressure_angle_deg: ArrayLike = 20.0,
        face_width: ArrayLike = 20.0,
        tooth_trace_radius: ArrayLike = 12.0,
        profile_shift: ArrayLike = (0.0, 0.0),
        center_distance: ArrayLike | None = None,
        *,
        addendum_coefficient: ArrayLike = 1.0,
        dedendum_coefficient: ArrayLike = 1.25,
        root_radius_coefficient: ArrayLike = 0.38,
    ):
        check_range("face_width", face_width, 0.0, None, low_inclusive=False, unit="mm")
        check_range("tooth_trace_radius", tooth_trace_radius, 0.0, None, low_inclusive=False, unit="mm")
        radius = as_float(tooth_trace_radius)
        width = as_float(face_width)
        if is_concrete(radius, width) and bool(jnp.any(radius <= 0.5 * width)):
            raise ValueError(
                f"tooth_trace_radius must be > b/2 = {float(jnp.max(0.5 * width)):.4f} mm (the arc "
                f"tooth trace must span the face width); got {jnp.asarray(radius)} mm"
            )
        self._init_section(
            teeth,
            normal_module,
            pressure_angle_deg,
            0.0,
            face_width,
            profile_shift,
            addendum_coefficient,
            dedendum_coefficient,
            root_radius_coefficient,
        )
        self.tooth_trace_radius = radius
        self._check_section(center_distance)

    def lead_displacement(self, z: ArrayLike) -> Scalar:
        """$d(z) = z^2/(R_t + \\sqrt{R_t^2 - z^2})$ (mm), along the base circles."""
        z = as_float(z)
        r = self.tooth_trace_radius
        return z * z / (r + jnp.sqrt(r * r - z * z))

    def lead_rotation(self, gear: int, z: ArrayLike) -> Scalar:
        """$\\psi_i(z) = -d(z)/r_{bi}$ (rad, in each gear's turning sense)."""
        return -self.lead_displacement(z) / self.base_radius[..., gear]

    def transverse_normal_fraction(self, gear: int, u: ArrayLike, z: ArrayLike) -> Scalar:
        """$|n_t| = \\sqrt{R_t^2 - z^2}/R_t$ (the local tooth-trace angle)."""
        z = as_float(z)
        r = self.tooth_trace_radius
        shape = jnp.broadcast_shapes(jnp.shape(u), jnp.shape(z))
        return jnp.broadcast_to(jnp.sqrt(r * r - z * z) / r, shape)

    def geometry_report(self) -> dict[str, ArrayLike]:
        return {
            **self._section_report(),
            "tooth_trace_radius_mm": self.tooth_trace_radius,
            "contact_line_length_mm": self.contact_line_length,
        }

    @property
    def contact_line_length(self) -> Scalar:
        """$L = 2R_t\\arcsin(b/2R_t)$ (mm), seed 002 eq. 18, whole face in mesh."""
        r = self.tooth_trace_radius
        return 2.0 * r * jnp.arcsin(0.5 * self.face_width / r)
