r"""Solving the slice problems of the general TCA (`_slice_problem.py`): starts, screening,
the three candidates' Newton solves, and the choice of the first contact.

A candidate counts only if its Newton solve converged and its contact lies on the active
flanks; the slice value is the largest valid $\Delta$ (the first feature to touch). The edge
and flank candidates coincide when the flank contact reaches the tip, so the slice value is
continuous, and (envelope theorem) so is its derivative with respect to the pinion angle.

An edge contact is the first contact only if it is a local maximum of $\Delta$ along the
curve of coincident points, i.e. if $\Delta$ rises towards the tip there
(`edge_is_first`). Where it falls at the edge the selection would keep, a flank contact
inside the active flanks touches first; if the flank solve missed it (Newton went to a
root beyond the tip, which the selection rejects), the flank candidate counts as failed
and the analysis solves it again from the edge contact with the damped Newton
(`solve_again`: on random designs with deep reliefs the flank root beyond the
tip hid the interior one at some pinion angles, so the slice value jumped by up to 3e-4
rad between neighbouring angles).

Every solve is `optimistix.root_find(..., Newton)` with the implicit adjoint of
`gearjax._solution` (no host callback) and the residual at module level and data passed as
`args`; the analysis solves the candidates whose Newton solve failed again with a damped
Newton (`gearjax.tca._newton.SafeguardedNewton`); failures are reported (`converged`), never
thrown. The analysis runs all of it on stop-gradient'ed data and gives the kept contact the
derivatives of its own root (`attach_derivatives`): the same derivatives as through its
solve, without tracing the others.
"""

from __future__ import annotations

import functools as ft

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx

from .._numerics import cross2, safe_norm
from .._solution import ADJOINT, implicit_root
from ..geometry._base import AbstractFlankPair
from ._slice_problem import (
    FLANK,
    SliceContact,
    SliceProblem,
    _coincidence_weight,
    _contact_residual,
    _parameter_tolerance,
    _weighted_residual,
    _within,
)
from .branch import on_extended_flanks


def _starts(problem: SliceProblem):
    """Starting points of the three candidates: the conjugate contact for the flank, held
    to the active flanks (beyond a tip a relief's parabola, extrapolated, tilts the flank
    so far that Newton runs off); for an edge, the mate's flank point at the
    radius of the tip corner."""
    pair = problem.pair
    lim1, lim2 = pair.profile_limits(0), pair.profile_limits(1)
    g1, g2 = pair.contact_guess(problem.pinion_rotation)
    g1, g2 = jnp.clip(g1, *lim1), jnp.clip(g2, *lim2)
    zero = jnp.zeros_like(g1)
    corner2 = problem.gear_point(lim2[1], zero)
    edge2_u1 = pair.parameter_at_radius(0, safe_norm(corner2 - pair.center(0)))
    corner1 = problem.pinion_point(lim1[1])
    edge1_u2 = pair.parameter_at_radius(1, safe_norm(corner1 - pair.center(1)))
    u1 = jnp.stack([g1, edge2_u1, jnp.broadcast_to(lim1[1], g1.shape)])
    u2 = jnp.stack([g2, jnp.broadcast_to(lim2[1], g2.shape), edge1_u2])
    dom1, dom2 = pair.parameter_domain(0), pair.parameter_domain(1)
    # Offset: the first-order (plane-of-action) value, the sum of both flanks' transverse
    # depths at the conjugate point turned into a gear rotation.
    depth1 = problem.depth.transverse(pair, 0, problem.pair_index, g1, problem.z)
    depth2 = problem.depth.transverse(pair, 1, problem.pair_index, g2, problem.z)
    offset = jnp.broadcast_to(-(depth1 + depth2) / pair.action_radius(1), u1.shape)
    return jnp.stack([jnp.clip(u1, *dom1), jnp.clip(u2, *dom2), offset], axis=-1)


def relevance(problem: SliceProblem):
    """Which candidates can touch on the active flanks, judged from the conjugate contact
    $(u_1, u_2)$ of the slice (3,): the flank contact near the active flanks, the gear-tip
    edge before and around the start of engagement, the pinion-tip edge around and after
    its end. Screening the others out keeps the batched Newton loop from iterating on
    problems without a solution (under `vmap` every slice would pay for them)."""
    pair = problem.pair
    (lo1, hi1), (lo2, hi2) = pair.profile_limits(0), pair.profile_limits(1)
    g1, g2 = pair.contact_guess(problem.pinion_rotation)
    m1, m2 = 0.25 * (hi1 - lo1), 0.25 * (hi2 - lo2)
    flank = (g1 > lo1 - m1) & (g1 < hi1 + m1) & (g2 > lo2 - m2) & (g2 < hi2 + m2)
    if not pair.screen_edges:
        # Non-conjugate families (double circular arc): the guess does not follow the
        # contact, so the edges are analysed wherever the flank is.
        return jnp.stack([flank, flank, flank])
    gear_edge = (g2 > hi2 - m2) & (g2 < hi2 + 2 * m2)
    pinion_edge = (g1 > hi1 - m1) & (g1 < hi1 + 2 * m1)
    return jnp.stack([flank, gear_edge, pinion_edge])


def _solve(problem, solver, max_steps, y0, selector, relevant):
    """One candidate solve: its value, converged (successful and relevant), and failed
    (relevant, unsuccessful, last iterate on the active flanks: where the solve may have
    missed a contact; an iterate off them, on a free coordinate, is heading for a root
    that `select_contact` would reject anyway: held at the domain's bound at the base
    circle, or creeping (a near-double root) beyond a tip where the edge candidate takes
    over). Iterates are bounded to the flanks' parameter domain."""
    pair = problem.pair
    dom1, dom2 = pair.parameter_domain(0), pair.parameter_domain(1)
    one = jnp.ones_like(dom1[0])
    options = dict(lower=jnp.stack([dom1[0], dom2[0], -one]), upper=jnp.stack([dom1[1], dom2[1], one]))
    weight = _coincidence_weight(pair, solver.atol)
    sol = optx.root_find(
        _weighted_residual, solver, y0, args=(weight, (problem, selector, y0, relevant)), options=options,
        max_steps=max_steps, throw=False, adjoint=ADJOINT,
    )
    success = sol.result == optx.RESULTS.successful
    (lo1, hi1), (lo2, hi2) = pair.profile_limits(0), pair.profile_limits(1)
    active_hi = jnp.stack([hi1, hi2])
    free = jnp.stack([selector[2] == 0, selector[1] == 0])
    on_flanks = _within(sol.value[:2], (jnp.stack([lo1, lo2]), active_hi), _parameter_tolerance(active_hi))
    off_flank = jnp.any(free & ~on_flanks)
    return sol.value, success & relevant, relevant & ~success & ~off_flank


def _on_active_flanks(pair: AbstractFlankPair, values):
    """Candidates (..., 3) whose contact $(u_1, u_2)$ lies on the active flanks."""
    lim1, lim2 = pair.profile_limits(0), pair.profile_limits(1)
    tol = _parameter_tolerance(lim1[1])
    return _within(values[..., 0], lim1, tol) & _within(values[..., 1], lim2, tol)


def edge_is_first(problem: SliceProblem, values):
    r"""Whether each edge candidate (rows of `values`, (3, 3)) is a local maximum of the
    offset along the curve of coincident points (3,; True for the flank row).

    On that curve $X_1(u_1) = X_2(u_2, \Delta)$, so $t_1\,du_1 = t_2\,du_2 + g\,d\Delta$
    with $t_i$ the profile tangents and $g = \partial X_2/\partial\Delta$; hence
    $d\Delta/du_2 = -(t_1\times t_2)/(t_1\times g)$ at the gear's tip edge and
    $d\Delta/du_1 = (t_2\times t_1)/(t_2\times g)$ at the pinion's. The edge (the end
    $u = u_\text{tip}$ of its flank's active range) touches first only if the offset rises
    towards it: the derivative, as the sine of the angle between the tangents, is not below
    $-10^3\varepsilon$."""

    def first(row, y):
        u1, u2, offset = y[0], y[1], y[2]
        _, t1 = problem.pinion_tangent(u1)
        _, t2 = problem.gear_tangent(u2, offset)
        _, g = jax.jvp(lambda d: problem.gear_point(u2, d), (offset,), (jnp.ones_like(offset),))
        # the sign of d offset / d u along the curve, scaled to the sine between the tangents
        gear_tip = -cross2(t1, t2) * jnp.sign(cross2(t1, g))
        pinion_tip = cross2(t2, t1) * jnp.sign(cross2(t2, g))
        rate = jnp.where(row == 1, gear_tip, pinion_tip) / (safe_norm(t1) * safe_norm(t2))
        eps = float(jnp.finfo(jnp.result_type(offset)).eps)
        return (row == FLANK) | (rate >= -1e3 * eps)

    return jax.vmap(first)(jnp.arange(3), values)


#: Points at which `edge_reachable` samples an active flank's distance from the mate's axis.
REACH_SAMPLES = 5


def edge_reachable(problem: SliceProblem):
    r"""Whether each edge candidate's tip corner can meet the mate's active flank (3,; True
    for the flank row).

    A tip corner turns with its gear, so at every gear offset it stays on one circle about
    that gear's axis $O_2$; so does every point of the gear flank. The gear's tip corner
    can touch the pinion's active flank only where that flank crosses the corner's circle,
    and the pinion's tip corner (fixed for the slice) can touch the gear's active flank
    only if its distance from $O_2$ lies among the radii of that flank. Both ranges are
    sampled at `REACH_SAMPLES` points of the active flank, ends included (the radius of a
    gear flank point grows with $u_2$; the pinion flank's distance from $O_2$ is monotone
    along it on involute flanks near the mesh), and a corner outside its range by more than
    `_parameter_tolerance` cannot touch: its failed solve misses no contact
    (17/170 random design 68, where the gear's tip circle misses the pinion's active flank at
    one slice and the edge solve, with no root to find, diverged)."""
    pair = problem.pair
    (lo1, hi1), (lo2, hi2) = pair.profile_limits(0), pair.profile_limits(1)
    o2 = pair.center(1)
    zero = jnp.zeros_like(problem.pinion_rotation)
    t = jnp.linspace(0.0, 1.0, REACH_SAMPLES, dtype=zero.dtype)
    pinion_flank = jax.vmap(lambda f: safe_norm(problem.pinion_point(lo1 + f * (hi1 - lo1)) - o2))(t)
    gear_flank = jax.vmap(lambda f: safe_norm(problem.gear_point(lo2 + f * (hi2 - lo2), zero) - o2))(t)
    # The corners are the flanks' last samples (f = 1: u = u_tip).
    gear_corner, pinion_corner = gear_flank[-1], pinion_flank[-1]

    def within(radius, radii):
        tol = _parameter_tolerance(radius)  # radii are lengths in mm, like the parameters
        return (radius >= jnp.min(radii) - tol) & (radius <= jnp.max(radii) + tol)

    return jnp.stack([jnp.ones((), bool), within(gear_corner, pinion_flank), within(pinion_corner, gear_flank)])


def _missed_flank(problem: SliceProblem, values, converged):
    """Edge candidates (3,) that `select_contact` would keep (valid, largest offset)
    although a flank contact inside the active flanks touches first (`edge_is_first`
    false): where the flank candidate is not valid too, the flank solve missed its contact.

    Only the kept edge proves a miss: the offset rises inwards from an edge that is not
    first, but the curve of coincident points may rise all the way to the other edge (the
    double circular arc's convex-on-concave zones: from the pinion's tip to the gear's),
    which is then valid, higher, and the slice's true contact."""
    ok = converged & _on_active_flanks(problem.pair, values)
    kept = ok & (values[:, 2] >= jnp.max(jnp.where(ok, values[:, 2], -jnp.inf)))
    return kept & ~edge_is_first(problem, values) & ~ok[FLANK]


def solve_candidates(problem: SliceProblem, solver: optx.AbstractRootFinder, max_steps: int):
    """Solve the three candidate problems of one slice: values (3, 3), converged (3,)
    (False for candidates screened out by `relevance`) and failed (3,) (relevant but not
    converged, last iterate on the active flanks, and for an edge of an involute family
    its corner able to reach the mate's active flank, `edge_reachable`; and the flank
    candidate where an edge contact proves that its solve missed an interior contact,
    `_missed_flank`: the TCA solves those again with `solve_again`)."""
    selectors = jnp.eye(3, dtype=problem.z.dtype)
    # Starts, screening and the missed-flank check carry no derivative (the implicit
    # adjoint gives the root's from the residual at the root, wherever Newton started), so
    # they see stop_gradient'ed data and differentiating the TCA does not trace them.
    fixed = jax.lax.stop_gradient(problem)
    values, converged, failed = jax.vmap(ft.partial(_solve, problem, solver, max_steps))(
        _starts(fixed), selectors, relevance(fixed))
    missed = jnp.any(_missed_flank(fixed, jax.lax.stop_gradient(values), converged))
    if problem.pair.conjugate_slices:
        failed = failed & edge_reachable(fixed)
    return values, converged, failed.at[FLANK].set(failed[FLANK] | missed)


def solve_again(problem: SliceProblem, candidate, solver: optx.AbstractRootFinder, max_steps: int, relevant,
                values, converged):
    """Solve candidate `candidate` (index into `CANDIDATES`) of one slice again with another
    solver (the TCA's fallback for failed Newton solves): its value, converged and failed
    as in `solve_candidates`. `relevant=False` (a padding entry of a fixed-size batch)
    solves the trivial problem $y = y_0$ in one step.

    It starts where the first solve did, whose `values` (3, 3) and `converged` (3,) are
    given; a flank candidate that missed its contact (`_missed_flank`) starts instead from
    the edge contact that proved it (plain Newton from there often runs past the tip too)
    and still fails unless this solve ends on the active flanks."""
    fixed, values = jax.lax.stop_gradient((problem, values))  # as in `solve_candidates`
    missed = _missed_flank(fixed, values, converged) & (candidate == FLANK)
    start = jnp.where(jnp.any(missed), values[jnp.argmax(missed)], _starts(fixed)[candidate])
    value, ok, failed = _solve(problem, solver, max_steps, start, jnp.eye(3, dtype=problem.z.dtype)[candidate],
                               jnp.asarray(relevant))
    again = jnp.any(missed) & ~(ok & _on_active_flanks(problem.pair, value))
    return value, ok, failed | (again & relevant)


def select_contact(pair: AbstractFlankPair, values, converged, failed, rule=None) -> SliceContact:
    """Keep the first contact among the valid candidates (largest offset); `rule`, a
    `Branch.rule` of the slice's pair, holds it to one branch of the regime switch."""
    ok = converged & _on_active_flanks(pair, values)
    if rule is not None:
        allowed, extended = rule
        ok = allowed & jnp.where(extended, converged & on_extended_flanks(pair, values), ok)
    # On ties (flank contact exactly at a tip) argmax keeps the first: the flank.
    kind = jnp.argmax(jnp.where(ok, values[:, 2], -jnp.inf))
    any_ok = jnp.any(ok)
    return SliceContact(
        offset=jnp.where(any_ok, values[kind, 2], -jnp.inf),
        pinion_parameter=values[kind, 0],
        gear_parameter=values[kind, 1],
        kind=kind,
        valid=any_ok,
        unconverged=jnp.sum(failed),
    )


def attach_derivatives(problem: SliceProblem, contact: SliceContact) -> SliceContact:
    r"""`contact`, solved on stop-gradient'ed data, with the derivatives of its
    $(u_1, u_2, \Delta)$ as the root of its own candidate's residual (`_contact_residual`,
    implicit function theorem: `implicit_root`); no derivative where the slice does not
    touch (there the found values are kept, and their derivatives are zero). So
    differentiating a TCA traces one residual per slice, not the three candidates'
    iterations, the fallback or the choice between them; the values are unchanged. The
    residual is unweighted: the rows' weights (`_coincidence_weight`) change no root."""
    selector = jax.nn.one_hot(contact.kind, 3, dtype=problem.z.dtype)
    found = jnp.stack([contact.pinion_parameter, contact.gear_parameter, jnp.where(contact.valid, contact.offset, 0.0)])
    # where the slice does not touch, the rule linearises the residual at a finite point
    # (a failed solve may have left NaN), and the values found are kept
    y = jnp.where(contact.valid, found, jnp.nan_to_num(found, nan=0.0, posinf=0.0, neginf=0.0))
    y = implicit_root(_contact_residual, y, (problem, selector, jax.lax.stop_gradient(y), contact.valid))
    y = jnp.where(contact.valid, y, found)
    return eqx.tree_at(lambda c: (c.pinion_parameter, c.gear_parameter, c.offset), contact,
                       (y[0], y[1], jnp.where(contact.valid, y[2], -jnp.inf)))


def solve_slice(problem: SliceProblem, solver: optx.AbstractRootFinder, max_steps: int) -> SliceContact:
    """First contact of one slice (general TCA)."""
    values, converged, failed = solve_candidates(problem, solver, max_steps)
    return select_contact(problem.pair, values, converged, failed)
