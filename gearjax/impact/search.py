r"""The first contact of the incoming tooth pair under load: bracket, root search, gradients.

**First contact.** Follow one tooth pair $k$ as the pinion turns. Its flank, tip-edge and
face-end candidates would touch at the gear offsets $\Delta_k(z, \varphi_1)$ of the unloaded
TCA along the face, while the pairs already in mesh hold the gear at their loaded transmission
error $\mathrm{LTE}_{\neg k}(\varphi_1)$, computed by the LTCA with pair $k$ unloaded. Pair
$k$ is clear while

$$H(\varphi_1) = \max_z \Delta_k(z, \varphi_1) - \mathrm{LTE}_{\neg k}(\varphi_1) < 0,$$

i.e. while its rigid gap (geometry, modifications, errors) exceeds the loaded approach of the
others, and first touches at the root $\varphi_1^*$ of $H$. The maximum over the face is
continuous in $z$ (`tca.face_peak`: around the best slice, the face ends included), not the
best slice's: a tip edge crossing a short relief touches over a stretch of the face narrower
than the slices' spacing. The cycle grid of the scene's TCA/LTCA brackets the first upward
crossing (with pair $k$ unloaded before its first contact, the scene's LTE equals
$\mathrm{LTE}_{\neg k}$ there, up to the TE the search's loaded contact counts from: the
largest slice value, unrefined between the slices). The first touching candidate gives the
point M at $z^*$, its normal and the **regime**: `edge` when it is a tip edge, `surface` when
it is a flank point. The same search serves every tooth family; on point-contact flanks
(double circular arc) the incoming pair's touching point is the one the loaded contact locates
between the slices (`point_peak`), and $\mathrm{LTE}_{\neg k}$ counts from the same located
peaks.

**Root search.** $H$ is smooth on each side of a regime switch (it kinks where the binding
slice or candidate changes, or where the LTCA's active set does), so a safeguarded Newton
iteration finds $\varphi_1^*$ in a handful of steps (Numerical Recipes' `rtsafe`). Each step
runs TCA and LTCA at the pinion angle and at its neighbours $\pm h$ in one call (`evaluate`):
the rate $\mathrm{LTE}_{\neg k}'$ is the central difference there, $\Delta_k'$ the touching
offset's rate at the first touching point (envelope theorem: the normal relative velocity over
the gear's arm), and so $H'$. No forward-mode pass: the rates cost a position axis of three,
not a second trace. The bracket $[\varphi_l, \varphi_u]$, $H(\varphi_l) < 0 \le H(\varphi_u)$,
starts as the grid step and moves its end of the same sign to every evaluated point; the first
point is the regula-falsi point of the grid values; the next is the Newton point $\varphi -
H/H'$ when it lies inside the bracket and is at most half the previous step, else the
bracket's midpoint (bisection), so the search never leaves the bracket and its steps at least
halve. It has converged when $|H| \le$ atol and the Newton step or the bracket is below atol +
rtol $|\varphi_1|$ (`Accuracy.newton_atol`, `newton_rtol`); `Accuracy.impact_max_steps` caps
the evaluations, `ImpactResult.search_steps` counts them. Where the bracket, both ends
evaluated, shrinks below that tolerance while $H$ rises across it by more than atol and by far
more than its end slopes allow, $H$ **jumps** across zero and has no root: e.g. the loaded TE
of the pairs in mesh drops below the incoming pair's offset in one step (a pair's contact
leaves its flank), so the gear swings through the step, freely or on the remaining pairs,
until the incoming pair stops it. That dynamic strike is not the quasi-static mesh-in this
module models: the search stops and the impact's result is `first_contact_jump`. A jump is
found by bisection, so it takes about as many evaluations as the bracket has bits above the
tolerance (26–29 at `default`); beyond `impact_max_steps` it is reported unconverged. The
values at the last evaluated point, rates included, are the first contact's: the search is the
only place the TCA/LTCA at the search's angle is traced in a program that is not
differentiated. The loop is a `lax.while_loop` with a result code, no callbacks. With
`SearchContext.branch` the incoming pair's first touching point is held to one branch of the
regime switch (`tca.branch`, `impact.branches`).

Gradients of $\varphi_1^*$ follow from the implicit function theorem, $\mathrm
d\varphi_1^*/\mathrm d\theta = -H_\theta/H_{\varphi}$, through a custom JVP (the iteration
itself is not differentiated): differentiating evaluates the contact at the root once more,
along the parameters' tangent and the root's together, so every output $Q$, the rates in the
impact velocity included, changes by $\dot Q_\theta + Q'\dot\varphi_1^*$ (one first-order
forward-mode pass). Where $H_\varphi = 0$ (zero load on perfect flanks: tangential engagement)
it is set to zero.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import Array, Bool, Float, Int, Scalar
from .._numerics import safe_divide
from ..ltca.analysis import LTCAResult, loaded_contact_analysis, moment_arms
from ..ltca.model import ContactModel
from ..ltca.point_analysis import closest_contact
from ..tca import TCAResult, tooth_contact_analysis
from ..tca._slice_problem import SliceContact, kind_index
from ..tca.branch import Branch
from ..tca.face_peak import FacePeak, face_peak


class SearchContext(eqx.Module):
    """What a single-position evaluation needs (static settings static; `branch`: `tca.branch`)."""

    pair: eqx.Module
    depth: eqx.Module
    torque: Scalar
    model: ContactModel
    pairs: tuple[int, ...] = eqx.field(static=True)
    branch: str | None = eqx.field(static=True, default=None)


class _Contact(eqx.Module):
    """Pair $k$ at one pinion angle: its rigid offset $\\max_z\\Delta_k$ (`te`), the others' loaded
    TE (`lte`), the TCA, the first touching point (`peak`), both offsets' rates along $\\varphi_1$."""

    te: Scalar
    lte: Scalar
    tca: TCAResult
    peak: FacePeak
    te_slope: Scalar
    lte_slope: Scalar

    @property
    def gap(self):
        """$H = \\max_j\\Delta_{kj} - \\mathrm{LTE}_{\\neg k}$ (rad, gear 2)."""
        return self.te - self.lte

    @property
    def gap_slope(self):
        """$H' = \\mathrm dH/\\mathrm d\\varphi_1$ (-)."""
        return self.te_slope - self.lte_slope


def rate_step(pair, dtype):
    """Step $h$ (rad) of the central difference for $\\mathrm{LTE}_{\\neg k}'$: $\\epsilon^{1/3}$ of the
    pinion's angular pitch (1.3e-6 rad, seed pair, float64), where truncation and rounding balance."""
    return float(jnp.finfo(dtype).eps) ** (1.0 / 3.0) * pair.angular_pitch(0)


def evaluate(ctx: SearchContext, column, phi1) -> tuple[_Contact, tuple]:
    """The incoming pair `column` at pinion angle `phi1` and the loaded TE of the other
    pairs, with the rates of both along $\\varphi_1$: `(contact, (j, solved))`, $j$ the
    pair's best slice.

    TCA and LTCA run at $\\varphi_1$ and $\\varphi_1 \\pm h$ (`rate_step`) in one call, traced
    once: $\\mathrm{LTE}_{\\neg k}'$ is the central difference of the loaded TE there. The
    incoming pair's first touching point along the face at $\\varphi_1$ is `face_peak`
    (continuous in $z$ around the best slice; for point-contact flanks `point_peak`, where
    the loaded contact puts it), and its rate is that of the touching offset at a fixed
    material point (envelope theorem): $\\Delta_k' = \\mathbf v^{(12)}_0\\cdot\\mathbf n / q$,
    the normal relative velocity per unit pinion speed over the gear's arm (for point
    contacts, whose peak is interpolated between slices, the central difference of the
    located peaks, one-sided where the pair touches on one side only)."""
    acc, h = ctx.model.accuracy, rate_step(ctx.pair, jnp.result_type(phi1))
    branch = None if ctx.branch is None else Branch(jnp.asarray(ctx.pairs)[column], ctx.branch)
    # The TCA's TE is only the reference the loaded TE counts from, so it is not refined
    # between slices: a shift of it cancels but for a small fraction (decision 0014).
    grid = tooth_contact_analysis(ctx.pair, ctx.depth, accuracy=acc, pairs=ctx.pairs,
                                  pinion_angles=phi1 + h * jnp.array([-1.0, 0.0, 1.0], jnp.result_type(phi1)),
                                  refine_peak=False)
    active = jnp.arange(grid.pair_index.shape[0]) != column
    ltca = loaded_contact_analysis(ctx.pair, grid, ctx.torque, ctx.model, active_pairs=active, rates=False)
    tca = grid.position(1)
    solved = jnp.all(ltca.converged)

    def central(values, valid=(True, True, True)):
        # one-sided where a neighbour has no value (a contact that starts or ends there)
        one_sided = jnp.where(valid[2], values[2] - values[1], jnp.where(valid[0], values[1] - values[0], 0.0)) / h
        return jnp.where(valid[0] & valid[2], (values[2] - values[0]) / (2.0 * h), one_sided)

    offsets = jnp.where(tca.valid[0, column], tca.slice_te[0, column], -jnp.inf)
    j = jnp.argmax(offsets)
    if ltca.point_contact is not None:
        peak, te, top = point_peak(grid, column)
        # the loaded pairs' contacts sit at the rigid TE of the located peaks, less the lag
        lte = top - ltca.rotation
        located = jnp.isfinite(te)
        contact = _Contact(peak.te, lte[1], tca, peak, central(jnp.where(located, te, 0.0), located), central(lte))
        return contact, (j, solved)
    spacing = ctx.pair.face_width / acc.face_slices
    peak = face_peak(ctx.pair, ctx.depth, acc, jnp.asarray(ctx.pairs)[column], phi1, tca.slice_z[j], offsets[j],
                     spacing, branch)
    _, q_arm = moment_arms(peak.pinion_point, peak.normal, ctx.pair.center(1))
    touching = jnp.isfinite(peak.te)
    te_slope = jnp.where(touching, safe_divide(jnp.dot(peak.relative_velocity, peak.normal), q_arm), 0.0)
    lte = ltca.transmission_error
    return _Contact(peak.te, lte[1], tca, peak, te_slope, central(lte)), (j, solved)


def point_peak(tca: TCAResult, column) -> tuple[FacePeak, Array, Array]:
    """The point contact of pair `column` at the TCA's middle position (of three), located
    between the face slices as the point-contact LTCA locates it (`closest_contact`: the
    parabola's peak; points, normal and velocity interpolated linearly between the slices
    around it): `(peak, te, top)`, with the pair's located peak value `te` (`-inf` where it
    does not touch) and the largest of all pairs `top` at every position (rad; the rigid
    TE the loaded contact's lag counts from)."""
    located = closest_contact(tca)
    middle = 1
    start, other, weight = (x[middle, column] for x in located["between"])
    touching = jnp.isfinite(located["gap"])

    def at(field):
        return (1.0 - weight) * field[middle, column, start] + weight * field[middle, column, other]

    nearest = located["slice"][middle, column]
    kind = jax.tree_util.tree_map(lambda x: x[middle, column, nearest], tca.kind)
    contact = SliceContact(
        offset=located["te"][middle, column],
        pinion_parameter=located["u1"][middle, column],
        gear_parameter=located["u2"][middle, column],
        kind=kind_index(kind),
        valid=touching[middle, column],
        unconverged=tca.unconverged[middle, column, nearest],
    )
    te = jnp.where(touching[:, column], located["te"][:, column], -jnp.inf)
    peak = FacePeak(located["z"][middle, column], te[middle], contact, at(tca.pinion_point), at(tca.gear_point),
                    located["normal"][middle, column], at(tca.relative_velocity))
    return peak, te, jnp.max(jnp.where(touching, located["te"], -jnp.inf), axis=-1)


class _Search(eqx.Module):
    """Outcome of the first-contact search: the contact at its last point."""

    pinion_angle: Scalar
    contact: _Contact
    slice_index: Int[Array, ""]
    solved: Bool[Array, ""]
    steps: Int[Array, ""]
    converged: Bool[Array, ""]
    jumped: Bool[Array, ""]


class _SearchState(eqx.Module):
    """Carry of the search loop: the bracket, the next point and the last outcome."""

    lower: Scalar
    upper: Scalar
    checked: Bool[Array, "2"]  # the sign of H at (lower, upper) was evaluated, not taken from the grid
    point: Scalar  # where the next evaluation goes
    probe: Int[Array, ""]  # the point is the lower end to check (-1), the upper one (+1), or neither (0)
    last_step: Scalar  # length of the previous step (the safeguard's reference)
    ends: Float[Array, "2 2"]  # H and H' at (lower, upper) where evaluated
    search: _Search


def _tolerances(ctx: SearchContext, dtype):
    """`(atol, rtol, tiny)`: the search's tolerances (`Accuracy.newton_atol/rtol` floored
    near machine precision) and the smallest slope $H'$ trusted for a Newton step."""
    rtol, atol = ctx.model.accuracy.newton_tolerances(dtype)
    return atol, rtol, 1e3 * float(jnp.finfo(dtype).eps)


def _jump(ends, below, h, dh, lower, upper, atol):
    """The bracket ends' `(H, H')` (rad, -) with the point just evaluated (`below`: it is
    the lower end), and whether $H$ jumps across zero inside the bracket `[lower, upper]`
    (rad): from end to end it rises by more than atol (rad) and by more than $10^3$ times
    what the steeper end's slope allows over the bracket's width (a continuous $H$ rises by
    about that slope times the width)."""
    ends = jnp.where(below, ends.at[0].set(jnp.stack([h, dh])), ends.at[1].set(jnp.stack([h, dh])))
    rise = ends[1, 0] - ends[0, 0]
    return ends, (rise > atol) & (rise > 1e3 * jnp.max(jnp.abs(ends[:, 1])) * (upper - lower))


def _search(ctx: SearchContext, column, lower, upper, gap_lower, gap_upper, found) -> _Search:
    """Safeguarded Newton iteration for $H(\\varphi_1) = 0$ on `[lower, upper]`
    ($H$(lower) < 0 <= $H$(upper); `gap_lower`, `gap_upper` are those values on the cycle
    grid), with $H$ and $H'$ from one forward-mode evaluation per step.

    Starts at the regula-falsi point of the grid values. Each step evaluates $H$ and $H'$ at
    the current point, moves the bracket end of the same sign there, and takes the Newton
    step when it stays inside the bracket and is at most half the previous step, else
    bisects.

    The grid's signs at the bracket ends are those of the scene's LTCA, with the incoming
    pair loaded; the search's $H$ leaves it out of the LTCA, and the window of tooth pairs
    shifts by one between the grid's last position and the angle one step before its first.
    So a bracket end is checked before the search relies on it: where the Newton step
    leaves the bracket past an end whose sign was never evaluated, or the bracket shrinks
    onto it, the next point is that end; if its sign is the wrong one the bracket moves
    outwards by its initial width and the new end is checked (5 of 400 random
    29/71 designs had $H > 0$ at the grid's lower end, so the search shrank onto it and
    never converged). Converged once $|H| \\le$ atol and either the Newton step or the bracket is
    below atol + rtol$|\\varphi_1|$ (the tolerances of `Accuracy.newton_atol/rtol`, floored
    near machine precision); stopped where $H$ jumps (`_jump`); at most `impact_max_steps`
    evaluations. No gradient flows through the iteration (`first_contact` supplies it).
    """
    ctx, column, lower, upper, gap_lower, gap_upper = jax.lax.stop_gradient(
        (ctx, column, lower, upper, gap_lower, gap_upper)
    )
    atol, rtol, tiny = _tolerances(ctx, lower.dtype)
    # One trace of the evaluation serves the loop body and the shape of its carry.
    evaluate_at = eqx.filter_closure_convert(lambda p: evaluate(ctx, column, p), lower)
    width = upper - lower
    start = lower - safe_divide(gap_lower * width, gap_upper - gap_lower, 0.5 * width)
    margin = width / 64
    start = jnp.where(jnp.isfinite(start), jnp.clip(start, lower + margin, upper - margin), lower + 0.5 * width)
    contact, (j, solved) = jax.tree_util.tree_map(
        lambda s: jnp.zeros(s.shape, s.dtype) if isinstance(s, jax.ShapeDtypeStruct) else s, evaluate_at.out_struct
    )
    zero = jnp.zeros((), jnp.int32)
    initial = _SearchState(
        lower, upper, jnp.zeros(2, bool), start, zero, width, jnp.zeros((2, 2), lower.dtype),
        _Search(start, contact, j, solved, zero, jnp.zeros((), bool), jnp.zeros((), bool)),
    )
    max_steps = ctx.model.accuracy.impact_max_steps

    def cond(state: _SearchState):
        s = state.search
        return (s.steps == 0) | (found & ~s.converged & ~s.jumped & (s.steps < max_steps))

    def body(state: _SearchState):
        x = state.point
        contact, (j, solved) = evaluate_at(x)
        h, dh = contact.gap, contact.gap_slope
        below = h < 0
        # A checked end of the wrong sign: the crossing lies beyond it, so the bracket
        # moves outwards by its initial width.
        out_down = (state.probe == -1) & ~below
        out_up = (state.probe == 1) & below
        lower = jnp.where(below, x, jnp.where(out_down, x - width, state.lower))
        upper = jnp.where(below, jnp.where(out_up, x + width, state.upper), x)
        checked = jnp.stack([jnp.where(below, True, state.checked[0] & ~out_down),
                             jnp.where(below, state.checked[1] & ~out_up, True)])
        tol = atol + rtol * jnp.abs(x)
        increasing = dh > tiny
        newton = -safe_divide(h, jnp.where(increasing, dh, 0.0))
        converged = (jnp.abs(h) <= atol) & ((upper - lower <= tol) | (increasing & (jnp.abs(newton) <= tol)))
        candidate = x + newton
        take_newton = (
            increasing & (candidate > lower) & (candidate < upper) & (jnp.abs(newton) <= 0.5 * state.last_step)
        )
        point = jnp.where(take_newton, candidate, lower + 0.5 * (upper - lower))
        # Check an end before relying on it: where the step leaves the bracket past it, or
        # the bracket has shrunk onto it.
        shrunk = upper - lower <= tol
        check_lower = ~checked[0] & (out_down | (increasing & (candidate <= lower)) | (shrunk & ~below))
        check_upper = ~checked[1] & ~check_lower & (out_up | (increasing & (candidate >= upper)) | (shrunk & below))
        point = jnp.where(check_lower, lower, jnp.where(check_upper, upper, point))
        probe = jnp.where(check_lower, -1, jnp.where(check_upper, 1, 0)).astype(jnp.int32)
        ends, rises = _jump(state.ends, below, h, dh, lower, upper, atol)
        jumped = shrunk & checked[0] & checked[1] & ~converged & rises
        search = _Search(x, contact, j, solved, state.search.steps + 1, converged, jumped)
        return _SearchState(lower, upper, checked, point, probe, jnp.abs(point - x), ends, search)

    return jax.lax.while_loop(cond, body, initial).search


@eqx.filter_custom_jvp
def first_contact(ctx: SearchContext, column, lower, upper, gap_lower, gap_upper, found) -> _Search:
    """First contact of pair `column` in `[lower, upper]` (see `_search`), with the
    gradients of the implicit function theorem: returns a `_Search` whose pinion angle
    $\\varphi_1^*$ and contact carry $\\mathrm d/\\mathrm d\\theta$ through the root.

    Differentiating evaluates the contact once more at $\\varphi_1^*$: with
    $\\dot H_\\theta$ the change of $H$ along the parameters' tangent at fixed angle,
    $\\dot\\varphi_1^* = -\\dot H_\\theta / H'$ (zero where $H' = 0$: tangential engagement of
    unloaded perfect flanks), and every output $Q$ (the rates included, so their change
    along $\\varphi_1$ enters) changes by $\\dot Q_\\theta + Q'\\dot\\varphi_1^*$, one
    forward-mode pass along $(\\dot\\theta, \\dot\\varphi_1^*)$. The bracket does not
    change the root, so its tangents are ignored. First order only.
    """
    return _search(ctx, column, lower, upper, gap_lower, gap_upper, found)


@first_contact.def_jvp
def _first_contact_jvp(primals, tangents):
    ctx, column = primals[:2]
    search = _search(*primals)
    root = search.pinion_angle
    diff, static = eqx.partition(ctx, eqx.is_inexact_array)
    d_ctx = jax.tree_util.tree_map(
        lambda x, t: None if x is None else (jnp.zeros_like(x) if t is None else t),
        diff,
        tangents[0],
        is_leaf=lambda v: v is None,
    )

    def contact_at(d, p):
        return evaluate(eqx.combine(d, static), column, p)[0]

    _, gap_tangent = jax.jvp(lambda d: contact_at(d, root).gap, (diff,), (d_ctx,))
    _, _, tiny = _tolerances(ctx, root.dtype)
    slope = search.contact.gap_slope
    d_root = -jnp.where(jnp.abs(slope) > tiny, safe_divide(gap_tangent, slope), 0.0)
    _, d_contact = jax.jvp(contact_at, (diff, root), (d_ctx, d_root))
    d_contact = jax.tree_util.tree_map(
        lambda t, x: t if eqx.is_inexact_array(x) else None, d_contact, search.contact
    )
    d_search = _Search(d_root, d_contact, None, None, None, None, None)
    return search, d_search


def bracket(tca: TCAResult, ltca: LTCAResult, columns=None):
    """First upward crossing of $H$ along the tracked tooth's history on the cycle grid:
    `(found, column, lower, upper, gap_lower, gap_upper)`; among the pairs `columns` only
    (a NumPy index array into the pair axis, default all: one contact zone's window).

    Pair $k$ at pinion angle $\\varphi_1$ is pair 0 at $\\varphi_1 - kp$, so ordering the
    grid by descending pair and ascending angle follows one tooth through the mesh. The
    gap at `upper` is the scene's, with pair $k$ loaded: it only seeds the first step. On
    point-contact flanks the offsets are the located peaks and the loaded TE counts from
    the largest of them, as in `evaluate`.
    """
    if ltca.point_contact is None:
        offsets = jnp.max(jnp.where(tca.valid, tca.slice_te, -jnp.inf), axis=-1)  # (pos, pair)
        loaded = ltca.transmission_error
    else:
        located = closest_contact(tca)
        offsets = jnp.where(jnp.isfinite(located["gap"]), located["te"], -jnp.inf)
        loaded = jnp.max(offsets, axis=-1) - ltca.rotation
    columns = np.arange(offsets.shape[-1]) if columns is None else np.asarray(columns)
    h = offsets[:, columns] - loaded[:, None]
    n_pos, n_pair = h.shape
    line = h[:, ::-1].T.reshape(-1)
    tracked = jnp.repeat(jnp.asarray(columns)[::-1], n_pos)
    angles = jnp.tile(tca.pinion_angle, n_pair)
    up = (line[1:] >= 0) & (line[:-1] < 0)
    i = jnp.argmax(up) + 1
    step = tca.pinion_angle[1] - tca.pinion_angle[0]
    return jnp.any(up), tracked[i], angles[i] - step, angles[i], line[i - 1], line[i]
