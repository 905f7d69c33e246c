r"""Involute helical gear pairs (spur when $\beta = 0$), ISO 21771 / Litvin & Fuentes (2004).

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
contact point along the line of action. On the pinion, $s$ is also the position along the
line of action measured from the pinion's tangency point $T_1$.

The flank is Litvin's involute helicoid: each transverse section is the involute of the
base circle, turned by $z\tan\beta_b/r_b$ (right hand pinion, left hand gear for
`hand="right"`).
"""

from __future__ import annotations

import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._custom_types import Array, ArrayLike, Float, Scalar
from .._numerics import (
    as_float,
    involute,
    inverse_involute,
    safe_arccos,
    safe_sqrt,
)
from .._validate import check_choice, check_int, check_range, is_concrete
from ._base import AbstractGearPair


def involute_point(base_radius: ArrayLike, base_angle: ArrayLike, roll_length: ArrayLike):
    r"""Counter-clockwise-facing involute of a circle (mm).

    $P(s) = r_b(\cos\theta, \sin\theta) + s(-\sin\theta, \cos\theta)$ with
    $\theta = \theta_0 - s/r_b$: the string unwinds clockwise from the base point at polar
    angle `base_angle` $\theta_0$; the outward normal is $(-\sin\theta, \cos\theta)$.
    """
    theta = base_angle - roll_length / base_radius
    c, s = jnp.cos(theta), jnp.sin(theta)
    return jnp.stack([base_radius * c - roll_length * s, base_radius * s + roll_length * c], -1)


def half_tooth_angle(teeth, shift, pressure_angle_t, pressure_angle_n, radius, base_radius):
    r"""Half the transverse tooth thickness angle at `radius` (rad):
    $\psi = \pi/(2z) + 2x\tan\alpha_n/z + \operatorname{inv}\alpha_t - \operatorname{inv}\alpha_r$,
    $\cos\alpha_r = r_b/r$."""
    alpha_r = safe_arccos(base_radius / radius)
    return (
        jnp.pi / (2 * teeth)
        + 2 * shift * jnp.tan(pressure_angle_n) / teeth
        + involute(pressure_angle_t)
        - involute(alpha_r)
    )


class InvoluteGearPair(AbstractGearPair):
    """External involute helical gear pair (spur for zero helix angle), ISO 21771.

    All lengths mm, angles stored in rad. Construct with degrees:

    >>> pair = InvoluteGearPair(teeth=(29, 71), normal_module=5.0, pressure_angle_deg=20.0,
    ...                         helix_angle_deg=27.5, face_width=42.0)

    Attributes:
        teeth: $(z_1, z_2)$, pinion first (static).
        hand: +1 if the pinion is right hand (gear left hand), -1 otherwise (static).
        normal_module: $m_n$ (mm).
        normal_pressure_angle: $\\alpha_n$ (rad).
        helix_angle: $\\beta \\ge 0$ at the reference cylinder (rad).
        face_width: $b$, common face width (mm).
        profile_shift: $(x_1, x_2)$ (-).
        addendum_coefficient: $h_{aP}^*$ of the basic rack, per gear (-).
        dedendum_coefficient: $h_{fP}^*$ of the basic rack, per gear (-).
        root_radius_coefficient: $\\rho_{fP}^*$ of the basic rack tip, per gear (-).
    """

    #: Each transverse slice is conjugate (line contact): the plane-of-action fast path applies.
    conjugate_slices: ClassVar[bool] = True

    teeth: tuple[int, int] = eqx.field(static=True)
    hand: int = eqx.field(static=True)
    normal_module: Scalar
    normal_pressure_angle: Scalar
    helix_angle: Scalar
    face_width: Scalar
    profile_shift: Float[Array, "2"]
    addendum_coefficient: Float[Array, "2"]
    dedendum_coefficient: Float[Array, "2"]
    root_radius_coefficient: Float[Array, "2"]

    def __init__(
        self,
        teeth: tuple[int, int],
        normal_module: ArrayLike,
        pressure_angle_deg: ArrayLike = 20.0,
        helix_angle_deg: ArrayLike = 0.0,
        face_width: ArrayLike = 20.0,
        profile_shift: ArrayLike = (0.0, 0.0),
        center_distance: ArrayLike | None = None,
        *,
        hand: str = "right",
        addendum_coefficient: ArrayLike = 1.0,
        dedendum_coefficient: ArrayLike = 1.25,
        root_radius_coefficient: ArrayLike = 0.38,
    ):
        if not isinstance(teeth, (tuple, list)) or len(teeth) != 2:
            raise ValueError(f"teeth must be a pair (z1, z2) of integers >= 5; got {teeth!r}")
        z1 = check_int("teeth[0] (pinion)", teeth[0], 5, 2000)
        z2 = check_int("teeth[1] (gear)", teeth[1], 5, 2000)
        check_choice("hand", hand, ("right", "left"))
        check_range("normal_module", normal_module, 0.0, 100.0, low_inclusive=False, unit="mm")
        check_range("pressure_angle_deg", pressure_angle_deg, 10.0, 35.0, unit="deg")
        check_range(
            "helix_angle_deg", helix_angle_deg, 0.0, 45.0, high_inclusive=False, unit="deg"
        )
        check_range("face_width", face_width, 0.0, None, low_inclusive=False, unit="mm")
        check_range("profile_shift", profile_shift, -1.0, 1.5)
        check_range("addendum_coefficient", addendum_coefficient, 0.3, 1.6)
        check_range("dedendum_coefficient", dedendum_coefficient, 0.5, 2.0)
        check_range("root_radius_coefficient", root_radius_coefficient, 0.0, 0.6)
        if center_distance is not None:
            check_range("center_distance", center_distance, 0.0, None, low_inclusive=False, unit="mm")

        self.teeth = (z1, z2)
        self.hand = 1 if hand == "right" else -1
        self.normal_module = as_float(normal_module)
        self.normal_pressure_angle = as_float(pressure_angle_deg) * (math.pi / 180.0)
        self.helix_angle = as_float(helix_angle_deg) * (math.pi / 180.0)
        self.face_width = as_float(face_width)
        self.profile_shift = _per_gear(profile_shift)
        self.addendum_coefficient = _per_gear(addendum_coefficient)
        self.dedendum_coefficient = _per_gear(dedendum_coefficient)
        self.root_radius_coefficient = _per_gear(root_radius_coefficient)

        if is_concrete(self):
            _check_feasible(self, center_distance)

    # ------------------------------------------------------------------ ISO 21771 quantities
    @property
    def transverse_module(self) -> Scalar:
        """$m_t = m_n/\\cos\\beta$ (mm)."""
        return self.normal_module / jnp.cos(self.helix_angle)

    @property
    def transverse_pressure_angle(self) -> Scalar:
        """$\\alpha_t = \\arctan(\\tan\\alpha_n/\\cos\\beta)$ (rad)."""
        return jnp.arctan(jnp.tan(self.normal_pressure_angle) / jnp.cos(self.helix_angle))

    @property
    def base_helix_angle(self) -> Scalar:
        """$\\beta_b = \\arctan(\\tan\\beta\\cos\\alpha_t)$ (rad)."""
        return jnp.arctan(jnp.tan(self.helix_angle) * jnp.cos(self.transverse_pressure_angle))

    @property
    def reference_radius(self) -> Float[Array, "2"]:
        """$r = z m_t / 2$ (mm), per gear."""
        return jnp.asarray(self.teeth, dtype=self.normal_module.dtype) * self.transverse_module[..., None] / 2

    @property
    def base_radius(self) -> Float[Array, "2"]:
        """$r_b = r\\cos\\alpha_t$ (mm), per gear."""
        return self.reference_radius * jnp.cos(self.transverse_pressure_angle)[..., None]

    @property
    def tip_radius(self) -> Float[Array, "2"]:
        """$r_a = r + m_n(h_{aP}^* + x)$ (mm), per gear."""
        return self.reference_radius + self.normal_module[..., None] * (
            self.addendum_coefficient + self.profile_shift
        )

    @property
    def root_radius(self) -> Float[Array, "2"]:
        """$r_f = r - m_n(h_{fP}^* - x)$ (mm), per gear."""
        return self.reference_radius - self.normal_module[..., None] * (
            self.dedendum_coefficient - self.profile_shift
        )

    @property
    def reference_center_distance(self) -> Scalar:
        """$a_0 = m_n(z_1+z_2)/(2\\cos\\beta)$ (mm)."""
        return self.normal_module * sum(self.teeth) / (2 * jnp.cos(self.helix_angle))

    @property
    def working_pressure_angle(self) -> Scalar:
        """$\\alpha_{wt}$ from $\\operatorname{inv}\\alpha_{wt} = \\operatorname{inv}\\alpha_t
        + 2(x_1+x_2)\\tan\\alpha_n/(z_1+z_2)$ (rad)."""
        alpha_t = self.transverse_pressure_angle
        shift_sum = self.profile_shift[..., 0] + self.profile_shift[..., 1]
        return inverse_involute(
            involute(alpha_t) + 2 * shift_sum * jnp.tan(self.normal_pressure_angle) / sum(self.teeth)
        )

    @property
    def center_distance(self) -> Scalar:
        """$a = a_0\\cos\\alpha_t/\\cos\\alpha_{wt}$ (mm), zero backlash."""
        return (
            self.reference_center_distance
            * jnp.cos(self.transverse_pressure_angle)
            / jnp.cos(self.working_pressure_angle)
        )

    @property
    def working_pitch_radius(self) -> Float[Array, "2"]:
        """$r_w = r_b/\\cos\\alpha_{wt}$ (mm), per gear."""
        return self.base_radius / jnp.cos(self.working_pressure_angle)[..., None]

    @property
    def transverse_base_pitch(self) -> Scalar:
        """$p_{bt} = \\pi m_t\\cos\\alpha_t$ (mm)."""
        return jnp.pi * self.transverse_module * jnp.cos(self.transverse_pressure_angle)

    @property
    def normal_base_pitch(self) -> Scalar:
        """$p_{bn} = \\pi m_n\\cos\\alpha_n$ (mm)."""
        return jnp.pi * self.normal_module * jnp.cos(self.normal_pressure_angle)

    @property
    def axial_pitch(self) -> Scalar:
        """$p_x = \\pi m_n/\\sin\\beta$ (mm); infinite for spur gears."""
        return jnp.pi * self.normal_module / jnp.sin(self.helix_angle)

    @property
    def line_of_action_length(self) -> Scalar:
        """Length of the transverse line of action between the base tangency points,
        $a\\sin\\alpha_{wt}$ (mm)."""
        return self.center_distance * jnp.sin(self.working_pressure_angle)

    @property
    def tip_roll_length(self) -> Float[Array, "2"]:
        """$s_a = \\sqrt{r_a^2 - r_b^2}$ (mm), per gear."""
        return safe_sqrt(self.tip_radius**2 - self.base_radius**2)

    @property
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

    @property
    def start_of_active_profile(self) -> Float[Array, "2"]:
        """Roll length where the mate's tip circle meets the line of action (mm), per gear:
        $s_{start,1} = a\\sin\\alpha_{wt} - s_{a2}$ and vice versa."""
        length = self.line_of_action_length[..., None]
        return length - self.tip_roll_length[..., ::-1]

    @property
    def transverse_contact_ratio(self) -> Scalar:
        """$\\varepsilon_\\alpha$ (-)."""
        s_a = self.tip_roll_length
        return (s_a[..., 0] + s_a[..., 1] - self.line_of_action_length) / self.transverse_base_pitch

    @property
    def overlap_ratio(self) -> Scalar:
        """$\\varepsilon_\\beta = b\\sin\\beta/(\\pi m_n)$ (-)."""
        return self.face_width * jnp.sin(self.helix_angle) / (jnp.pi * self.normal_module)

    @property
    def total_contact_ratio(self) -> Scalar:
        """$\\varepsilon_\\gamma = \\varepsilon_\\alpha + \\varepsilon_\\beta$ (-)."""
        return self.transverse_contact_ratio + self.overlap_ratio

    @property
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

    def half_base_thickness_angle(self, gear: int) -> Scalar:
        """$\\psi_b = \\pi/(2z) + 2x\\tan\\alpha_n/z + \\operatorname{inv}\\alpha_t$ (rad)."""
        z = self.teeth[gear]
        return (
            jnp.pi / (2 * z)
            + 2 * self.profile_shift[..., gear] * jnp.tan(self.normal_pressure_angle) / z
            + involute(self.transverse_pressure_angle)
        )

    # ------------------------------------------------------------------ family interface
    def profile(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        return involute_point(
            self.base_radius[..., gear], self.half_base_thickness_angle(gear), as_float(u)
        )

    def profile_limits(self, gear: int) -> tuple[Scalar, Scalar]:
        return self.form_roll_length[..., gear], self.tip_roll_length[..., gear]

    # Closed forms of the derived geometry (the base class would use autodiff; nesting it
    # inside the Newton solves multiplies the size of the compiled program).
    def _local_angle(self, gear: int, u: ArrayLike) -> Scalar:
        base = self.placement(gear) + self.half_base_thickness_angle(gear)
        return base - as_float(u) / self.base_radius[..., gear]

    def profile_tangent(self, gear: int, u: ArrayLike):
        """Point and $\\mathrm{d}P/\\mathrm{d}s = (s/r_b)(\\cos\\theta, \\sin\\theta)$."""
        u = as_float(u)
        theta = self._local_angle(gear, u)
        c, s = jnp.cos(theta), jnp.sin(theta)
        rb = self.base_radius[..., gear]
        point = jnp.stack([rb * c - u * s, rb * s + u * c], -1)
        return point, (u / rb)[..., None] * jnp.stack([c, s], -1)

    def profile_normal(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        """$(-\\sin\\theta, \\cos\\theta)$, defined down to the base circle."""
        theta = self._local_angle(gear, u)
        return jnp.stack([-jnp.sin(theta), jnp.cos(theta)], -1)

    def transverse_normal_fraction(self, gear: int, u: ArrayLike, z: ArrayLike) -> Scalar:
        """$|n_t| = \\cos\\beta_b$ everywhere on an involute helicoid."""
        shape = jnp.broadcast_shapes(jnp.shape(u), jnp.shape(z))
        return jnp.broadcast_to(jnp.cos(self.base_helix_angle), shape)

    def lead_rotation(self, gear: int, z: ArrayLike) -> Scalar:
        """$\\psi_i(z) = \\pm z\\tan\\beta_b/r_{bi}$: right-hand pinion (left-hand gear) for
        `hand = +1`; both turn their sections in their own sense of rotation."""
        return self.hand * as_float(z) * jnp.tan(self.base_helix_angle) / self.base_radius[..., gear]

    def placement(self, gear: int) -> Scalar:
        """Tooth 0 of each gear touches the other at the pitch point at zero rotation: the
        base point of the pinion flank lies at $\\operatorname{inv}\\alpha_{wt}$, that of the
        gear at $\\pi + \\operatorname{inv}\\alpha_{wt}$."""
        inv_w = involute(self.working_pressure_angle)
        base = inv_w if gear == 0 else jnp.pi + inv_w
        return base - self.half_base_thickness_angle(gear)

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


def _per_gear(value: ArrayLike) -> Float[Array, "2"]:
    arr = as_float(value)
    if arr.ndim == 0 or arr.shape[-1] != 2:
        arr = jnp.stack([arr, arr], axis=-1)
    return arr


def _check_feasible(pair: InvoluteGearPair, center_distance: ArrayLike | None) -> None:
    """Physical feasibility of the pair (concrete values only): undercut, pointed tips,
    interference, tip clearance, contact ratio and centre distance consistency."""
    z1, z2 = pair.teeth
    s_form = np.asarray(pair.form_roll_length)
    for i, name in enumerate(("pinion", "gear")):
        if np.any(s_form[..., i] < 0):
            x_min = _min_shift_without_undercut(pair, i)
            raise ValueError(
                f"profile_shift[{i}] gives an undercut {name} (z={pair.teeth[i]}): the involute "
                f"would start below the base circle; profile_shift[{i}] must be >= {x_min:.4f}"
            )
    tip = np.asarray(pair.tip_thickness)
    for i, name in enumerate(("pinion", "gear")):
        if np.any(tip[..., i] <= 0.0):
            raise ValueError(
                f"profile_shift[{i}] / addendum_coefficient give a pointed {name} tip "
                f"(tip thickness {np.min(tip[..., i]):.4f} mm); tip thickness must be > 0 mm"
            )
    if center_distance is not None:
        a = np.asarray(pair.center_distance)
        given = np.asarray(center_distance, dtype=float)
        if np.any(np.abs(given - a) > 1e-6 * np.maximum(1.0, a)):
            alpha_t = np.asarray(pair.transverse_pressure_angle)
            a0 = np.asarray(pair.reference_center_distance)
            ratio = a0 * np.cos(alpha_t) / given
            if np.all(np.abs(ratio) < 1):
                alpha_w = np.arccos(ratio)
                needed = (
                    (np.tan(alpha_w) - alpha_w - (np.tan(alpha_t) - alpha_t))
                    * (z1 + z2)
                    / (2 * np.tan(np.asarray(pair.normal_pressure_angle)))
                )
                hint = f"; center_distance={_fmt(given)} mm would need x1 + x2 = {_fmt(needed)}"
            else:
                hint = (
                    f"; center_distance={_fmt(given)} mm is not reachable by any profile shift "
                    f"(it is at most a0*cos(alpha_t) = {_fmt(a0 * np.cos(alpha_t))} mm)"
                )
            shifts = np.asarray(pair.profile_shift)
            raise ValueError(
                f"center_distance={_fmt(given)} mm is inconsistent with profile_shift "
                f"x1 + x2 = {_fmt(shifts[..., 0] + shifts[..., 1])}, which gives a = {_fmt(a)} mm "
                f"(zero backlash){hint}; omit center_distance to derive it"
            )
    a = np.asarray(pair.center_distance)
    clearance = a[..., None] - np.asarray(pair.tip_radius) - np.asarray(pair.root_radius)[..., ::-1]
    if np.any(clearance < 0.0):
        raise ValueError(
            "addendum_coefficient / dedendum_coefficient leave no tip clearance: a tip circle "
            f"cuts the mating root circle (clearance {np.min(clearance):.4f} mm must be >= 0 mm)"
        )
    s_start = np.asarray(pair.start_of_active_profile)
    for i, name in enumerate(("pinion", "gear")):
        if np.any(s_start[..., i] < s_form[..., i] - 1e-9):
            raise ValueError(
                f"profile_shift / addendum_coefficient cause tip interference: the "
                f"{('gear', 'pinion')[i]} tip reaches below the {name}'s involute (start of "
                f"active profile {np.min(s_start[..., i]):.4f} mm < form roll length "
                f"{np.min(s_form[..., i]):.4f} mm, as roll lengths)"
            )
    eps = np.asarray(pair.total_contact_ratio)
    eps_a = np.asarray(pair.transverse_contact_ratio)
    if np.any(eps < 1.0) or np.any(eps_a <= 0.0):
        raise ValueError(
            "the pair's total contact ratio eps_alpha + eps_beta = "
            f"{np.min(eps):.4f} must be >= 1 (eps_alpha = {np.min(eps_a):.4f}); increase "
            "face_width, helix_angle_deg or addendum_coefficient"
        )


def _min_shift_without_undercut(pair: InvoluteGearPair, gear: int) -> float:
    alpha_t = float(np.asarray(pair.transverse_pressure_angle).ravel()[0])
    alpha_n = float(np.asarray(pair.normal_pressure_angle).ravel()[0])
    mn = float(np.asarray(pair.normal_module).ravel()[0])
    rb = float(np.asarray(pair.base_radius)[..., gear].ravel()[0])
    hf = float(np.asarray(pair.dedendum_coefficient)[..., gear].ravel()[0])
    rho = float(np.asarray(pair.root_radius_coefficient)[..., gear].ravel()[0])
    return hf - rho * (1 - math.sin(alpha_n)) - rb * math.tan(alpha_t) * math.sin(alpha_t) / mn


def _fmt(value: np.ndarray) -> str:
    flat = np.ravel(value)
    return f"{flat[0]:.4f}" if flat.size == 1 else "[" + ", ".join(f"{v:.4f}" for v in flat[:4]) + "]"

