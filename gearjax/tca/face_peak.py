r"""The first touching point of one tooth pair along the face, found continuously in $z$.

At a pinion angle $\varphi_1$ the slice value of pair $k$,
$g(z) = \max_c \Delta_{kc}(z) + \lambda(z)$ over its valid candidates $c$ (flank, tip
edges; $\lambda$ the leads' correction, `analysis._lead_correction`), is known on the face
slices only. Its maximum over the face, $g^* = \max_{|z| \le b/2} g(z)$, is where the pair
touches first; sampled at the slices it can be missed by far: a tip edge crossing a short,
deep relief touches over a stretch of the face narrower than the slice spacing, so the
slices see it late or never (seed 001 pair, a 24 µm root relief over 0.5 mm: the edge's
peak lies 12 µrad above the best of 21 slices, and the first contact found on them is a
flank contact 3.3 mrad later).

`face_peak` maximises $g$ on the face stretch around the best slice, one slice spacing to
each side, clipped to the face, by repeated grid refinement: $g$ at `GRID_POINTS` equally
spaced points of the stretch, ends included (so a peak at a face end, the tip-edge ×
face-end corner, is a grid point from the start), then the stretch between the best
point's neighbours, a quarter of the previous one, `GRID_ROUNDS` times. The search is
derivative-free, since $g$ kinks where the binding candidate changes (a flank contact
reaching a tip, a relief's start), and keeps the best slice if it is higher. Like any
bracketing search it converges to a local maximum of the stretch; a second peak more than a
slice spacing away from the best slice is found only when the slices see it. Each
evaluation solves its slices as the TCA solves its grid, the damped fallback included
(`slice_values`), so $g$ at a slice position is the TCA's slice value. All the search's
evaluations, and the last solve at $z^*$ and its neighbours, go through one vmapped slice
solve inside one loop, so the solve is traced once.

Derivatives follow the envelope theorem: the search runs on stop-gradient'ed data and
$g^*$ is evaluated at the found $z^*$, so $\mathrm dg^*/\mathrm d\theta = \partial g/\partial
\theta\,(z^*)$, exact at a smooth interior maximum or a face end, one-sided at a kink.
The polish round places a smooth interior maximum at the vertex of the parabola through $z^*$
and its neighbours at $\pm h$ (`_vertex`), and the differentiable value does it once more
around that point, from the loop's last solve there with the derivatives of each contact's
root (`attach_derivatives`): the search, comparing values, places it only to
about $\sqrt{\epsilon}$ of the stretch, and what is evaluated there (the strike point,
its normal and velocity) must move with the maximum as the design changes
($\mathrm dz^*/\mathrm d\theta = -g_{z\theta}/g_{zz}$); at a face end or a kink $z^*$ is
pinned.
"""

from __future__ import annotations

import functools as ft

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, Scalar
from .._numerics import as_float
from ._slice_problem import SliceContact
from .analysis import _lead_correction, _plane_of_action_slice, attach_grid, contact_point, solve_grid

#: points per refinement round, the stretch's ends included
GRID_POINTS = 9
#: rounds: the stretch (two slice spacings at most) shrinks by (2/8)^16 = 2e-10
GRID_ROUNDS = 16
#: step $h$ of the parabola around $z^*$ (`_vertex`), in slice spacings
FD_STEP = 1e-3


class FacePeak(eqx.Module):
    """The first touching point of one tooth pair at one pinion angle.

    Attributes:
        z: axial position $z^*$ (mm).
        te: $g^* = g(z^*)$, the gear offset at which the pair touches (rad, gear 2).
        contact: the slice contact at $z^*$ (`SliceContact`: parameters, candidate kind).
        pinion_point, gear_point: the contact on each flank, fixed frame (mm).
        normal: outward unit normal of the pinion flank there.
        relative_velocity: $v^{(12)}$ per unit pinion speed, nominal ratio (mm/rad).
    """

    z: Scalar
    te: Scalar
    contact: SliceContact
    pinion_point: Array
    gear_point: Array
    normal: Array
    relative_velocity: Array


def slice_values(pair, depth, accuracy, k, phi1, zs, branch=None) -> tuple[SliceContact, Array]:
    """The contacts of pair `k`'s slices at the axial positions `zs` (n,) and their values
    $g(z)$ (n,; rad, `-inf` where no candidate touches on the active flanks), solved as the
    TCA solves its grid (`analysis.solve_grid`: the damped fallback included, without which
    a flank solve that ran past the tip leaves the edge as the slice's contact, and $g$
    jumps by up to 3e-4 rad); `branch` as there."""
    if accuracy.tca_method == "surface":
        grid = solve_grid(pair, depth, accuracy, phi1[None], k[None], zs, branch=branch)
        contact = jax.tree_util.tree_map(lambda x: x[0, 0], grid)
    else:
        contact = jax.vmap(lambda zz: _plane_of_action_slice(pair, depth, k, zz, phi1))(zs)
    return contact, _values(pair, contact, zs)


def _values(pair, contact: SliceContact, zs):
    """$g(z)$ of slice contacts at `zs` (rad): offset plus the leads' correction, `-inf`
    where the slice does not touch."""
    return jnp.where(contact.valid, contact.offset + jax.vmap(ft.partial(_lead_correction, pair))(zs), -jnp.inf)


def face_peak(pair, depth, accuracy, k, phi1, z_best, te_best, spacing, branch=None) -> FacePeak:
    """Maximise pair `k`'s slice value over `[z_best - spacing, z_best + spacing]` clipped to
    the face (see the module docstring); `z_best`, `te_best` are the best slice's position
    and value, kept where the search finds nothing higher; `branch` holds the pair to one
    branch of the regime switch (`tca.branch`)."""
    half, step = 0.5 * pair.face_width, FD_STEP * spacing
    k = as_float(k)
    # the search sees no derivative at all
    fixed_phi, z0, g0, fixed_half, fixed_step, fixed_spacing = jax.lax.stop_gradient(
        (phi1, z_best, te_best, half, step, spacing))
    frozen = jax.lax.stop_gradient((pair, depth))
    surface = accuracy.tca_method == "surface"

    lo = jnp.clip(z0 - fixed_spacing, -fixed_half, fixed_half)
    hi = jnp.clip(z0 + fixed_spacing, -fixed_half, fixed_half)
    fractions = jnp.linspace(0.0, 1.0, GRID_POINTS, dtype=z0.dtype)
    around = fixed_step * jnp.zeros(GRID_POINTS, z0.dtype).at[:3].set(jnp.array([-1.0, 0.0, 1.0], z0.dtype))
    # One trace of the slice solve serves every round and the shape of the loop's carry.
    solve = eqx.filter_closure_convert(lambda zs: slice_values(*frozen, accuracy, k, fixed_phi, zs, branch), fractions)

    def interior(z):
        return (z - fixed_step > -fixed_half) & (z + fixed_step < fixed_half)

    def refine(r, state):
        # rounds 0 .. GRID_ROUNDS - 1 refine the grid; round GRID_ROUNDS moves a smooth
        # maximum to its vertex (`_vertex` on z* +- h) and the last one solves z* +- h
        # again there for the differentiable value: the same 9-point solve, one trace
        lo, hi, z_best, g_best, _ = state
        polish, last = r == GRID_ROUNDS, r > GRID_ROUNDS
        zs = jnp.where(polish | last, jnp.clip(z_best + around, -fixed_half, fixed_half), lo + fractions * (hi - lo))
        contacts, gs = solve(zs)
        i = jnp.argmax(gs)
        better = gs[i] > g_best
        z_grid, g_grid = jnp.where(better, zs[i], z_best), jnp.where(better, gs[i], g_best)
        first3 = jax.tree_util.tree_map(lambda x: x[:3], contacts)
        shift, g_vertex, _ = _vertex(first3, gs[:3], fixed_step, interior(z_best))
        z_next = jnp.where(last, z_best, jnp.where(polish, z_best + shift, z_grid))
        g_next = jnp.where(last, g_best, jnp.where(polish, jnp.where(shift != 0.0, g_vertex, g_best), g_grid))
        return zs[jnp.maximum(i - 1, 0)], zs[jnp.minimum(i + 1, GRID_POINTS - 1)], z_next, g_next, first3

    blank = jax.tree_util.tree_map(lambda x: jnp.zeros((3, *x.shape[1:]), x.dtype), solve.out_struct[0])
    # the best slice competes with the search; the last round only where its solve is used
    rounds = GRID_ROUNDS + 1 + int(surface)
    _, _, z_found, _, found = jax.lax.fori_loop(0, rounds, refine, (lo, hi, z0, g0, blank))
    z_star = jax.lax.stop_gradient(z_found)
    # z* and its neighbours at +-h (the last round's solve), differentiable: a smooth
    # maximum moves with the data to the vertex of their parabola (`_vertex`)
    zs = jnp.clip(z_star + step * jnp.array([-1.0, 0.0, 1.0], z_star.dtype), -half, half)
    if surface:
        contacts = jax.tree_util.tree_map(lambda x: x[0, 0], attach_grid(
            pair, depth, phi1[None], k[None], zs, jax.tree_util.tree_map(lambda x: x[None, None], found)))
        gs = _values(pair, contacts, zs)
    else:
        contacts, gs = slice_values(pair, depth, accuracy, k, phi1, zs, branch)
    shift, te, contact = _vertex(contacts, gs, step, interior(z_star))
    x1, x2, n, v12, _ = contact_point(pair, depth, phi1, k, z_star + shift, contact.pinion_parameter,
                                      contact.gear_parameter, jnp.where(jnp.isfinite(te), te, 0.0))
    return FacePeak(z_star + shift, te, contact, x1, x2, n, v12)


def _vertex(contacts: SliceContact, gs, step, interior):
    r"""A smooth interior maximum placed at the vertex of the parabola through $g$ at
    $z^* - h, z^*, z^* + h$: `(shift, g, contact)`, the vertex's offset from $z^*$, the
    parabola's value there and the slice contact with its parameters moved along their
    central differences.

    The search compares values, so it places a smooth maximum only to about
    $\sqrt\epsilon$ of its stretch (1e-6 mm on the seed pair), where the vertex is set
    by the slope's rounding (1e-9 mm); and the vertex moves with the data $\theta$ (pinion
    angle, design) as $\mathrm dz^*/\mathrm d\theta = -g_{z\theta}/g_{zz}$ (implicit
    function theorem on $g_z = 0$), so the strike point, its normal and its velocity follow
    the maximum as the design changes. At a face end, at a kink (the three points'
    candidates differ) or where the parabola is not concave, $z^*$ stays (pinned)."""
    same = jnp.all(contacts.valid) & jnp.all(contacts.kind == contacts.kind[1]) & jnp.all(jnp.isfinite(gs))
    g = jnp.where(same, gs, 0.0)
    curvature = jax.lax.stop_gradient((g[2] - 2.0 * g[1] + g[0]) / step**2)
    smooth = interior & same & (curvature < 0.0)
    slope = (g[2] - g[0]) / (2.0 * step)
    shift = jnp.where(smooth, jnp.clip(-slope / jnp.where(smooth, curvature, -1.0), -step, step), 0.0)
    value = jnp.where(smooth, g[1] + slope * shift + 0.5 * curvature * shift**2, gs[1])

    def moved(u):
        return u[1] + jnp.where(smooth, (u[2] - u[0]) / (2.0 * step), 0.0) * shift

    contact = jax.tree_util.tree_map(lambda x: x[1], contacts)
    contact = eqx.tree_at(lambda c: (c.pinion_parameter, c.gear_parameter), contact,
                          (moved(contacts.pinion_parameter), moved(contacts.gear_parameter)))
    return shift, value, contact
