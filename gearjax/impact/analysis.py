r"""Mesh-in impact of the incoming tooth pair (seed 001): where it first touches under
load (`search`), how fast it closes there, and the force.

**Regime switch.** As the load grows on a modified pair, the flank contact point moves
toward the gear's tip edge and the edge candidate takes over exactly when the flank point
reaches the edge: both candidates then coincide in position, normal and offset, so the
first-contact offset, the point and the impact velocity are continuous across the switch
and only their derivatives kink; no smoothing is needed, and gradients are the one-sided
ones of the regime that binds.

**Impact velocity.** With the pinion speed $\omega_1$ and the gear turning at
$\omega_1(z_1/z_2 + \mathrm{d\,LTE}_{\neg k}/\mathrm d\varphi_1)$ (the real, loaded motion),
$v_n = \mathbf v^{(12)}\cdot\mathbf n = \omega_1(\mathbf v^{(12)}_0\cdot\mathbf n
- q\,\mathrm{LTE}'_{\neg k})$, with $\mathbf v^{(12)}_0$ the relative velocity at the nominal
ratio per unit pinion speed and $q$ the gear's moment arm of the normal. It equals the
closing rate of the gap, $\omega_1 q H'(\varphi_1^*)$, reported as `gap_closing_velocity`:
for point contacts a cross-check (their $\Delta_k'$ is a central difference of the located
peaks); on line contacts the search takes $\Delta_k' = \mathbf v^{(12)}_0\cdot\mathbf n/q$
itself (`search.evaluate`), so there the two agree by construction.

Local stiffness (`stiffness.py`), equivalent mass and force (`energy.py`) complete it.

**Point contact** (double circular arc, `ToothSectionCompliance`). Each contact zone has
its own incoming pair per pitch, so the search runs once per zone (batched) and every
field of the `ImpactResult` gains a leading zone axis, in the order of
`pair.contact_zones()`. The first touching point is the one the loaded contact uses
(`search.point_peak`), and the local stiffness is that point's explicit law
$\delta = cF + hF^{2/3}$ (`point_local_stiffness`): the tooth's section compliance and the
Hertz point contact, so $n$ lies between 1 and 3/2.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, Float, Int, Scalar
from .._numerics import safe_divide
from .._solution import RESULTS, enum_name, enum_where, first_failure
from ..ltca.analysis import LTCAResult, _levers, moment_arms
from ..ltca.model import ContactModel
from ..ltca.point_analysis import ToothSectionCompliance, point_coefficients
from ..tca import ContactKind, TCAResult
from ..tca._slice_problem import contact_kind
from .energy import base_radius_equivalent_mass, equivalent_mass, gear_inertia, impact_force
from .search import SearchContext, _Search, bracket, first_contact
from .stiffness import LocalStiffness, local_stiffness, point_local_stiffness


class ImpactRegime(eqx.Enumeration):
    """How the incoming pair first touches (items are pytrees: they pass `jit` and `vmap`)."""

    surface = "flank on flank: the first contact is a flank point"
    edge = "a tip edge strikes the mating flank"


class ImpactResult(eqx.Module):
    """Mesh-in impact of the incoming tooth pair.

    Units: angular transmission-error quantities are in rad (gear 2) and carry no suffix
    (`loaded_te`); along the transverse line of action they are in mm with the suffix
    `_line` (as `TCAResult.transmission_error_line`). For a pair of several contact zones
    (double circular arc) every field has a zone axis, leading (after the batch axes of a
    batched call; the sweeps keep one zone, `check_one_zone`).

    Attributes:
        result: `RESULTS.successful`, or the first failure of the search:
            `first_contact_not_bracketed` (no first contact on the cycle grid),
            `first_contact_jump` (the gap jumps across zero: no quasi-static first
            contact), `first_contact_unconverged` (the root search), `impact_contact_unconverged`
            (the loaded contact at the first-contact position) or `stiffness_fit_failed`
            (a solve of the local force-approach curve). The other fields are meaningful
            only where it is successful (for `first_contact_jump`, `pinion_angle` locates
            the jump).
        pair_index: the incoming tooth pair $k$ of the window.
        pinion_angle: $\\varphi_1^*$ at first contact (rad, cycle frame of pair $k$).
        slice_z: axial position of M (mm).
        kind: `ContactKind` of the first touching candidate.
        regime: `ImpactRegime.edge` where `kind` is a tip edge, else `ImpactRegime.surface`;
            `regime_name` gives its name.
        pinion_point, gear_point: M on each flank, fixed frame (mm).
        normal: common unit normal at M (pinion flank, fixed frame).
        pinion_parameter, gear_parameter: profile parameters of M (mm; roll lengths for
            involute flanks).
        loaded_te: $\\mathrm{LTE}_{\\neg k}(\\varphi_1^*)$, the gear offset at first contact (rad).
        te_slope, lte_slope: $\\mathrm d\\Delta_k/\\mathrm d\\varphi_1$ and
            $\\mathrm d\\mathrm{LTE}_{\\neg k}/\\mathrm d\\varphi_1$ at $\\varphi_1^*$ (-).
        relative_velocity: $\\mathbf v^{(12)}$ at M, real kinematics (mm/s).
        velocity: $v_n = \\mathbf v^{(12)}\\cdot\\mathbf n$ (mm/s), positive approaching.
        gap_closing_velocity: $\\omega_1qH'$ (mm/s), the same velocity from the gap's rate
            (see the module docstring).
        pinion_arm, gear_arm: moment arms $p$, $q$ of the normal (mm).
        inertia: $(J_1, J_2)$ (t·mm²).
        mass: equivalent mass $m_{eq}$ (t).
        base_radius_mass: $m_{eq}$ with the base radii as arms and no helix factor, the
            form of the mesh-in impact paper (`base_radius_equivalent_mass`; t).
        stiffness: `LocalStiffness` ($K_s$, $n$, curve).
        force: peak impact force $F_s$ (N).
        approach: peak approach $\\delta_s$ (mm).
        kinetic_energy: $\\tfrac12m_{eq}v_n^2$ (N·mm).
        search_steps: evaluations of TCA and LTCA at one pinion angle taken by the
            first-contact search (at most `Accuracy.impact_max_steps`).
    """

    result: RESULTS
    pair_index: Int[Array, ""]
    pinion_angle: Scalar
    slice_z: Scalar
    kind: ContactKind
    regime: ImpactRegime
    pinion_point: Float[Array, "3"]
    gear_point: Float[Array, "3"]
    normal: Float[Array, "3"]
    pinion_parameter: Scalar
    gear_parameter: Scalar
    loaded_te: Scalar
    te_slope: Scalar
    lte_slope: Scalar
    relative_velocity: Float[Array, "3"]
    velocity: Scalar
    gap_closing_velocity: Scalar
    pinion_arm: Scalar
    gear_arm: Scalar
    inertia: Float[Array, "2"]
    mass: Scalar
    base_radius_mass: Scalar
    stiffness: LocalStiffness
    force: Scalar
    approach: Scalar
    kinetic_energy: Scalar
    search_steps: Int[Array, ""]

    @property
    def regime_name(self):
        """`"surface"` or `"edge"`: a str, or an array of str for a batched result (needs a
        concrete result)."""
        return enum_name(self.regime)


def impact_analysis(
    pair,
    depth,
    tca: TCAResult,
    ltca: LTCAResult,
    *,
    torque,
    speed,
    model: ContactModel,
    pairs: tuple[int, ...],
    inertia=None,
) -> ImpactResult:
    """Mesh-in impact of the pair coming into mesh (see the module docstring); for a
    point-contact pair, of each contact zone's incoming pair (leading axis: zone).

    Args:
        pair, depth: the gear pair and its flank depths (modifications, errors).
        tca, ltca: the scene's unloaded and loaded contact over the cycle.
        torque: pinion torque (N·mm).
        speed: pinion speed $\\omega_1$ (rad/s).
        model: the loaded-contact model, as for the LTCA (`ContactModel`; its accuracy
            also sets the first-contact search and the stiffness fit).
        pairs: the tooth-pair window of `tca` (static).
        inertia: $(J_1, J_2)$ of the rotating assemblies (t·mm²); default the solid discs
            $\\pi\\rho b(r_b^4 - r_h^4)/2$.
    """
    pair = pair.resolve()
    ctx = SearchContext(pair, depth, jnp.asarray(torque, ltca.rotation.dtype), model, tuple(pairs))
    if ltca.point_contact is None:
        found, column, lower, upper, gap_lower, gap_upper = bracket(tca, ltca)
        search = first_contact(ctx, column, lower, upper, gap_lower, gap_upper, found)
        return _impact_at(ctx, column, search, speed, inertia, found)
    # point contact: each contact zone's incoming pair strikes on its own, in one vmapped search
    zones = len(pair.contact_zones())
    if tca.pair_index.shape[0] != zones * len(pairs):
        raise ValueError(f"the TCA's pair axis must hold each of the {zones} zones' window {pairs}; "
                         f"got {tca.pair_index.shape[0]} pairs")
    brackets = [bracket(tca, ltca, range(z * len(pairs), (z + 1) * len(pairs))) for z in range(zones)]
    brackets = jax.tree_util.tree_map(lambda *x: jnp.stack(x), *brackets)

    def strike(found, column, lower, upper, gap_lower, gap_upper):
        search = first_contact(ctx, column, lower, upper, gap_lower, gap_upper, found)
        return _impact_at(ctx, column, search, speed, inertia, found)

    return jax.vmap(strike)(*brackets)


def _local_fit(ctx: SearchContext, tca: TCAResult, column, p_arm) -> LocalStiffness:
    """Local stiffness $F = K_s\\delta^n$ of the incoming pair alone, from its
    first-contact configuration, loaded up to the static normal load (at least 10 N per mm
    of face width); for point-contact flanks from the pair's point coefficients there."""
    pair, acc = ctx.pair, ctx.model.accuracy
    normal_load = safe_divide(ctx.torque, jnp.abs(p_arm))
    reference = jnp.maximum(normal_load, 10.0 * pair.face_width)
    if isinstance(ctx.model.compliance, ToothSectionCompliance):
        contact, coefficients = point_coefficients(pair, tca, ctx.model.material,
                                                   ctx.model.compliance.coupling_length)
        # unit coefficients where the pair does not touch (no strike found): finite, and flagged
        touching = jnp.isfinite(contact["gap"][0, column])
        hertz, linear = (jnp.where(touching, coefficients[0, column, i], 1.0) for i in (0, 1))
        return point_local_stiffness(linear, hertz, reference, acc)
    n_mid = acc.face_slices
    model = ctx.model
    points = model.compliance(pair, model.material, model.hub_radius, tca, n_mid, acc.quadrature_points,
                              jnp.ones(tca.valid[..., :n_mid].shape, p_arm.dtype))
    matrix = points.blocks[0, column]
    nonlinear = points.nonlinear[0, column]
    _, q_all = _levers(tca, n_mid, pair.center(1))
    # Separations count from the first touching cell midpoint: a face-end M (width 0) has
    # no compliance of its own, and an offset at the start would spoil the power law.
    slice_te = tca.slice_te[0, column, :n_mid]
    valid = tca.valid[0, column, :n_mid]
    first = jnp.max(jnp.where(valid, slice_te, -jnp.inf))
    separation = jnp.maximum(q_all[0, column] * (first - jnp.where(valid, slice_te, first)), 0.0)
    return local_stiffness(matrix, nonlinear, points.exponent, separation, valid, reference, acc)


def _impact_at(ctx: SearchContext, column, search: _Search, speed, inertia, found) -> ImpactResult:
    pair = ctx.pair
    phi1, j, solved = search.pinion_angle, search.slice_index, search.solved
    contact = search.contact
    te, lte, tca, dte, dlte = contact.te, contact.lte, contact.tca, contact.te_slope, contact.lte_slope
    peak = contact.peak
    x1, n = peak.pinion_point, peak.normal
    kind = contact_kind(peak.contact.kind)
    center2 = pair.center(1)
    p_arm, q_arm = moment_arms(x1, n, center2)
    r2 = x1[:2] - center2
    # v12 = v1 - v2; the loaded gear turns faster by LTE' w1 about its axis (-z).
    gear_extra = jnp.stack([r2[1], -r2[0], jnp.zeros_like(r2[0])])  # (-e_z) x r2
    v12 = speed * (peak.relative_velocity - dlte * gear_extra)
    velocity = jnp.dot(v12, n)
    fit = _local_fit(ctx, tca, column, p_arm)

    radii = pair.action_radii()
    if inertia is None:
        inertia = gear_inertia(ctx.model.material.density, pair.face_width, radii, ctx.model.hub_radius)
    else:
        inertia = jnp.asarray(inertia, te.dtype)
    mass = equivalent_mass(inertia, p_arm, q_arm)
    force, approach = impact_force(mass, velocity, fit.coefficient, fit.exponent)
    v = jnp.maximum(velocity, 0.0)
    result = first_failure(
        (~found, RESULTS.first_contact_not_bracketed),
        (search.jumped, RESULTS.first_contact_jump),
        (~search.converged, RESULTS.first_contact_unconverged),
        (~solved, RESULTS.impact_contact_unconverged),
        (fit.result != RESULTS.successful, fit.result),
    )
    return ImpactResult(
        result=result,
        pair_index=tca.pair_index[column],
        pinion_angle=phi1,
        slice_z=peak.z,
        kind=kind,
        regime=enum_where(kind == ContactKind.flank, ImpactRegime.surface, ImpactRegime.edge),
        pinion_point=x1,
        gear_point=peak.gear_point,
        normal=n,
        pinion_parameter=peak.contact.pinion_parameter,
        gear_parameter=peak.contact.gear_parameter,
        loaded_te=lte,
        te_slope=dte,
        lte_slope=dlte,
        relative_velocity=v12,
        velocity=velocity,
        gap_closing_velocity=speed * q_arm * (dte - dlte),
        pinion_arm=p_arm,
        gear_arm=q_arm,
        inertia=inertia,
        mass=mass,
        base_radius_mass=base_radius_equivalent_mass(inertia, radii),
        stiffness=fit,
        force=force,
        approach=approach,
        kinetic_energy=0.5 * mass * v * v,
        search_steps=search.steps,
    )
