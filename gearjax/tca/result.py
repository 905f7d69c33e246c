"""`TCAResult`: the unloaded contact over a mesh cycle, and the merge of contact zones."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, Bool, Float, Int
from .._solution import RESULTS, enum_name, first_failure
from ._slice_problem import ContactKind


class TCAResult(eqx.Module):
    """Unloaded contact over a mesh cycle. Axes: position, pair, slice.

    Units: angular transmission-error quantities are in rad (gear 2) and carry no suffix;
    the same quantity along the transverse line of action, $r_{b2}$ times the angle, is in
    mm and carries the suffix `_line` (`transmission_error` / `transmission_error_line`,
    `te_peak_to_peak` / `te_peak_to_peak_line`).

    Attributes:
        pinion_angle: $\\varphi_1$ (rad), shape (pos,).
        transmission_error: angular TE of gear 2, $\\varphi_2 - \\varphi_1 z_1/z_2$ (rad).
        pair_index: tooth pairs $k$ of the window (pair $k$ meshes $k$ pitches after pair 0).
        pair_zone: contact zone of each entry of the pair axis (0 for single-zone
            families; double circular arc: 0 convex, 1 concave driving tooth).
        slice_z: axial slice positions (mm): the midpoints, then the face ends $\\mp b/2$.
        slice_width: face width represented by each slice (mm; 0 for the face ends).
        slice_te: TE at which each slice would touch (rad); meaningful where `valid`.
        valid: the slice has a contact on the active flanks.
        kind: `ContactKind` of every slice contact (flank, gear_tip_edge,
            pinion_tip_edge); compare with `==`, names by `kind_name`.
        pinion_parameter, gear_parameter: profile parameters of the contact (mm).
        pinion_point, gear_point: contact point on each flank, fixed frame (mm), with the
            gear turned to the slice's own touching position.
        normal: outward unit normal of the pinion flank at the contact (fixed frame).
        relative_velocity: $v^{(12)}$ at the contact per unit pinion speed, nominal ratio
            (mm/rad).
        separation: normal gap to the binding contact (mm); `inf` where not valid.
        transverse_normal_fraction: $|n_t|$ at the contact (converts normal to transverse).
        action_radius: $(r_{b1}, r_{b2})$ (mm), shape (2,): the radii converting the
            angles of pinion and gear to the transverse line of action (base radii for
            involute flanks).
        unconverged: relevant candidate solves that failed with their last iterate on the
            active flanks, per slice (0 to 3); their candidates are excluded, so a
            non-zero count flags a possibly missed contact. (A failed solve whose iterate
            left the active flanks is not counted: its contact would be rejected anyway.)
        result: `RESULTS.successful`, or `RESULTS.tca_unconverged` where some count of
            `unconverged` is non-zero (a warning: the other contacts are valid).
    """

    pinion_angle: Float[Array, " pos"]
    transmission_error: Float[Array, " pos"]
    pair_index: Int[Array, " pair"]
    pair_zone: Int[Array, " pair"]
    slice_z: Float[Array, " slice"]
    slice_width: Float[Array, " slice"]
    slice_te: Float[Array, "pos pair slice"]
    valid: Bool[Array, "pos pair slice"]
    kind: ContactKind
    pinion_parameter: Float[Array, "pos pair slice"]
    gear_parameter: Float[Array, "pos pair slice"]
    pinion_point: Float[Array, "pos pair slice 3"]
    gear_point: Float[Array, "pos pair slice 3"]
    normal: Float[Array, "pos pair slice 3"]
    relative_velocity: Float[Array, "pos pair slice 3"]
    separation: Float[Array, "pos pair slice"]
    transverse_normal_fraction: Float[Array, "pos pair slice"]
    action_radius: Float[Array, "2"]
    unconverged: Int[Array, "pos pair slice"]
    result: RESULTS

    @property
    def transmission_error_line(self) -> Float[Array, " pos"]:
        """TE along the (transverse) line of action, $r_{b2}\\,\\mathrm{TE}$ (mm)."""
        return self.transmission_error * self.action_radius[..., 1, None]

    @property
    def te_peak_to_peak(self) -> Float[Array, ""]:
        """Peak-to-peak angular TE over the cycle (rad)."""
        return jnp.max(self.transmission_error, -1) - jnp.min(self.transmission_error, -1)

    @property
    def te_peak_to_peak_line(self) -> Float[Array, ""]:
        """Peak-to-peak TE along the line of action (mm)."""
        return self.te_peak_to_peak * self.action_radius[..., 1]

    @property
    def binding(self) -> tuple[Int[Array, " pos"], Int[Array, " pos"]]:
        """(pair, slice) indices of the binding contact at each position."""
        flat = jnp.where(self.valid, self.slice_te, -jnp.inf).reshape(self.valid.shape[0], -1)
        idx = jnp.argmax(flat, axis=-1)
        return idx // self.valid.shape[2], idx % self.valid.shape[2]

    def in_contact(self, tolerance: float = 1e-6) -> Bool[Array, "pos pair slice"]:
        """Slices whose separation is below `tolerance` (mm): the contact lines."""
        return self.valid & (self.separation <= tolerance)

    def position(self, index: int) -> TCAResult:
        """The result at grid position `index` alone (a position axis of length 1)."""
        def fields(r):
            return [getattr(r, name) for name in _PER_POSITION]

        taken = [jax.tree_util.tree_map(lambda x: x[index:index + 1], x) for x in fields(self)]
        one = eqx.tree_at(fields, self, taken)
        return eqx.tree_at(lambda r: r.result, one, _tca_result(one.unconverged))

    @property
    def kind_name(self):
        """Names of `kind` ("flank", "gear_tip_edge", "pinion_tip_edge"), an array of
        str of shape (pos, pair, slice); needs a concrete result."""
        return enum_name(self.kind)


#: the fields of `TCAResult` with a leading position axis
_PER_POSITION = ("pinion_angle", "transmission_error", "slice_te", "valid", "kind", "pinion_parameter", "gear_parameter",
                 "pinion_point", "gear_point", "normal", "relative_velocity", "separation",
                 "transverse_normal_fraction", "unconverged")


def _tca_result(unconverged) -> RESULTS:
    return first_failure((jnp.any(unconverged > 0), RESULTS.tca_unconverged))


def merge_zones(results: list[TCAResult]) -> TCAResult:
    """One result from per-zone analyses: the pair axis holds zone 0's pairs, then zone
    1's (`pair_zone` tells them apart); TE is the largest of the zones' and every
    separation is re-measured from it."""
    te = jnp.max(jnp.stack([r.transmission_error for r in results]), axis=0)

    def cat(name, axis):  # arrays and enumeration items (pytrees) alike
        return jax.tree_util.tree_map(lambda *xs: jnp.concatenate(xs, axis=axis), *[getattr(r, name) for r in results])

    slice_te = cat("slice_te", -2)
    valid = cat("valid", -2)
    frac = cat("transverse_normal_fraction", -2)
    radius = results[0].action_radius
    gap = (te[..., :, None, None] - jnp.where(valid, slice_te, 0.0)) * radius[..., 1, None, None, None] * frac
    fields = {name: cat(name, -2) for name in ("slice_te", "valid", "kind", "pinion_parameter", "gear_parameter", "unconverged")}
    fields.update({name: cat(name, -3) for name in ("pinion_point", "gear_point", "normal", "relative_velocity")})
    return TCAResult(
        pinion_angle=results[0].pinion_angle,
        transmission_error=te,
        pair_index=cat("pair_index", -1),
        pair_zone=jnp.concatenate([jnp.full(r.pair_index.shape, i) for i, r in enumerate(results)]),
        slice_z=results[0].slice_z,
        slice_width=results[0].slice_width,
        separation=jnp.where(valid, gap, jnp.inf),
        transverse_normal_fraction=frac,
        action_radius=radius,
        result=_tca_result(fields["unconverged"]),
        **fields,
    )
