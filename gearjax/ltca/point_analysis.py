r"""Loaded contact of a double-circular-arc pair: each tooth pair of each contact zone
touches at one point, which the TCA finds (`gearjax.tca`), and carries its share of the
torque through its teeth's compliance and a Hertz point contact (`point_contact`).

Per position and tooth pair (both zones), at the pair's contact located between the TCA's
face slices (`closest_contact`, the face ends among them):

* the rigid gap $e_k$ (the TCA's separation, mm) and the arm $m_k = r_{a2}|n_t|$ (mm per
  radian of the gear's lag, the TCA's own conversion);
* the Hertz coefficient $h_k$ from the two flanks' relative curvatures at the contact
  (`hertz_point.relative_curvatures` on `flank_point`, `hertz_point_contact`);
* the linear compliance $c_k$: each tooth's section compliance (`section_compliance`, the
  tooth's generated transverse profile as the section, the load at the contact point along
  the transverse part of the normal), spread along the face with the decay length
  $\lambda$ between free face ends (`point_load_compliance`: twice as compliant at an
  end as mid-face), made normal by $|n_t|^2$, the two teeth summed. No
  fillet-foundation term, no coupling between the teeth of different pairs. Edge contacts
  (a tip edge or a face end on a flank) are taken with the flanks' curvatures, floored at
  `MIN_CURVATURE`: the edge's own rounding is not modelled.

The lag $\Theta$ and the loads then come from `point_contact.share_load` on the gear's
torque $T_2 = T_1 z_2/z_1$; the loaded TE is the TCA's less $\Theta$, as for the involute
families.
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, ArrayLike, Bool, Float
from .._numerics import safe_divide, safe_norm
from .._validate import check_range
from ..geometry._base import SceneFileSpec
from ..geometry.double_arc import DoubleArcGearPair
from ..tca import TCAResult
from ..tca._slice_problem import kind_index
from ..units import Material
from .compliance import AbstractCompliance
from .hertz_point import effective_modulus, hertz_point_contact, relative_curvatures
from .point_contact import point_load_compliance, section_compliance, share_load

#: Samples of the section between the root circle and the load point.
SECTION_SAMPLES = 200
#: Floor of the relative curvatures $A$, $B$ (mm⁻¹): an edge contact's flank curvatures can
#: vanish or change sign; the floor is a relative radius of 50 m.
MIN_CURVATURE = 1e-5


class ToothSectionCompliance(AbstractCompliance):
    """The point-contact model of this module for double-circular-arc teeth: each tooth's
    generated transverse section as a cantilever, a point load spread along the face with
    the decay length $\\lambda$, and the Hertz point contact of the two flanks.

    The contact is located between the TCA's face slices by a parabola, which converges
    from 21 slices on (decision 0009: the peak's error is −1.8…+13.9 µm at 9 slices,
    −0.16…+0.07 µm at 21), so a loaded scene needs at least `min_face_slices`. It also needs
    float64: in float32 the seed pair's loaded TE is a third off (decision 0009).

    Attributes:
        coupling_length: decay length $\\lambda$ of a point load along the face, in units
            of the normal module (default 1.1, as `SliceCompliance`).
    """

    families: ClassVar[tuple[type, ...]] = (DoubleArcGearPair,)
    scene_file: ClassVar[SceneFileSpec] = SceneFileSpec(
        "point", "point contact: tooth-section bending and shear, Hertz point contact",
        {"coupling_length_mn": ("coupling_length", "number", "m_n", 1.0)},
        required=(),
    )
    min_face_slices: ClassVar[int] = 21
    needs_float64: ClassVar[bool] = True

    coupling_length: float = eqx.field(static=True, default=1.1)

    def __check_init__(self):
        check_range("coupling_length", self.coupling_length, 0.0, 50.0, unit="m_n", low_inclusive=False)


class ToothSection(eqx.Module):
    """A tooth as a cantilever along its centre line (the tooth frame's $x$ axis): the
    half thickness against $x$, from its generated transverse profile.

    Attributes:
        x: positions on the centre line (mm), non-decreasing from the root (the tooth space's
            centre on the root circle) to the tip.
        half_thickness: the profile's distance $|y|$ from the centre line there (mm).
    """

    x: Float[Array, " sample"]
    half_thickness: Float[Array, " sample"]

    @classmethod
    def of(cls, pair, gear: int, samples: int = 80) -> ToothSection:
        """The section of `gear` of a `DoubleArcGearPair` (its `tooth_profile`, root to tip;
        traceable)."""
        profile = pair.tooth_profile(gear, samples)[::-1]
        return cls(jax.lax.cummax(profile[:, 0]), jnp.abs(profile[:, 1]))  # x increasing, as interpolation needs

    def compliance(self, point: ArrayLike, normal: ArrayLike, youngs_modulus, poisson_ratio) -> Array:
        """Transverse section compliance (mm²/N per unit face width) for a load at the
        profile `point` (tooth frame, mm) along the unit transverse `normal`: at $x_F$ on the
        centre line, $y_F = |y|$ off it, at the angle $\\gamma$ between the normal and the
        direction across the tooth ($\\cos\\gamma = |n_y|$)."""
        angle = jnp.arctan2(jnp.abs(normal[0]), jnp.abs(normal[1]))
        x = jnp.linspace(self.x[0], point[0], SECTION_SAMPLES)
        h = jnp.interp(x, self.x, self.half_thickness)
        return section_compliance(x, h, jnp.abs(point[1]), angle, youngs_modulus, poisson_ratio)


class PointContactLoads(eqx.Module):
    """The loaded point contacts over a mesh cycle. Axes: position, pair (both zones, as
    the TCA's pair axis).

    Attributes:
        rotation: the gear's lag $\\Theta$ (rad), shape (pos,).
        transmission_error: loaded TE of gear 2, the TCA's less $\\Theta$ (rad).
        loads: normal load of each pair (N).
        stiffness: $dF_k/d\\delta_k$ of each pair (N/mm; 0 out of contact).
        mesh_stiffness: $dT_2/d\\Theta$ (N·mm/rad), shape (pos,).
        semi_major, semi_minor: contact ellipse semi-axes (mm).
        curvature_a, curvature_b: the relative curvatures $A \\le B$ (1/mm) that the Hertz
            law takes (`relative_curvatures`; edge contacts floored at `MIN_CURVATURE`; 1
            for pairs out of mesh, which carry no load).
        max_pressure: $p_0$ (MPa).
        linear_compliance: $c_k$ (mm/N); hertz_coefficient: $h_k$ (mm/N^(2/3)).
        gaps: rigid gaps $e_k$ (mm); arms: $m_k$ (mm).
        slice_index: the TCA slice of each pair's contact.
        axial_position: the contact's $z$ between the slices (mm).
    """

    rotation: Float[Array, " pos"]
    transmission_error: Float[Array, " pos"]
    loads: Float[Array, "pos pair"]
    stiffness: Float[Array, "pos pair"]
    mesh_stiffness: Float[Array, " pos"]
    semi_major: Float[Array, "pos pair"]
    semi_minor: Float[Array, "pos pair"]
    curvature_a: Float[Array, "pos pair"]
    curvature_b: Float[Array, "pos pair"]
    max_pressure: Float[Array, "pos pair"]
    linear_compliance: Float[Array, "pos pair"]
    hertz_coefficient: Float[Array, "pos pair"]
    gaps: Float[Array, "pos pair"]
    arms: Float[Array, "pos pair"]
    slice_index: Array
    axial_position: Float[Array, "pos pair"]


def _tooth_frame_normal(zone, gear, u):
    """Profile point and unit normal of `gear`'s flank at `u`, tooth frame (tooth on +x)."""
    point, tangent = jax.jvp(lambda t: zone.profile(gear, t), (u,), (jnp.ones_like(u),))
    normal = jnp.stack([-tangent[1], tangent[0]])
    return point, normal / jnp.linalg.norm(normal)


def _contact_coefficients(zone, sections, k, phi1, u1, u2, z, te, normal, frac, material, decay_length):
    """(Hertz coefficient, linear compliance) of one contact of `zone`'s pair `k`."""
    rot1 = phi1 - k * zone.angular_pitch(0)
    rot2 = phi1 / zone.gear_ratio - k * zone.angular_pitch(1) + te
    surface1 = lambda u, zz: zone.flank_point(0, u, zz, rot1)  # noqa: E731
    surface2 = lambda u, zz: zone.flank_point(1, u, zz, rot2)  # noqa: E731
    a_curv, b_curv, _ = relative_curvatures(surface1, jnp.stack([u1, z]), surface2, jnp.stack([u2, z]), normal)
    # an edge contact (a tip edge or face end on a flank) has no common tangent plane: its
    # curvatures, taken on the flanks, are floored at a flat contact's
    a_curv, b_curv = jnp.maximum(a_curv, MIN_CURVATURE), jnp.maximum(b_curv, MIN_CURVATURE)
    modulus = effective_modulus(material.youngs_modulus, material.poisson_ratio)
    hertz = hertz_point_contact(1.0, a_curv, b_curv, modulus).approach_coefficient
    linear = 0.0
    for gear, u in ((0, u1), (1, u2)):
        point, n2 = _tooth_frame_normal(zone, gear, u)
        section = sections[gear].compliance(point, n2, material.youngs_modulus, material.poisson_ratio)
        linear = linear + frac**2 * point_load_compliance(section, decay_length, z, zone.face_width)
    return hertz, linear, a_curv, b_curv


def parabola_peak(x: tuple[ArrayLike, ArrayLike, ArrayLike],
                  y: tuple[ArrayLike, ArrayLike, ArrayLike]) -> tuple[Array, Array, Array]:
    """The vertex of the parabola through three points $x_0 < x_1 < x_2$ (any spacing):
    `(x, peak, concave)`, its abscissa clipped to $[x_0, x_2]$, the parabola's value there,
    and whether it opens downwards (where not, `x` is $x_1$ and `peak` $y_1$).

    In Newton's form $y = y_0 + d_1(x - x_0) + A(x - x_0)(x - x_1)$, with
    $d_1 = (y_1 - y_0)/(x_1 - x_0)$ and $A = (d_2 - d_1)/(x_2 - x_0)$, the vertex is
    $x^* = (x_0 + x_1)/2 - d_1/(2A)$."""
    (x0, x1, x2), (y0, y1, y2) = x, y
    d1, d2 = (y1 - y0) / (x1 - x0), (y2 - y1) / (x2 - x1)
    curvature = (d2 - d1) / (x2 - x0)
    concave = curvature < 0.0
    safe = jnp.where(concave, curvature, -1.0)
    vertex = jnp.where(concave, jnp.clip(0.5 * (x0 + x1) - 0.5 * d1 / safe, x0, x2), x1)
    value = y0 + (vertex - x0) * (d1 + safe * (vertex - x1))
    return vertex, jnp.where(concave, value, y1), concave


def closest_contact(tca: TCAResult) -> dict[str, Array]:
    """Each pair's point contact, (pos, pair): where the parabola through the largest slice
    TE and its neighbours along the face peaks. The face ends count as slices at their own
    positions (the TCA's last two), half a spacing from the first and last middle slice, so
    a peak near an end is located as one mid-face, and a peak at an end is the end's contact.
    The slice TE is smooth along the face only while the same candidate binds (a tip edge
    taking over from the flank contact is a kink or a step), so where the three slices'
    contact kinds differ, where one of them does not touch, or where the parabola does not
    open downwards, the largest slice is the contact.
    Returns the nearest slice `slice`, the rigid normal gap `gap` (mm, from the largest of
    the pairs' peaks; `inf` out of mesh), the profile parameters `u1`, `u2`, the axial
    position `z` (mm), `frac` ($|n_t|$) and the contact normal `normal` (renormalised),
    interpolated linearly between the two slices around the peak, the peak TE `te` (rad;
    0 out of mesh), and `between`, those slices `(start, other)` and the weight of
    `other`."""
    n_mid = tca.slice_z.shape[-1] - 2
    order = jnp.asarray([n_mid, *range(n_mid), n_mid + 1])  # the slices along the face
    z_sorted = tca.slice_z[order]
    te = jnp.where(tca.valid, tca.slice_te, -jnp.inf)[..., order]
    best = jnp.argmax(te, axis=-1)
    centre = jnp.clip(best, 1, n_mid)
    pick = lambda x, k: jnp.take_along_axis(x, k[..., None], axis=-1)[..., 0]  # noqa: E731
    left, here, right = pick(te, centre - 1), pick(te, centre), pick(te, centre + 1)
    kind = kind_index(tca.kind)[..., order]
    same_kind = (pick(kind, centre - 1) == pick(kind, centre)) & (pick(kind, centre + 1) == pick(kind, centre))
    ok = jnp.isfinite(left) & jnp.isfinite(here) & jnp.isfinite(right) & same_kind
    nodes = (z_sorted[centre - 1], z_sorted[centre], z_sorted[centre + 1])
    # zeros where not fitted (not concave): no infinite value reaches the fit's derivatives
    z, peak, concave = parabola_peak(nodes, tuple(jnp.where(ok, v, 0.0) for v in (left, here, right)))
    ok = ok & concave
    z = jnp.where(ok, z, z_sorted[best])
    peak = jnp.where(ok, peak, pick(te, best))
    # the two slices around z and the weight of the outer one
    start = jnp.where(ok, centre, best)
    outer = jnp.where(z >= nodes[1], centre + 1, centre - 1)
    other = jnp.where(ok, outer, best)
    weight = jnp.where(ok, (z - nodes[1]) / (z_sorted[outer] - nodes[1]), 0.0)
    start, other = order[start], order[other]

    def interpolate(field):
        return (1.0 - weight) * pick(field, start) + weight * pick(field, other)

    normal = jax.vmap(interpolate, in_axes=-1, out_axes=-1)(tca.normal)
    frac = interpolate(tca.transverse_normal_fraction)
    finite = jnp.isfinite(peak)
    top = jnp.max(peak, axis=-1, keepdims=True)
    gap = jnp.where(finite, (top - jnp.where(finite, peak, 0.0)) * tca.action_radius[1] * frac, jnp.inf)
    return {"slice": jnp.where(weight > 0.5, other, start), "gap": gap, "u1": interpolate(tca.pinion_parameter),
            "u2": interpolate(tca.gear_parameter), "z": z, "te": jnp.where(finite, peak, 0.0), "frac": frac,
            "normal": safe_divide(normal, safe_norm(normal)[..., None]), "between": (start, other, weight)}


def point_coefficients(pair, tca: TCAResult, material: Material, coupling_length_mn: float = 1.1,
                       sections: tuple[ToothSection, ToothSection] | None = None):
    """Each pair's point contact located between the TCA's face slices (`closest_contact`)
    and its coefficients there, (pos, pair, 4): the Hertz coefficient $h$ of
    $\\delta = cF + hF^{2/3}$ (mm/N^(2/3)), the linear compliance $c$ (mm/N: both teeth's
    sections and the spreading along the face) and the two principal relative curvatures
    (1/mm). Pairs out of mesh get coefficients of no meaning, not always finite (their
    slice solves need not have converged); `point_contact_analysis` replaces them."""
    if sections is None:
        sections = (ToothSection.of(pair, 0), ToothSection.of(pair, 1))
    decay_length = coupling_length_mn * pair.normal_module
    contact = closest_contact(tca)
    gaps, u1, u2, z, te, frac, normal = (contact[name] for name in ("gap", "u1", "u2", "z", "te", "frac", "normal"))
    phi1 = jnp.broadcast_to(tca.pinion_angle[:, None], gaps.shape)
    k = jnp.broadcast_to(tca.pair_index[None, :].astype(gaps.dtype), gaps.shape)
    zones = pair.contact_zones()

    def coefficients(zone_index, *args):
        # each pair in its own zone (`contact_zone` of a traced index: one trace for all);
        # the zones' pair windows need not be the same length (`tca.merge_zones`)
        zone = zones[0] if len(zones) == 1 else pair.contact_zone(zone_index)
        return jnp.stack(_contact_coefficients(zone, sections, *args, material, decay_length))

    zone = jnp.broadcast_to(tca.pair_zone[None, :], gaps.shape)
    return contact, jnp.vectorize(coefficients, signature="(),(),(),(),(),(),(),(3),()->(4)")(
        zone, k, phi1, u1, u2, z, te, normal, frac)


def point_contact_analysis(pair, tca: TCAResult, torque: ArrayLike, material: Material | None = None,
                           coupling_length_mn: float = 1.1,
                           sections: tuple[ToothSection, ToothSection] | None = None,
                           active_pairs: Bool[Array, " pair"] | None = None) -> PointContactLoads:
    """Loaded contact of a `DoubleArcGearPair` over the TCA's positions.

    Each contact is located between the TCA's face slices, the face ends among them, by a
    parabola through three of them (`closest_contact`), so the slices must be close
    compared with the width of a point contact's peak (decision 0009 measures which grids
    converge: the `fast` preset's 9 slices do not).

    Args:
        pair: the resolved pair.
        tca: its `tooth_contact_analysis`.
        torque: pinion torque $T_1$ (N·mm).
        material: both gears' (default `Material()`, built at the call so that it takes
            the precision in force then).
        coupling_length_mn: the decay length $\\lambda$ of a point load along the face, in
            $m_n$ (as `SliceCompliance`).
        sections: the two teeth's `ToothSection`s; sampled from the pair if None.
        active_pairs: optional mask over the TCA's tooth pairs; the others carry no load.

    Returns:
        `PointContactLoads`.
    """
    material = Material() if material is None else material
    contact, coefficients = point_coefficients(pair, tca, material, coupling_length_mn, sections)
    j, gaps, z, frac = (contact[name] for name in ("slice", "gap", "z", "frac"))
    if active_pairs is not None:
        gaps = jnp.where(active_pairs, gaps, jnp.inf)
    finite = jnp.isfinite(gaps)
    # pairs out of mesh have no contact: unit coefficients keep their (zero) loads finite
    coefficients = jnp.where(finite[..., None], coefficients, 1.0)
    hertz, linear = coefficients[..., 0], coefficients[..., 1]
    arms = tca.action_radius[1] * jnp.where(finite, frac, 1.0)
    gear_torque = torque * pair.teeth[1] / pair.teeth[0]
    rotation, loads = share_load(gear_torque, gaps, arms, linear, hertz)
    cube = jnp.cbrt(loads)
    safe = jnp.where(cube > 0.0, cube, 1.0)
    stiffness = jnp.where(cube > 0.0, safe / (linear * safe + 2.0 / 3.0 * hertz), 0.0)
    modulus = effective_modulus(material.youngs_modulus, material.poisson_ratio)
    contact = hertz_point_contact(loads, coefficients[..., 2], coefficients[..., 3], modulus)
    return PointContactLoads(
        rotation=rotation,
        transmission_error=tca.transmission_error - rotation,
        loads=loads,
        stiffness=stiffness,
        mesh_stiffness=jnp.sum(arms**2 * stiffness, axis=-1),
        semi_major=contact.semi_major,
        semi_minor=contact.semi_minor,
        curvature_a=coefficients[..., 2],
        curvature_b=coefficients[..., 3],
        max_pressure=contact.max_pressure,
        linear_compliance=linear,
        hertz_coefficient=hertz,
        gaps=gaps,
        arms=arms,
        slice_index=j,
        axial_position=z,
    )
