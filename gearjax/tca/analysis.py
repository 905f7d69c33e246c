r"""Unloaded tooth contact analysis over a mesh cycle.

For pinion angles $\varphi_1$ over one angular pitch, every tooth pair $k$ of the window and
every transverse slice $z_j$, the slice problem (`_slice_problem.py`, solved in `_slice.py`) gives the gear offset at which
that slice touches. The gear is pushed by the pinion, so it sits at the largest offset of
all slices of all pairs: that is the transmission error

$$\mathrm{TE}(\varphi_1) = \varphi_2 - \tfrac{z_1}{z_2}\varphi_1 = \max_{k, j}\,\Delta_{kj}(\varphi_1)$$

(rad, gear 2; negative when the gear lags). Over the slice midpoints the maximum is refined
between slices (`peak.py`); the two face ends are edge candidates. The normal gap of
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

import functools as ft
import math

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._custom_types import Array, Float
from ._newton import SafeguardedNewton
from .._numerics import as_float, rotate2
from ..accuracy import Accuracy
from ..geometry._base import AbstractGearPair
from ..geometry.depth import FlankDepth
from ._slice import attach_derivatives, select_contact, solve_again, solve_candidates
from ._slice_problem import FLANK, SliceContact, _contact_residual, contact_kind, make_problem
from .branch import Branch
from .grid import face_slices, nested_vmap, pair_window, positions
from .peak import explicit_peak_correction, peak_correction
from .result import TCAResult, _tca_result, merge_zones


def tooth_contact_analysis(
    pair: AbstractGearPair,
    depth: FlankDepth | None = None,
    *,
    accuracy: Accuracy = Accuracy(),
    pairs: tuple[int, ...] | None = None,
    pitches: int = 1,
    pinion_angles: Float[Array, " pos"] | None = None,
    refine_peak: bool = True,
) -> TCAResult:
    """Unloaded TCA of `pair` over `pitches` angular pitches of the pinion.

    Args:
        pair: the gear pair (any tooth family; several contact zones are analysed in one
            `vmap` over the zone index, or one by one where `pairs` is not given, and
            merged, `merge_zones`).
        depth: modifications and errors (`FlankDepth`); None for perfect flanks.
        accuracy: discretisation and solver settings (static).
        pairs: the tooth-pair window (static); derived from the geometry if omitted
            (then `pair` must be concrete, i.e. not traced).
        pitches: number of angular pitches covered by the positions.
        pinion_angles: evaluate at these pinion angles (rad) instead of the cycle grid
            (e.g. to differentiate with respect to the pinion angle).
        refine_peak: refine each pair's largest midpoint value to its peak between the
            slices (`tca.peak`; with at least 3 slices). False keeps the largest slice
            value: a smaller program for callers that use only differences to the TE,
            such as the loaded TE (the LTCA's separations and its rotation count from the
            same TE, so the loaded TE depends on it only where a contact normal's moment
            arm about the gear axis differs from $r_{b2}$ times its transverse fraction:
            modified flanks and edge contacts, a small fraction of the shift).

    Returns:
        `TCAResult`.
    """
    zones = pair.contact_zones()
    if len(zones) == 1:
        return _zone_analysis(zones[0], depth, accuracy, pairs, pitches, pinion_angles, refine_peak)
    # Families with several contact zones per tooth (double circular arc: convex and concave
    # driving tooth): one analysis per zone, merged along the pair axis; with a given
    # window, all zones in one `vmap` over the zone index (one trace; `contact_zone` takes
    # an integer array wherever `contact_zones` has several).
    if pairs is None:  # `pair_window` needs concrete zones
        return merge_zones([_zone_analysis(zone, depth, accuracy, pairs, pitches, pinion_angles, refine_peak)
                            for zone in zones])

    def zone(index):
        return _zone_analysis(pair.contact_zone(index), depth, accuracy, pairs, pitches, pinion_angles, refine_peak,
                              "zone")

    results = jax.vmap(zone, axis_name="zone")(jnp.arange(len(zones)))
    return merge_zones([jax.tree_util.tree_map(lambda x: x[i], results) for i in range(len(zones))])


def _zone_analysis(pair, depth, accuracy, pairs, pitches, pinion_angles, refine_peak, zone_axis=None) -> TCAResult:
    """`tooth_contact_analysis` of one contact zone; `zone_axis` names the `vmap` axis
    over the zones, if any (the fallback then runs for all of them or none)."""
    pair = pair.resolve()
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
        contact = solve_grid(pair, depth, accuracy, phi, ks, z, zone_axis)
        return _assemble(pair, depth, phi, ks, z, width, contact, accuracy.face_slices, True, refine_peak)
    if not pair.conjugate_slices:
        raise ValueError(
            f"tca_method='plane_of_action' needs an involute family; {type(pair).__name__} "
            "has no plane of action: use tca_method='surface'"
        )
    contact = on_grid(lambda phi1, k, zz: _plane_of_action_slice(pair, depth, k, zz, phi1), phi, ks, z)
    return _assemble(pair, depth, phi, ks, z, width, contact, accuracy.face_slices, False, refine_peak)


def on_grid(f, phi, ks, z, *fields):
    """`f(phi1, k, z, *fields)` over pinion angles `phi` (pos,), pairs `ks` (pair,) and
    slices `z` (slice,); `fields` are per slice, with leading axes (pos, pair, slice)."""
    rest = (0,) * len(fields)
    return nested_vmap(f, [(0, None, None, *rest), (None, 0, None, *rest), (None, None, 0, *rest)], phi, ks, z, *fields)


def solve_grid(pair, depth, accuracy: Accuracy, phi, ks, z, zone_axis=None, branch: Branch | None = None
               ) -> SliceContact:
    """The general TCA's first contact of every slice, (pos, pair, slice): the three
    candidates solved with Newton, the failed ones again with the damped fallback
    (`_retry_failed`), the first contact kept (`select_contact`), all on stop-gradient'ed
    data; the kept contact then gets the derivatives of its own root
    (`attach_derivatives`), so that a derivative of the TCA traces neither the solves nor
    the choice between them. `zone_axis`: as in `_retry_failed`; `branch` holds one pair
    to one branch of the regime switch (`select_contact`)."""
    rtol, atol = accuracy.newton_tolerances(jnp.result_type(phi))
    steps = accuracy.newton_max_steps
    fixed_pair, fixed_depth, fixed_phi, fixed_z = jax.lax.stop_gradient((pair, depth, phi, z))

    def one(phi1, k, zz):
        problem = make_problem(fixed_pair, fixed_depth, k, zz, phi1)
        return solve_candidates(problem, optx.Newton(rtol=rtol, atol=atol), steps)

    candidates = _retry_failed(fixed_pair, fixed_depth, fixed_phi, ks, fixed_z, on_grid(one, fixed_phi, ks, fixed_z),
                               SafeguardedNewton(rtol=rtol, atol=atol), fallback_steps(steps), zone_axis)
    if branch is None:
        contact = nested_vmap(ft.partial(select_contact, fixed_pair), [(0, 0, 0)] * 3, *candidates)
    else:
        contact = on_grid(lambda _, k, __, *c: select_contact(fixed_pair, *c, rule=branch.rule(k)),
                          fixed_phi, ks, fixed_z, *candidates)
    return attach_grid(pair, depth, phi, ks, z, contact)


def attach_grid(pair, depth, phi, ks, z, contact: SliceContact) -> SliceContact:
    """`attach_derivatives` over a grid of slice contacts (pos, pair, slice) found on
    stop-gradient'ed data."""

    def attach(phi1, k, zz, c):
        return attach_derivatives(make_problem(pair, depth, k, zz, phi1), c)

    return on_grid(attach, phi, ks, z, contact)


#: steps of the fallback solver per Newton step allowed (`Accuracy.newton_max_steps`)
FALLBACK_STEPS = 4
#: the fallback's step cap whatever the preset (`fallback_steps`)
FALLBACK_MIN_STEPS = 128


def fallback_steps(newton_max_steps: int) -> int:
    """Step cap of the damped fallback: `FALLBACK_STEPS` per Newton step allowed, at least
    `FALLBACK_MIN_STEPS`. The fallback's problems are the hard ones, and how many steps
    they need does not follow the preset's tolerances: on random 17/170 design 143 of
    `tests/test_hard_cases_ratios.py` (m_n 1 mm, a 0.14 mm root relief near the pinion's
    base circle) the flank contact lies 1 µm inside the relief's end, where the flank's
    curvature jumps by two orders of magnitude, and `SafeguardedNewton` zig-zags across
    it for 40 to 71 steps before it converges, more than `FALLBACK_STEPS` times the `fast`
    preset's Newton cap. Only failed candidates are retried, so a higher cap costs steps
    only where a retried solve does not converge."""
    return max(FALLBACK_STEPS * newton_max_steps, FALLBACK_MIN_STEPS)


def fallback_capacity(candidates: int) -> int:
    """Failed candidate solves retried per analysis: one in 16 of all, at least 32 (a
    fixed size, so the program's shapes stay static)."""
    return min(candidates, max(32, candidates // 16))


def _retry_failed(pair, depth, phi, ks, z, candidates, solver, max_steps, zone_axis=None):
    """Solve the failed candidates of a (positions, pairs, slices, 3) grid again with
    `solver` (`SafeguardedNewton`): plain Newton can cycle where a relief's curvature jumps
    inside the contact's reach (6 of 400 random 29/71 designs missed loaded
    contacts at `fast`). The failures are gathered into a fixed number of problems
    (`fallback_capacity`; failures beyond it stay failed), solved from their starts and
    scattered back, so the fallback costs a few dozen solves whatever the grid's size, and
    every candidate Newton solved keeps its value; a single analysis skips it where none
    failed, but under `vmap` (batched designs, sweeps) the condition is batched and the
    fallback runs for every entry of the batch (so whatever it costs, every batch pays). A flank
    solve that an edge contact proved to have missed an interior contact (`solve_again`)
    starts from that edge contact; such misses are many on designs with deep reliefs (121
    slices of one cycle on random 29/71 design 0), hence one in 16, not 64 as for the
    Newton cycles alone. Under a `vmap` over contact zones named `zone_axis` the condition
    counts the failures of all zones, so it stays unbatched: the fallback runs for every
    zone or for none."""
    shape = candidates[2].shape

    def retry(candidates):
        values, converged, failed = candidates
        (index,) = jnp.nonzero(failed.reshape(-1), size=fallback_capacity(failed.size), fill_value=-1)
        a, b, c, kind = jnp.unravel_index(jnp.maximum(index, 0), shape)
        taken = index >= 0

        def again(a, b, c, kind, taken):
            return solve_again(make_problem(pair, depth, ks[b], z[c], phi[a]), kind, solver, max_steps, taken,
                               values[a, b, c], converged[a, b, c])

        # Padding entries solve a trivial problem, so that they cost the fallback one step,
        # not its whole step budget.
        value, ok, still = jax.vmap(again)(a, b, c, kind, taken)
        # Padding entries (index -1) scatter out of bounds and are dropped.
        target = jnp.where(taken, index, failed.size)
        scatter = lambda full, part: full.reshape(-1, *full.shape[len(shape):]).at[target].set(part, mode="drop").reshape(full.shape)  # noqa: E731
        return scatter(values, value), scatter(converged, ok & taken), scatter(failed, still & taken)

    # A grid without failures (nearly every one) skips the fallback; under `vmap` the
    # condition is batched and both branches run, as without it.
    failures = jnp.sum(candidates[2])
    if zone_axis is not None:
        failures = jax.lax.psum(failures, zone_axis)
    return jax.lax.cond(failures > 0, retry, lambda candidates: candidates, candidates)


def _plane_of_action_slice(pair, depth, k, z, phi1) -> SliceContact:
    """Fast path: conjugate contact point, separation = sum of the flanks' depths."""
    problem = make_problem(pair, depth, k, z, phi1)
    u1, u2 = pair.contact_guess(problem.pinion_rotation)
    lo1, hi1 = pair.profile_limits(0)
    lo2, hi2 = pair.profile_limits(1)
    ok = (u1 >= lo1) & (u1 <= hi1) & (u2 >= lo2) & (u2 <= hi2)
    total = depth.transverse(pair, 0, problem.pair_index, u1, z) + depth.transverse(pair, 1, problem.pair_index, u2, z)
    offset = -total / pair.action_radius(1)
    return SliceContact(
        offset=jnp.where(ok, offset, -jnp.inf),
        pinion_parameter=u1,
        gear_parameter=u2,
        kind=jnp.asarray(FLANK),
        valid=ok,
        unconverged=jnp.asarray(0),
    )


def _lead_correction(pair, z):
    """Gear offset that the leads of both flanks add at axial `z` (rad)."""
    return pair.lead_rotation(0, z) / pair.gear_ratio - pair.lead_rotation(1, z)


def _peak_rise(pair, depth, phi, ks, z, contact: SliceContact, best, found, n_mid: int, surface: bool):
    """Rise of each pair's binding midpoint value (slice `best`, where `found`) to its peak
    between slices, (pos, pair)."""
    half = 0.5 * pair.face_width / n_mid
    limits = (pair.profile_limits(0), pair.profile_limits(1))

    def correction(phi1, k, j, u1, u2, offset, kind_j):
        if not surface:

            def value(zz):
                return _plane_of_action_slice(pair, depth, k, zz, phi1).offset + _lead_correction(pair, zz)

            def params(zz):
                c = _plane_of_action_slice(pair, depth, k, zz, phi1)
                return jnp.stack([c.pinion_parameter, c.gear_parameter])

            return explicit_peak_correction(value, params, z[..., j], half, limits)

        selector = jax.nn.one_hot(kind_j, 3, dtype=u1.dtype)

        def residual(y, zz):
            return _contact_residual(y, (make_problem(pair, depth, k, zz, phi1), selector, y, True))

        y = jnp.stack([u1, u2, offset])
        rise = peak_correction(residual, y, z[..., j], lambda zz: _lead_correction(pair, zz), half, limits)
        if pair.linear_lead:
            return rise
        # A curved lead bends the tip edges' offsets g(z) far from a parabola, so one
        # Newton step would overshoot (seen: +4e-4 rad on a conjugate curvilinear pair);
        # edge candidates then keep their slice value.
        return jnp.where(kind_j == FLANK, rise, 0.0)

    def pick(a):
        return jnp.take_along_axis(a[..., :n_mid], best[..., None], -1)[..., 0]

    return nested_vmap(correction, [(0, None, 0, 0, 0, 0, 0), (None, 0, 0, 0, 0, 0, 0)],
        phi, as_float(ks), best, pick(contact.pinion_parameter), pick(contact.gear_parameter),
        jnp.where(found, pick(contact.offset), 0.0), pick(contact.kind),
    )


def _binding_te(pair, depth, phi, ks, z, contact: SliceContact, slice_te, n_mid: int, surface: bool, refine: bool):
    """TE per position: the largest slice value over pairs, midpoints (refined between
    slices when `refine` and there are at least 3) and face ends."""
    valid = contact.valid
    masked = jnp.where(valid[..., :n_mid], slice_te[..., :n_mid], -jnp.inf)
    mid = jnp.max(masked, axis=-1)  # (pos, pair)
    if refine and n_mid >= 3:
        found = jnp.isfinite(mid)
        rise = _peak_rise(pair, depth, phi, ks, z, contact, jnp.argmax(masked, axis=-1), found, n_mid, surface)
        mid = mid + jnp.where(found, rise, 0.0)
    ends = jnp.max(jnp.where(valid[..., n_mid:], slice_te[..., n_mid:], -jnp.inf), axis=-1)
    return jnp.max(jnp.maximum(mid, ends), axis=-1)


def contact_point(pair, depth, phi1, k, zz, u1, u2, te_slice):
    """One slice contact's points on both flanks, the pinion's outward unit normal, the
    relative velocity per unit pinion speed and $|n_t|$, the gear turned to the slice's own
    touching position `te_slice` (pinion angle `phi1`, pair `k`, axial `zz`)."""
    ratio = 1.0 / pair.gear_ratio
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


def _contact_geometry(pair, depth, phi, ks, z, contact: SliceContact, slice_te):
    """`contact_point` of every slice contact, (pos, pair, slice, ...)."""
    points = ft.partial(contact_point, pair, depth)
    return nested_vmap(points, [(0, None, None, 0, 0, 0), (None, 0, None, 0, 0, 0), (None, None, 0, 0, 0, 0)],
                       phi, as_float(ks), z, contact.pinion_parameter, contact.gear_parameter, slice_te)


def _assemble(pair, depth, phi, ks, z, width, contact: SliceContact, n_mid: int, surface: bool,
              refine: bool) -> TCAResult:
    """The `TCAResult` of the slice contacts: each slice's value with the leads' correction
    (rad), the binding TE (`_binding_te`), each contact's points, normal and velocity at
    its own touching position, and the separations from the TE along the normal,
    $(\\Delta - \\Delta_i)\\,r_{b2}f_i$ (mm; `inf` where a slice does not touch)."""
    slice_te = contact.offset + _lead_correction(pair, z)
    valid = contact.valid
    te = _binding_te(pair, depth, phi, ks, z, contact, slice_te, n_mid, surface, refine)
    safe_te = jnp.where(valid, slice_te, 0.0)
    x1, x2, normal, v12, frac = _contact_geometry(pair, depth, phi, ks, z, contact, safe_te)
    radii = pair.action_radii()
    gap = (te[:, None, None] - safe_te) * radii[..., 1] * frac
    return TCAResult(
        pinion_angle=phi,
        transmission_error=te,
        pair_index=ks,
        pair_zone=jnp.zeros(ks.shape, dtype=ks.dtype),
        slice_z=z,
        slice_width=width,
        slice_te=slice_te,
        valid=valid,
        kind=contact_kind(contact.kind),
        pinion_parameter=contact.pinion_parameter,
        gear_parameter=contact.gear_parameter,
        pinion_point=x1,
        gear_point=x2,
        normal=normal,
        relative_velocity=v12,
        separation=jnp.where(valid, gap, jnp.inf),
        transverse_normal_fraction=frac,
        action_radius=radii,
        unconverged=contact.unconverged,
        result=_tca_result(contact.unconverged),
    )
