r"""Unloaded tooth contact analysis over a mesh cycle.

For pinion angles $\varphi_1$ over one angular pitch, every tooth pair $k$ of the window and
every transverse slice $z_j$, the slice problem (`_slice.py`) gives the gear offset at which
that slice touches. The gear is pushed by the pinion, so it sits at the largest offset of
all slices of all pairs: that is the transmission error

$$\mathrm{TE}(\varphi_1) = \varphi_2 - \tfrac{z_1}{z_2}\varphi_1 = \max_{k, j}\,\Delta_{kj}(\varphi_1)$$

(rad, gear 2; negative when the gear lags). Over the slice midpoints the maximum is refined
by the vertex of the parabola through the best slice and its neighbours, exact for the
parabolic gap of crowned flanks; the two face ends are edge candidates. The normal gap of
every other slice to the binding one is its *initial separation* (mm), the input of LTCA.

Two methods (`Accuracy.tca_method`):

* `"surface"`: the general TCA on the real flanks, edge contact included (any family).
* `"plane_of_action"`: involute families only; the contact point of slice $j$ of pair $k$
  is the conjugate point on the plane of action and its separation is the sum of both
  flanks' depths there. It is first order in the depths: a depth slope $\delta'$ (per unit
  roll length $s$) tilts the flank normal, so the true tangency leaves the plane of action
  and the gap shrinks by about $\tfrac12\rho_\text{rel}(r_b/s)^2\delta'^2$, with
  $\rho_\text{rel} = s_1s_2/(s_1+s_2)$; near the pinion root this is a sizeable fraction
  of a relief (0.46 of 2.9 um for seed 001's root relief), which the surface method
  resolves. It also has no edge contact.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import lineax as lx
import optimistix as optx

from .._custom_types import Array, Bool, Float, Int
from .._numerics import as_float, rotate2, safe_divide
from .._solution import RESULTS, enum_name, first_failure
from ..accuracy import Accuracy
from ..geometry._base import AbstractGearPair
from ..geometry.depth import FlankDepth
from ._slice import FLANK, ContactKind, SliceContact, _contact_residual, contact_kind, make_problem, solve_slice


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
        unconverged: relevant candidate solves that failed, per slice (0 to 3); their
            candidates are excluded, so a non-zero count flags a possibly missed contact.
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

    @property
    def kind_name(self):
        """Names of `kind` ("flank", "gear_tip_edge", "pinion_tip_edge"), an array of
        str of shape (pos, pair, slice); needs a concrete result."""
        return enum_name(self.kind)


def _tca_result(unconverged) -> RESULTS:
    return first_failure((jnp.any(unconverged > 0), RESULTS.tca_unconverged))


def positions(pair: AbstractGearPair, accuracy: Accuracy, pitches: int = 1) -> Float[Array, " pos"]:
    """Pinion angles (rad): `positions_per_pitch` per angular pitch, centred on 0."""
    n = accuracy.positions_per_pitch * pitches
    step = pair.angular_pitch(0) / accuracy.positions_per_pitch
    start = -0.5 * pitches * pair.angular_pitch(0)
    return as_float(start + step * np.arange(n))


def face_slices(pair: AbstractGearPair, accuracy: Accuracy) -> tuple[Array, Array]:
    """Slice positions (midpoints, then the two face ends) and the width each represents."""
    n = accuracy.face_slices
    b = pair.face_width
    fractions = (np.arange(n) + 0.5) / n - 0.5
    z = jnp.concatenate([b[..., None] * fractions, jnp.stack([-0.5 * b, 0.5 * b], -1)], -1)
    width = jnp.concatenate([jnp.broadcast_to(b[..., None] / n, b.shape + (n,)), jnp.zeros(b.shape + (2,))], -1)
    return z, width


def pair_window(pair: AbstractGearPair, pitches: int = 1, margin: int = 1) -> tuple[int, ...]:
    """Tooth pairs that can touch during the cycle (static; needs concrete geometry).

    Pair $k$ is in the window if its nominal contact lies on both active flanks for some
    position of the cycle and some slice, widened by `margin` pairs on each side for the
    edge contacts of approaching and receding teeth.
    """
    zones = pair.contact_zones()
    if len(zones) > 1:
        window = sorted(set().union(*(pair_window(zone, pitches, margin) for zone in zones)))
        return tuple(range(window[0], window[-1] + 1))
    pair = zones[0].resolve()
    grid = np.linspace(-math.pi, math.pi, 8001)
    u1, u2 = jax.vmap(pair.contact_guess)(as_float(grid))
    lo1, hi1 = pair.profile_limits(0)
    lo2, hi2 = pair.profile_limits(1)
    ok = (
        (np.asarray(u1) >= np.asarray(lo1)) & (np.asarray(u1) <= np.asarray(hi1))
        & (np.asarray(u2) >= np.asarray(lo2)) & (np.asarray(u2) <= np.asarray(hi2))
    )
    ok = ok.reshape(ok.shape[0], -1).any(axis=1)
    if not ok.any():
        raise ValueError("the pair has no active contact: check its geometry")
    angle_lo, angle_hi = grid[ok].min(), grid[ok].max()
    b = np.max(np.asarray(pair.face_width))
    leads = np.asarray(jax.vmap(lambda z: pair.lead_rotation(0, z))(as_float(np.linspace(-b / 2, b / 2, 41))))
    p = 2 * math.pi / pair.teeth[0]
    phi_lo, phi_hi = -0.5 * pitches * p, 0.5 * pitches * p
    k_lo = math.ceil((phi_lo + leads.min() - angle_hi) / p) - margin
    k_hi = math.floor((phi_hi + leads.max() - angle_lo) / p) + margin
    return tuple(range(k_lo, k_hi + 1))


def tooth_contact_analysis(
    pair: AbstractGearPair,
    depth: FlankDepth | None = None,
    *,
    accuracy: Accuracy = Accuracy(),
    pairs: tuple[int, ...] | None = None,
    pitches: int = 1,
    pinion_angles: Float[Array, " pos"] | None = None,
) -> TCAResult:
    """Unloaded TCA of `pair` over `pitches` angular pitches of the pinion.

    Args:
        pair: the gear pair (any tooth family; several contact zones are analysed one by
            one and merged, `merge_zones`).
        depth: modifications and errors (`FlankDepth`); None for perfect flanks.
        accuracy: discretisation and solver settings (static).
        pairs: the tooth-pair window (static); derived from the geometry if omitted
            (then `pair` must be concrete, i.e. not traced).
        pitches: number of angular pitches covered by the positions.
        pinion_angles: evaluate at these pinion angles (rad) instead of the cycle grid
            (e.g. to differentiate with respect to the pinion angle).

    Returns:
        `TCAResult`.
    """
    zones = pair.contact_zones()
    if len(zones) > 1:
        # Families with several contact zones per tooth (double circular arc: convex and
        # concave driving tooth): one analysis per zone, merged along the pair axis.
        results = [
            tooth_contact_analysis(zone, depth, accuracy=accuracy, pairs=pairs, pitches=pitches, pinion_angles=pinion_angles)
            for zone in zones
        ]
        return merge_zones(results)
    pair = zones[0].resolve()
    depth = FlankDepth() if depth is None else depth
    if pinion_angles is not None:
        phi = as_float(pinion_angles)
        if pairs is None:
            span = np.max(np.abs(np.asarray(phi))) / (math.pi / pair.teeth[0])
            pairs = pair_window(pair, max(1, math.ceil(span)))
    else:
        phi = positions(pair, accuracy, pitches)
    if pairs is None:
        pairs = pair_window(pair, pitches)
    z, width = face_slices(pair, accuracy)
    ks = jnp.asarray(pairs)

    if accuracy.tca_method == "surface":
        solver = optx.Newton(rtol=accuracy.newton_rtol, atol=accuracy.newton_atol)

        def one(phi1, k, zz):
            return solve_slice(make_problem(pair, depth, k, zz, phi1), solver, accuracy.newton_max_steps)

    else:
        if not pair.conjugate_slices:
            raise ValueError(
                f"tca_method='plane_of_action' needs an involute family; {type(pair).__name__} "
                "has no plane of action: use tca_method='surface'"
            )

        def one(phi1, k, zz):
            return _plane_of_action_slice(pair, depth, k, zz, phi1)

    contact = jax.vmap(jax.vmap(jax.vmap(one, (None, None, 0)), (None, 0, None)), (0, None, None))(phi, ks, z)
    return _assemble(
        pair, depth, phi, ks, z, width, contact, accuracy.face_slices, accuracy.tca_method == "surface"
    )


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


def _plane_of_action_slice(pair, depth, k, z, phi1) -> SliceContact:
    """Fast path: conjugate contact point, separation = sum of the flanks' depths."""
    problem = make_problem(pair, depth, k, z, phi1)
    u1, u2 = pair.contact_guess(problem.pinion_rotation)
    lo1, hi1 = pair.profile_limits(0)
    lo2, hi2 = pair.profile_limits(1)
    ok = (u1 >= lo1) & (u1 <= hi1) & (u2 >= lo2) & (u2 <= hi2)
    total = depth(pair, 0, problem.pair_index, u1, z) / pair.transverse_normal_fraction(0, u1, z)
    total = total + depth(pair, 1, problem.pair_index, u2, z) / pair.transverse_normal_fraction(1, u2, z)
    offset = -total / pair.action_radius(1)
    return SliceContact(
        offset=jnp.where(ok, offset, -jnp.inf),
        pinion_parameter=u1,
        gear_parameter=u2,
        kind=jnp.asarray(FLANK),
        valid=ok,
        unconverged=jnp.asarray(0),
    )


def _peak_correction(residual, y, z, lead_correction, half_width, limits) -> Array:
    """Rise of the slice value $g(z)$ from the best slice to the peak between slices.

    One Newton step on $g'(z) = 0$ from the best slice $z^*$: $t = -g'/g''$, clipped to
    half a slice width and to the stretch on which the contact's parameters stay on the
    active flanks (so it never extrapolates past the end of a contact line), rise
    $g't + \\tfrac12 g''t^2 \\ge 0$. Exact for the parabolic ($C^1$) reliefs and
    crowning, whose parabolas peak at their start points; zero on a plateau
    ($g' = g'' = 0$) and wherever $g$ is not concave.

    The derivatives of the solution $y(z)$ of $F(y, z) = 0$ follow from the implicit
    function theorem on the explicit residual (no second trace of the Newton solver):
    $y' = -J^{-1}F_z$, $y'' = -J^{-1}\\,\\mathrm{d}^2F(y + t y', z + t)/\\mathrm{d}t^2$.
    """
    jac = jax.jacfwd(residual, 0)(y, z)
    operator = lx.MatrixLinearOperator(jac)
    _, f_z = jax.jvp(lambda zz: residual(y, zz), (z,), (jnp.ones_like(z),))
    dy = -lx.linear_solve(operator, f_z, throw=False).value

    def along(t):
        return residual(y + t * dy, z + t)

    def first(t):
        return jax.jvp(along, (t,), (jnp.ones_like(t),))[1]

    zero = jnp.zeros_like(z)
    second = jax.jvp(first, (zero,), (jnp.ones_like(zero),))[1]
    d2y = -lx.linear_solve(operator, second, throw=False).value
    _, lc1 = jax.jvp(lead_correction, (z,), (jnp.ones_like(z),))
    lc2 = jax.jvp(lambda zz: jax.jvp(lead_correction, (zz,), (jnp.ones_like(zz),))[1], (z,), (jnp.ones_like(z),))[1]
    low, high = _room(y[:2], dy[:2], limits, half_width)
    return _newton_rise(dy[2] + lc1, d2y[2] + lc2, low, high)


def _explicit_peak_correction(value, params, z, half_width, limits) -> Array:
    """`_peak_correction` for an explicit slice value $g(z)$ with contact parameters
    `params(z)` (plane-of-action path)."""

    def first(zz):
        return jax.jvp(value, (zz,), (jnp.ones_like(zz),))[1]

    d1, d2 = jax.jvp(first, (z,), (jnp.ones_like(z),))
    u, du = jax.jvp(params, (z,), (jnp.ones_like(z),))
    low, high = _room(u, du, limits, half_width)
    return _newton_rise(d1, d2, low, high)


def _room(u, rate, limits, half_width):
    """Largest steps (down, up) in $z$ before a parameter moving at `rate` leaves its
    limits, capped at `half_width`."""
    lo = jnp.stack([limits[0][0], limits[1][0]])
    hi = jnp.stack([limits[0][1], limits[1][1]])
    up = jnp.where(rate > 0, safe_divide(hi - u, rate, jnp.inf), jnp.where(rate < 0, safe_divide(lo - u, rate, jnp.inf), jnp.inf))
    down = jnp.where(rate > 0, safe_divide(u - lo, rate, jnp.inf), jnp.where(rate < 0, safe_divide(u - hi, rate, jnp.inf), jnp.inf))
    return jnp.clip(jnp.min(down), 0.0, half_width), jnp.clip(jnp.min(up), 0.0, half_width)


def _newton_rise(d1, d2, low, high) -> Array:
    concave = d2 < 0
    step = jnp.clip(safe_divide(-d1, jnp.where(concave, d2, -1.0)), -low, high)
    rise = d1 * step + 0.5 * d2 * step**2
    return jnp.where(concave & jnp.isfinite(rise), jnp.maximum(rise, 0.0), 0.0)


def _assemble(pair, depth, phi, ks, z, width, contact: SliceContact, n_mid: int, surface: bool) -> TCAResult:
    ratio = 1.0 / pair.gear_ratio

    def lead_correction(zz):
        return ratio * pair.lead_rotation(0, zz) - pair.lead_rotation(1, zz)

    slice_te = contact.offset + lead_correction(z)
    valid = contact.valid
    kind = contact.kind

    masked = jnp.where(valid[..., :n_mid], slice_te[..., :n_mid], -jnp.inf)
    best = jnp.argmax(masked, axis=-1)  # (pos, pair)
    mid = jnp.max(masked, axis=-1)
    if n_mid >= 3:
        half = 0.5 * pair.face_width / n_mid
        limits = (pair.profile_limits(0), pair.profile_limits(1))

        def correction(phi1, k, j, u1, u2, offset, kind_j):
            if not surface:

                def value(zz):
                    return _plane_of_action_slice(pair, depth, k, zz, phi1).offset + lead_correction(zz)

                def params(zz):
                    c = _plane_of_action_slice(pair, depth, k, zz, phi1)
                    return jnp.stack([c.pinion_parameter, c.gear_parameter])

                return _explicit_peak_correction(value, params, z[..., j], half, limits)

            selector = jax.nn.one_hot(kind_j, 3, dtype=u1.dtype)

            def residual(y, zz):
                return _contact_residual(y, (make_problem(pair, depth, k, zz, phi1), selector, y, True))

            y = jnp.stack([u1, u2, offset])
            rise = _peak_correction(residual, y, z[..., j], lead_correction, half, limits)
            if pair.linear_lead:
                return rise
            # A curved lead bends the tip edges' offsets g(z) far from a parabola, so one
            # Newton step would overshoot (seen: +4e-4 rad on a conjugate curvilinear pair);
            # edge candidates then keep their slice value.
            return jnp.where(kind_j == FLANK, rise, 0.0)

        def pick(a):
            return jnp.take_along_axis(a[..., :n_mid], best[..., None], -1)[..., 0]

        rise = jax.vmap(jax.vmap(correction, (None, 0, 0, 0, 0, 0, 0)), (0, None, 0, 0, 0, 0, 0))(
            phi, as_float(ks), best, pick(contact.pinion_parameter), pick(contact.gear_parameter),
            jnp.where(jnp.isfinite(mid), pick(contact.offset), 0.0), pick(kind),
        )
        mid = mid + jnp.where(jnp.isfinite(mid), rise, 0.0)
    ends = jnp.max(jnp.where(valid[..., n_mid:], slice_te[..., n_mid:], -jnp.inf), axis=-1)
    pair_te = jnp.maximum(mid, ends)
    te = jnp.max(pair_te, axis=-1)

    # Geometry of every slice contact: points, normals, relative velocity.
    def points(phi1, k, zz, u1, u2, te_slice):
        rot1 = phi1 - k * pair.angular_pitch(0)
        rot2 = ratio * phi1 - k * pair.angular_pitch(1) + te_slice

        def surface1(uz):
            d = depth(pair, 0, k, uz[0], uz[1])
            return pair.flank_point(0, uz[0], uz[1], rot1, d)

        x1 = surface1(jnp.stack([u1, zz]))
        jac = jax.jacfwd(surface1)(jnp.stack([u1, zz]))
        n = jnp.cross(jac[:, 0], jac[:, 1])
        n = n / jnp.linalg.norm(n)
        # Orient outwards: along the planar outward normal of the pinion profile.
        planar_out = pair.profile_normal(0, u1)
        sense = jnp.sign(jnp.dot(n[:2], rotate2(rot1 + pair.lead_rotation(0, zz), planar_out)))
        n = n * jnp.where(sense == 0, 1.0, sense)
        x2 = pair.flank_point(1, u2, zz, rot2, depth(pair, 1, k, u2, zz))
        omega1 = jnp.array([0.0, 0.0, 1.0], dtype=x1.dtype)
        omega2 = jnp.array([0.0, 0.0, -ratio], dtype=x1.dtype)
        o2 = jnp.concatenate([pair.center(1), jnp.zeros((1,), x1.dtype)])
        v12 = jnp.cross(omega1, x1) - jnp.cross(omega2, x1 - o2)
        frac = pair.transverse_normal_fraction(0, u1, zz)
        return x1, x2, n, v12, frac

    safe_te = jnp.where(valid, slice_te, 0.0)
    geo = jax.vmap(
        jax.vmap(jax.vmap(points, (None, None, 0, 0, 0, 0)), (None, 0, None, 0, 0, 0)),
        (0, None, None, 0, 0, 0),
    )(phi, as_float(ks), z, contact.pinion_parameter, contact.gear_parameter, safe_te)
    x1, x2, normal, v12, frac = geo

    radius = pair.action_radius(1)
    gap = (te[:, None, None] - safe_te) * radius * frac
    separation = jnp.where(valid, gap, jnp.inf)
    return TCAResult(
        pinion_angle=phi,
        transmission_error=te,
        pair_index=ks,
        pair_zone=jnp.zeros(ks.shape, dtype=ks.dtype),
        slice_z=z,
        slice_width=width,
        slice_te=slice_te,
        valid=valid,
        kind=contact_kind(kind),
        pinion_parameter=contact.pinion_parameter,
        gear_parameter=contact.gear_parameter,
        pinion_point=x1,
        gear_point=x2,
        normal=normal,
        relative_velocity=v12,
        separation=separation,
        transverse_normal_fraction=frac,
        action_radius=jnp.stack([pair.action_radius(0), radius], -1),
        unconverged=contact.unconverged,
        result=_tca_result(contact.unconverged),
    )
