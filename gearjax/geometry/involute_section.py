r"""The involute transverse section shared by the involute families (ISO 21771, Litvin &
Fuentes 2004): helical gears (`InvoluteGearPair`) and curvilinear-tooth gears
(`CurvilinearGearPair`) differ only in how the section turns along the face.

Formulas (transverse quantities subscript t, normal n, base b, working w):

* $\tan\alpha_t = \tan\alpha_n/\cos\beta$, $m_t = m_n/\cos\beta$, $r = z m_t/2$,
  $r_b = r\cos\alpha_t$, $r_a = r + m_n(h_{aP}^* + x)$, $r_f = r - m_n(h_{fP}^* - x)$,
  $\tan\beta_b = \tan\beta\cos\alpha_t$.
* $p_{bt} = \pi m_t\cos\alpha_t$, $p_{bn} = \pi m_n\cos\alpha_n$, $p_x = \pi m_n/\sin\beta$.
* $\operatorname{inv}\alpha_{wt} = \operatorname{inv}\alpha_t + 2(x_1+x_2)\tan\alpha_n/(z_1+z_2)$,
  $a = a_0\cos\alpha_t/\cos\alpha_{wt}$, $a_0 = m_n(z_1+z_2)/(2\cos\beta)$.
* $\varepsilon_\alpha = [\sqrt{r_{a1}^2-r_{b1}^2} + \sqrt{r_{a2}^2-r_{b2}^2} - a\sin\alpha_{wt}]/p_{bt}$,
  $\varepsilon_\beta = b\sin\beta/(\pi m_n)$.

The profile parameter $u$ of both flanks is the transverse **roll length**
$s = \sqrt{r^2 - r_b^2}$ (mm): the distance from the base-circle tangency point to the
contact point along the line of action, and the radius of curvature of the transverse
profile there. On the pinion, $s$ is also the position along the line of action measured
from the pinion's tangency point $T_1$.
"""

from __future__ import annotations

import abc
import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, ArrayLike, Float, Scalar
from .._numerics import as_float, involute, inverse_involute, safe_sqrt
from .._validate import check_range, is_concrete
from ._base import AbstractFlankPair, derived, resolve_derived
from .involute_checks import check_feasible, check_section_inputs, per_gear
from .involute_curve import half_tooth_angle, involute_normal, involute_point, involute_tangent, slice_frame


class AbstractInvolutePair(AbstractFlankPair):
    """External pair whose transverse sections are involutes of the base circles.

    Holds the ISO 21771 parameters and everything derived from them; a concrete family adds
    how the section turns along the face (`lead_rotation`) and the flank normal's
    transverse fraction (`transverse_normal_fraction`). All lengths mm, angles in rad.

    Attributes:
        teeth: $(z_1, z_2)$, pinion first (static).
        normal_module: $m_n$ (mm).
        normal_pressure_angle: $\\alpha_n$ (rad).
        helix_angle: $\\beta \\ge 0$ at the reference cylinder (rad).
        face_width: $b$, common face width (mm).
        profile_shift: $(x_1, x_2)$ (-).
        addendum_coefficient: $h_{aP}^*$ of the basic rack, per gear (-).
        dedendum_coefficient: $h_{fP}^*$ of the basic rack, per gear (-).
        root_radius_coefficient: $\\rho_{fP}^*$ of the basic rack tip, per gear (-).
        derived: values of the `derived` quantities once resolved, else None.
    """

    #: Each transverse slice is conjugate (line contact): the plane-of-action fast path applies.
    conjugate_slices: ClassVar[bool] = True
    screen_edges: ClassVar[bool] = True
    supported_effects: ClassVar[frozenset[str]] = frozenset({"ltca", "impact"})

    teeth: tuple[int, int] = eqx.field(static=True)
    normal_module: Scalar
    normal_pressure_angle: Scalar
    helix_angle: Scalar
    face_width: Scalar
    profile_shift: Float[Array, "2"]
    addendum_coefficient: Float[Array, "2"]
    dedendum_coefficient: Float[Array, "2"]
    root_radius_coefficient: Float[Array, "2"]
    derived: dict[str, Array] | None

    def _init_section(
        self,
        teeth,
        normal_module,
        pressure_angle_deg,
        helix_angle_deg,
        face_width,
        profile_shift,
        addendum_coefficient,
        dedendum_coefficient,
        root_radius_coefficient,
    ) -> None:
        """Validate (`check_section_inputs`) and set the section's parameters (called by the
        families' `__init__`)."""
        self.teeth = check_section_inputs(
            teeth, normal_module, pressure_angle_deg, helix_angle_deg, face_width, profile_shift,
            addendum_coefficient, dedendum_coefficient, root_radius_coefficient,
        )
        self.normal_module = as_float(normal_module)
        self.normal_pressure_angle = as_float(pressure_angle_deg) * (math.pi / 180.0)
        self.helix_angle = as_float(helix_angle_deg) * (math.pi / 180.0)
        self.face_width = as_float(face_width)
        self.profile_shift = per_gear(profile_shift)
        self.addendum_coefficient = per_gear(addendum_coefficient)
        self.dedendum_coefficient = per_gear(dedendum_coefficient)
        self.root_radius_coefficient = per_gear(root_radius_coefficient)
        self.derived = None

    def _check_section(self, center_distance) -> None:
        """Physical feasibility (concrete values only), after all fields are set."""
        if center_distance is not None:
            check_range("center_distance", center_distance, 0.0, None, low_inclusive=False, unit="mm")
        if is_concrete(self):
            check_feasible(self.resolve(), center_distance)

    # ------------------------------------------------------------------ ISO 21771 quantities
    @derived
    def transverse_module(self) -> Scalar:
        """$m_t = m_n/\\cos\\beta$ (mm)."""
        return self.normal_module / jnp.cos(self.helix_angle)

    @derived
    def transverse_pressure_angle(self) -> Scalar:
        """$\\alpha_t = \\arctan(\\tan\\alpha_n/\\cos\\beta)$ (rad)."""
        return jnp.arctan(jnp.tan(self.normal_pressure_angle) / jnp.cos(self.helix_angle))

    @derived
    def base_helix_angle(self) -> Scalar:
        """$\\beta_b = \\arctan(\\tan\\beta\\cos\\alpha_t)$ (rad)."""
        return jnp.arctan(jnp.tan(self.helix_angle) * jnp.cos(self.transverse_pressure_angle))

    @derived
    def reference_radius(self) -> Float[Array, "2"]:
        """$r = z m_t / 2$ (mm), per gear."""
        return jnp.asarray(self.teeth, dtype=self.normal_module.dtype) * self.transverse_module[..., None] / 2

    @derived
    def base_radius(self) -> Float[Array, "2"]:
        """$r_b = r\\cos\\alpha_t$ (mm), per gear."""
        return self.reference_radius * jnp.cos(self.transverse_pressure_angle)[..., None]

    @derived
    def tip_radius(self) -> Float[Array, "2"]:
        """$r_a = r + m_n(h_{aP}^* + x)$ (mm), per gear."""
        return self.reference_radius + self.normal_module[..., None] * (
            self.addendum_coefficient + self.profile_shift
        )

    @derived
    def root_radius(self) -> Float[Array, "2"]:
        """$r_f = r - m_n(h_{fP}^* - x)$ (mm), per gear."""
        return self.reference_radius - self.normal_module[..., None] * (
            self.dedendum_coefficient - self.profile_shift
        )

    @derived
    def reference_center_distance(self) -> Scalar:
        """$a_0 = m_n(z_1+z_2)/(2\\cos\\beta)$ (mm)."""
        return self.normal_module * sum(self.teeth) / (2 * jnp.cos(self.helix_angle))

    @derived
    def working_pressure_angle(self) -> Scalar:
        """$\\alpha_{wt}$ from $\\operatorname{inv}\\alpha_{wt} = \\operatorname{inv}\\alpha_t
        + 2(x_1+x_2)\\tan\\alpha_n/(z_1+z_2)$ (rad)."""
        alpha_t = self.transverse_pressure_angle
        shift_sum = self.profile_shift[..., 0] + self.profile_shift[..., 1]
        return inverse_involute(
            involute(alpha_t) + 2 * shift_sum * jnp.tan(self.normal_pressure_angle) / sum(self.teeth)
        )

    @derived
    def center_distance(self) -> Scalar:
        """$a = a_0\\cos\\alpha_t/\\cos\\alpha_{wt}$ (mm), zero backlash."""
        return (
            self.reference_center_distance
            * jnp.cos(self.transverse_pressure_angle)
            / jnp.cos(self.working_pressure_angle)
        )

    @derived
    def working_pitch_radius(self) -> Float[Array, "2"]:
        """$r_w = r_b/\\cos\\alpha_{wt}$ (mm), per gear."""
        return self.base_radius / jnp.cos(self.working_pressure_angle)[..., None]

    @derived
    def transverse_base_pitch(self) -> Scalar:
        """$p_{bt} = \\pi m_t\\cos\\alpha_t$ (mm)."""
        return jnp.pi * self.transverse_module * jnp.cos(self.transverse_pressure_angle)

    @derived
    def normal_base_pitch(self) -> Scalar:
        """$p_{bn} = \\pi m_n\\cos\\alpha_n$ (mm)."""
        return jnp.pi * self.normal_module * jnp.cos(self.normal_pressure_angle)

    @derived
    def axial_pitch(self) -> Scalar:
        """$p_x = \\pi m_n/\\sin\\beta$ (mm); infinite for spur gears."""
        return jnp.pi * self.normal_module / jnp.sin(self.helix_angle)

    @derived
    def line_of_action_length(self) -> Scalar:
        """Length of the transverse line of action between the base tangency points,
        $a\\sin\\alpha_{wt}$ (mm)."""
        return self.center_distance * jnp.sin(self.working_pressure_angle)

    @derived
    def tip_roll_length(self) -> Float[Array, "2"]:
        """$s_a = \\sqrt{r_a^2 - r_b^2}$ (mm), per gear."""
        return safe_sqrt(self.tip_radius**2 - self.base_radius**2)

    @derived
    def form_roll_length(self) -> Float[Array, "2"]:
        r"""Roll length where the generated involute starts (root form circle), ISO 21771:
        $s_{Ff} = r_b\tan\alpha_t - (h_{fP}^* - \rho_{fP}^*(1-\sin\alpha_n) - x)\,m_n/\sin\alpha_t$
        (mm). Negative means undercut."""
        alpha_t = self.transverse_pressure_angle[..., None]
        straight = (
            self.dedendum_coefficient
            - self.root_radius_coefficient * (1 - jnp.sin(self.normal_pressure_angle))[..., None]
            - self.profile_shift
        )
        return self.base_radius * jnp.tan(alpha_t) - straight * self.normal_module[..., None] / jnp.sin(alpha_t)

    @derived
    def start_of_active_profile(self) -> Float[Array, "2"]:
        """Roll length where the mate's tip circle meets the line of action (mm), per gear:
        $s_{start,1} = a\\sin\\alpha_{wt} - s_{a2}$ and vice versa."""
        length = self.line_of_action_length[..., None]
        return length - self.tip_roll_length[..., ::-1]

    @derived
    def transverse_contact_ratio(self) -> Scalar:
        """$\\varepsilon_\\alpha$ (-)."""
        s_a = self.tip_roll_length
        return (s_a[..., 0] + s_a[..., 1] - self.line_of_action_length) / self.transverse_base_pitch

    @property
    @abc.abstractmethod
    def contact_line_length(self) -> Scalar:
        """Length of a contact line across the whole face, $\\int_{-b/2}^{b/2}\\mathrm{d}z/|n_t|$
        (mm): the length of line contact the LTCA's Hertz law refers the local load intensity
        to (`gearjax.ltca.SliceCompliance`)."""

    @derived
    def overlap_ratio(self) -> Scalar:
        """$\\varepsilon_\\beta = b\\sin\\beta/(\\pi m_n)$ (-)."""
        return self.face_width * jnp.sin(self.helix_angle) / (jnp.pi * self.normal_module)

    @derived
    def total_contact_ratio(self) -> Scalar:
        """$\\varepsilon_\\gamma = \\varepsilon_\\alpha + \\varepsilon_\\beta$ (-)."""
        return self.transverse_contact_ratio + self.overlap_ratio

    @derived
    def tip_thickness(self) -> Float[Array, "2"]:
        """Transverse tooth thickness at the tip circle (arc, mm), per gear."""
        z = jnp.asarray(self.teeth, dtype=self.normal_module.dtype)
        psi = half_tooth_angle(
            z,
            self.profile_shift,
            self.transverse_pressure_angle[..., None],
            self.normal_pressure_angle[..., None],
            self.tip_radius,
            self.base_radius,
        )
        return 2 * self.tip_radius * psi

    @derived
    def half_base_thickness_angles(self) -> Float[Array, "2"]:
        """$\\psi_b = \\pi/(2z) + 2x\\tan\\alpha_n/z + \\operatorname{inv}\\alpha_t$ (rad),
        per gear."""
        z = jnp.asarray(self.teeth, dtype=self.normal_module.dtype)
        return (
            jnp.pi / (2 * z)
            + 2 * self.profile_shift * jnp.tan(self.normal_pressure_angle)[..., None] / z
            + involute(self.transverse_pressure_angle)[..., None]
        )

    def half_base_thickness_angle(self, gear: int) -> Scalar:
        """`half_base_thickness_angles` of `gear` (rad)."""
        return self.half_base_thickness_angles[..., gear]

    @derived
    def placements(self) -> Float[Array, "2"]:
        """`placement` of both gears (rad): the base point of the pinion flank lies at
        $\\operatorname{inv}\\alpha_{wt}$, that of the gear at $\\pi + \\operatorname{inv}\\alpha_{wt}$."""
        inv_w = involute(self.working_pressure_angle)[..., None]
        return inv_w + jnp.asarray([0.0, jnp.pi], dtype=inv_w.dtype) - self.half_base_thickness_angles

    # ------------------------------------------------------------------ family interface
    def profile(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        return involute_point(
            self.base_radius[..., gear], self.half_base_thickness_angle(gear), as_float(u)
        )

    def profile_limits(self, gear: int) -> tuple[Scalar, Scalar]:
        return self.form_roll_length[..., gear], self.tip_roll_length[..., gear]

    # Closed forms of the derived geometry (the base class would use autodiff; nesting it
    # inside the Newton solves multiplies the size of the compiled program).
    def _base_angle(self, gear: int) -> Scalar:
        return self.placement(gear) + self.half_base_thickness_angle(gear)

    def profile_tangent(self, gear: int, u: ArrayLike):
        """Point and $\\mathrm{d}P/\\mathrm{d}s$ (`involute_tangent`)."""
        return involute_tangent(self.base_radius[..., gear], self._base_angle(gear), as_float(u))

    def profile_normal(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        """$(-\\sin\\theta, \\cos\\theta)$, defined down to the base circle."""
        return involute_normal(self.base_radius[..., gear], self._base_angle(gear), as_float(u))

    def slice_point(self, gear: int, u: ArrayLike, z: ArrayLike, slice_rotation: ArrayLike,
                    depth: ArrayLike = 0.0) -> Float[Array, "2"]:
        """$X = O + r_b e_r(\\psi) + (s - \\delta/|n_t|)\\,n(\\psi)$: the involute point
        $r_b e_r + s\\,n$ moved by the transverse offset $\\delta/|n_t|$ along its normal."""
        u = as_float(u)
        offset = depth / self.transverse_normal_fraction(gear, u, z)
        return self._offset_point(gear, u, offset, *self._slice_frame(gear, u, slice_rotation))

    def _slice_frame(self, gear: int, u: Array, slice_rotation: ArrayLike):
        return slice_frame(gear, self.working_pressure_angle, self.base_radius[..., gear], u, slice_rotation)

    def _offset_point(self, gear: int, u: Array, offset, radial, normal) -> Float[Array, "2"]:
        """$O + r_b e_r + (s - o)\\,n$ for the transverse offset $o$ (mm)."""
        return self.center(gear) + self.base_radius[..., gear, None] * radial + (u - offset)[..., None] * normal

    def slice_point_tangent(self, gear: int, u: ArrayLike, z: ArrayLike, slice_rotation: ArrayLike, depth=None):
        """Point and $\\mathrm{d}X/\\mathrm{d}s = ((s - o)/r_b)\\,e_r(\\psi) - o'\\,n(\\psi)$, $o(s)$
        the transverse offset $\\delta(s)/|n_t|$ (from $\\mathrm{d}e_r/\\mathrm{d}s = -n/r_b$,
        $\\mathrm{d}n/\\mathrm{d}s = e_r/r_b$); only $o'$ is differentiated automatically."""
        u = as_float(u)
        if depth is None:
            offset, rate = jnp.zeros_like(u), jnp.zeros_like(u)
        else:
            offset, rate = jax.jvp(lambda t: depth(t) / self.transverse_normal_fraction(gear, t, z),
                                   (u,), (jnp.ones_like(u),))
        radial, normal = self._slice_frame(gear, u, slice_rotation)
        tangent = ((u - offset) / self.base_radius[..., gear])[..., None] * radial - rate[..., None] * normal
        return self._offset_point(gear, u, offset, radial, normal), tangent

    def placement(self, gear: int) -> Scalar:
        """Tooth 0 of each gear touches the other at the pitch point at zero rotation
        (`placements`)."""
        return self.placements[..., gear]

    def contact_guess(self, angle: ArrayLike) -> tuple[Scalar, Scalar]:
        """Conjugate contact: $s_1 = r_{b1}(\\tan\\alpha_{wt} + \\varphi)$, $s_2 = a\\sin\\alpha_{wt} - s_1$."""
        s1 = self.base_radius[..., 0] * (jnp.tan(self.working_pressure_angle) + angle)
        return s1, self.line_of_action_length - s1

    def relief_coordinates(self, gear: int) -> tuple[Scalar, Scalar]:
        return self.start_of_active_profile[..., gear], self.tip_roll_length[..., gear]

    def parameter_domain(self, gear: int) -> tuple[Scalar, Scalar]:
        """From just off the involute's cusp at the base circle to 1.5 tip radii."""
        rb = self.base_radius[..., gear]
        return 1e-3 * rb, safe_sqrt((1.5 * self.tip_radius[..., gear]) ** 2 - rb**2)

    def parameter_at_radius(self, gear: int, radius: ArrayLike) -> Scalar:
        """$s = \\sqrt{r^2 - r_b^2}$ (zero inside the base circle)."""
        return safe_sqrt(as_float(radius) ** 2 - self.base_radius[..., gear] ** 2)

    def action_radius(self, gear: int) -> Scalar:
        return self.base_radius[..., gear]

    def line_of_action_point(self, roll_length: ArrayLike, z: ArrayLike = 0.0) -> Float[Array, "3"]:
        """Point of the plane of action at pinion roll length `roll_length` and axial `z`
        (fixed frame, mm): $T_1 + s\\,(\\sin\\alpha_{wt}, \\cos\\alpha_{wt})$."""
        alpha = self.working_pressure_angle
        rb1 = self.base_radius[..., 0]
        x = rb1 * jnp.cos(alpha) + roll_length * jnp.sin(alpha)
        y = -rb1 * jnp.sin(alpha) + roll_length * jnp.cos(alpha)
        return jnp.stack([x, y, jnp.broadcast_to(as_float(z), jnp.shape(x))], -1)

    def resolve(self):
        return resolve_derived(self)

    def _section_report(self) -> dict[str, ArrayLike]:
        """The involute section's quantities for `geometry_report`."""
        deg = 180.0 / math.pi
        return {
            "normal_module_mm": self.normal_module,
            "helix_angle_deg": self.helix_angle * deg,
            "face_width_mm": self.face_width,
            "center_distance_mm": self.center_distance,
            "transverse_pressure_angle_deg": self.transverse_pressure_angle * deg,
            "working_pressure_angle_deg": self.working_pressure_angle * deg,
            "base_helix_angle_deg": self.base_helix_angle * deg,
            "reference_radius_mm": self.reference_radius,
            "base_radius_mm": self.base_radius,
            "tip_radius_mm": self.tip_radius,
            "root_radius_mm": self.root_radius,
            "transverse_base_pitch_mm": self.transverse_base_pitch,
            "normal_base_pitch_mm": self.normal_base_pitch,
            "transverse_contact_ratio": self.transverse_contact_ratio,
            "overlap_ratio": self.overlap_ratio,
            "total_contact_ratio": self.total_contact_ratio,
            "start_of_active_profile_roll_mm": self.start_of_active_profile,
            "tip_roll_length_mm": self.tip_roll_length,
        }
