r"""Mesh-in impact: first contact of the incoming tooth pair under load (seed 001).

**First contact.** Follow one tooth pair $k$ as the pinion turns. Its slices $j$ would
touch at the gear offsets $\Delta_{kj}(\varphi_1)$ of the unloaded TCA (flank, tip-edge and
face-end candidates alike), while the pairs already in mesh hold the gear at their loaded
transmission error $\mathrm{LTE}_{\neg k}(\varphi_1)$, computed by the LTCA with pair $k$
unloaded. Pair $k$ is clear while

$$H(\varphi_1) = \max_j \Delta_{kj}(\varphi_1) - \mathrm{LTE}_{\neg k}(\varphi_1) < 0,$$

i.e. while its rigid gap (geometry, modifications, errors) exceeds the loaded approach of
the others, and first touches at the root $\varphi_1^*$ of $H$. The cycle grid of the
scene's TCA/LTCA brackets the first upward crossing (with pair $k$ unloaded before its
first contact, the scene's LTE equals $\mathrm{LTE}_{\neg k}$ there), then optimistix's
bisection finds $\varphi_1^*$ with TCA and LTCA evaluated at single positions. The first
touching candidate gives the point M, its normal and the **regime**: `edge` when it is a
tip edge, `surface` when it is a flank point. The same search serves every tooth family.

Gradients of $\varphi_1^*$ follow from the implicit function theorem,
$\mathrm d\varphi_1^*/\mathrm d\theta = -H_\theta/H_{\varphi}$ (bisection itself is not
differentiated). Where $H_\varphi = 0$ (zero load on perfect flanks: tangential
engagement) the derivative is set to zero.

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
closing rate of the gap, $\omega_1 q H'(\varphi_1^*)$, a cross-check reported as
`gap_closing_velocity`.

Local stiffness (`stiffness.py`), equivalent mass and force (`energy.py`) complete it.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx

from .._custom_types import Array, Float, Int, Scalar
from .._numerics import safe_divide
from .._solution import ADJOINT, RESULTS, enum_name, enum_where, first_failure
from ..ltca.analysis import LTCAResult, _levers, loaded_contact_analysis, moment_arms
from ..ltca.model import ContactModel
from ..tca import ContactKind, TCAResult, tooth_contact_analysis
from .energy import equivalent_mass, gear_inertia, impact_force, seed_equivalent_mass
from .stiffness import LocalStiffness, local_stiffness


class ImpactRegime(eqx.Enumeration):
    """How the incoming pair first touches (items are pytrees: they pass `jit` and `vmap`)."""

    surface = "flank on flank: the first contact is a flank point"
    edge = "a tip edge strikes the mating flank"


class ImpactResult(eqx.Module):
    """Mesh-in impact of the incoming tooth pair.

    Units: angular transmission-error quantities are in rad (gear 2) and carry no suffix
    (`loaded_te`); along the transverse line of action they are in mm with the suffix
    `_line` (as `TCAResult.transmission_error_line`).

    Attributes:
        result: `RESULTS.successful`, or the first failure of the search:
            `first_contact_not_bracketed` (no first contact on the cycle grid),
            `first_contact_unconverged` (the bisection), `impact_contact_unconverged`
            (the loaded contact at the first-contact position) or `stiffness_fit_failed`
            (a solve of the local force-approach curve). The other fields are meaningful
            only where it is successful.
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
        gap_closing_velocity: $\\omega_1qH'$ (mm/s), the same velocity from the gap's rate.
        pinion_arm, gear_arm: moment arms $p$, $q$ of the normal (mm).
        inertia: $(J_1, J_2)$ (t·mm²).
        mass: equivalent mass $m_{eq}$ (t).
        seed_mass: seed 001's $m_{eq}$ with base radii as arms (t).
        stiffness: `LocalStiffness` ($K_s$, $n$, curve).
        force: peak impact force $F_s$ (N).
        approach: peak approach $\\delta_s$ (mm).
        kinetic_energy: $\\tfrac12m_{eq}v_n^2$ (N·mm).
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
    seed_mass: Scalar
    stiffness: LocalStiffness
    force: Scalar
    approach: Scalar
    kinetic_energy: Scalar

    @property
    def regime_name(self):
        """`"surface"` or `"edge"`: a str, or an array of str for a batched result (needs a
        concrete result)."""
        return enum_name(self.regime)


class _Context(eqx.Module):
    """What a single-position evaluation needs (static settings kept static)."""

    pair: eqx.Module
    depth: eqx.Module
    torque: Scalar
    model: ContactModel
    pairs: tuple[int, ...] = eqx.field(static=True)


def _single(ctx: _Context, phi1, column):
    """TCA at one pinion angle, the loaded TE of the pairs other than `column` and the
    incoming pair's first-touching slice."""
    tca = tooth_contact_analysis(
        ctx.pair, ctx.depth, accuracy=ctx.model.accuracy, pairs=ctx.pairs, pinion_angles=phi1[None]
    )
    active = jnp.arange(len(ctx.pairs)) != column
    ltca = loaded_contact_analysis(ctx.pair, tca, ctx.torque, ctx.model, active_pairs=active, rates=False)
    offsets = jnp.where(tca.valid[0, column], tca.slice_te[0, column], -jnp.inf)
    j = jnp.argmax(offsets)
    return (offsets[j], ltca.transmission_error[0]), (tca, j, ltca.converged[0])


def _gap(phi1, args):
    ctx, column = args
    (te, lte), _ = _single(ctx, phi1, column)
    return te - lte


def first_contact(ctx: _Context, column, lower, upper):
    """Bisection for $H(\\varphi_1) = 0$ on `[lower, upper]` (H(lower) < 0 <= H(upper)),
    then the implicit-function correction that carries the gradients. Returns
    `(phi1, converged)`."""
    dtype = jnp.result_type(lower)
    eps = float(jnp.finfo(dtype).eps)
    acc = ctx.model.accuracy
    atol = max(acc.newton_atol, 64 * eps)
    rtol = max(acc.newton_rtol, 16 * eps)
    solver = optx.Bisection(rtol=rtol, atol=atol, flip=False)
    frozen = jax.tree_util.tree_map(
        lambda x: jax.lax.stop_gradient(x) if eqx.is_array(x) else x, (ctx, lower, upper)
    )
    args = (frozen[0], column)
    sol = optx.root_find(
        _gap,
        solver,
        0.5 * (frozen[1] + frozen[2]),
        args=args,
        options=dict(lower=frozen[1], upper=frozen[2]),
        max_steps=acc.impact_max_steps,
        throw=False,
        adjoint=ADJOINT,
    )
    return jax.lax.stop_gradient(sol.value), sol.result == optx.RESULTS.successful


def _bracket(tca: TCAResult, ltca: LTCAResult):
    """First upward crossing of $H$ along the tracked tooth's history on the cycle grid.

    Pair $k$ at pinion angle $\\varphi_1$ is pair 0 at $\\varphi_1 - kp$, so ordering the
    grid by descending pair and ascending angle follows one tooth through the mesh.
    """
    offsets = jnp.max(jnp.where(tca.valid, tca.slice_te, -jnp.inf), axis=-1)  # (pos, pair)
    h = offsets - ltca.transmission_error[:, None]
    n_pos, n_pair = h.shape
    line = h[:, ::-1].T.reshape(-1)
    columns = jnp.repeat(jnp.arange(n_pair)[::-1], n_pos)
    angles = jnp.tile(tca.pinion_angle, n_pair)
    up = (line[1:] >= 0) & (line[:-1] < 0)
    i = jnp.argmax(up) + 1
    step = tca.pinion_angle[1] - tca.pinion_angle[0]
    return jnp.any(up), columns[i], angles[i] - step, angles[i]


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
    """Mesh-in impact of the pair coming into mesh (see the module docstring).

    Args:
        pair, depth: the gear pair and its flank depths (modifications, errors).
        tca, ltca: the scene's unloaded and loaded contact over the cycle.
        torque: pinion torque (N·mm).
        speed: pinion speed $\\omega_1$ (rad/s).
        model: the loaded-contact model, as for the LTCA (`ContactModel`; its accuracy
            also sets the bisection and the stiffness fit).
        pairs: the tooth-pair window of `tca` (static).
        inertia: $(J_1, J_2)$ of the rotating assemblies (t·mm²); default the solid discs
            $\\pi\\rho b(r_b^4 - r_h^4)/2$.
    """
    pair = pair.resolve()
    ctx = _Context(pair, depth, jnp.asarray(torque, ltca.rotation.dtype), model, tuple(pairs))
    found, column, lower, upper = _bracket(tca, ltca)
    root, bisected = first_contact(ctx, column, lower, upper)
    return _impact_at(ctx, column, root, speed, inertia, found, bisected)


def _follow_root(ctx: _Context, column, root):
    """Everything at the first contact `root`, continued so that it carries the gradients
    of $\\varphi_1^*$: returns `(phi1, (te, lte, tca, dte, dlte), j, solved)`.

    One forward-mode evaluation at the root gives the values, their rates along
    $\\varphi_1$, and (implicit function theorem) the gradients of $\\varphi_1^*$:
    $\\mathrm d\\varphi_1^*/\\mathrm d\\theta = -H_\\theta/H_\\varphi$. Every output $Q$ is
    continued as $Q + Q'\\,\\text{shift}$, where `shift` is zero in value and carries those
    gradients. Second order as well: the impact velocity contains the rates, and their own
    change along $\\varphi_1$ enters its gradient through $\\varphi_1^*$.
    """

    def evaluate(p):
        (te, lte), (tca, j, solved) = _single(ctx, p, column)
        return (te, lte, tca), (j, solved)

    def with_rates(p):
        (te, lte, tca), (dte, dlte, _), aux = jax.jvp(evaluate, (p,), (jnp.ones_like(p),), has_aux=True)
        return (te, lte, tca, dte, dlte), aux

    values, tangents, (j, solved) = jax.jvp(with_rates, (root,), (jnp.ones_like(root),), has_aux=True)
    te, lte, _, dte, dlte = values
    h = te - lte
    slope = jax.lax.stop_gradient(dte - dlte)
    eps = float(jnp.finfo(root.dtype).eps)
    steep = jnp.abs(slope) > 1e3 * eps
    shift = -jnp.where(steep, safe_divide(h - jax.lax.stop_gradient(h), slope), 0.0)

    def follow(x, dx):
        if eqx.is_inexact_array(x):
            return x + jax.lax.stop_gradient(dx) * shift
        return x

    return root + shift, jax.tree_util.tree_map(follow, values, tangents), j, solved


def _local_fit(ctx: _Context, tca: TCAResult, column, p_arm) -> LocalStiffness:
    """Local stiffness $F = K_s\\delta^n$ of the incoming pair alone, from its
    first-contact configuration, loaded up to the static normal load (at least 10 N per mm
    of face width)."""
    pair, acc = ctx.pair, ctx.model.accuracy
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
    normal_load = safe_divide(ctx.torque, jnp.abs(p_arm))
    reference = jnp.maximum(normal_load, 10.0 * pair.face_width)
    return local_stiffness(matrix, nonlinear, points.exponent, separation, valid, reference, acc)


def _impact_at(ctx: _Context, column, root, speed, inertia, found, bisected) -> ImpactResult:
    pair = ctx.pair
    phi1, (te, lte, tca, dte, dlte), j, solved = _follow_root(ctx, column, root)
    x1 = tca.pinion_point[0, column, j]
    n = tca.normal[0, column, j]
    kind = jax.tree_util.tree_map(lambda v: v[0, column, j], tca.kind)
    center2 = pair.center(1)
    p_arm, q_arm = moment_arms(x1, n, center2)
    r2 = x1[:2] - center2
    # v12 = v1 - v2; the loaded gear turns faster by LTE' w1 about its axis (-z).
    gear_extra = jnp.stack([r2[1], -r2[0], jnp.zeros_like(r2[0])])  # (-e_z) x r2
    v12 = speed * (tca.relative_velocity[0, column, j] - dlte * gear_extra)
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
        (~bisected, RESULTS.first_contact_unconverged),
        (~solved, RESULTS.impact_contact_unconverged),
        (fit.result != RESULTS.successful, fit.result),
    )
    return ImpactResult(
        result=result,
        pair_index=jnp.asarray(ctx.pairs)[column],
        pinion_angle=phi1,
        slice_z=tca.slice_z[j],
        kind=kind,
        regime=enum_where(kind == ContactKind.flank, ImpactRegime.surface, ImpactRegime.edge),
        pinion_point=x1,
        gear_point=tca.gear_point[0, column, j],
        normal=n,
        pinion_parameter=tca.pinion_parameter[0, column, j],
        gear_parameter=tca.gear_parameter[0, column, j],
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
        seed_mass=seed_equivalent_mass(inertia, radii),
        stiffness=fit,
        force=force,
        approach=approach,
        kinetic_energy=0.5 * mass * v * v,
    )
