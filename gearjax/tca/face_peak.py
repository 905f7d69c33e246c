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
evaluations go through one vmapped slice solve inside one loop, so the solve is traced
once for the search (and once more for the differentiable value at $z^*$).

Derivatives follow the envelope theorem: the search runs on stop-gradient'ed data and
$g^*$ is evaluated at the found $z^*$, so $\mathrm dg^*/\mathrm d\theta = \partial g/\partial
\theta\,(z^*)$, exact at a smooth interior maximum or a face end, one-sided at a kink.
"""

from __future__ import annotations

import functools as ft

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx

from .._custom_types import Array, Scalar
from .._newton import SafeguardedNewton
from .._numerics import as_float
from ._slice import SliceContact, make_problem, select_contact, solve_candidates
from .analysis import _lead_correction, _plane_of_action_slice, _retry_failed, contact_point, fallback_steps

#: points per refinement round, the stretch's ends included
GRID_POINTS = 9
#: rounds: the stretch (two slice spacings at most) shrinks by (2/8)^16 = 2e-10
GRID_ROUNDS = 16


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


def slice_values(pair, depth, accuracy, k, phi1, zs) -> tuple[SliceContact, Array]:
    """The contacts of pair `k`'s slices at the axial positions `zs` (n,) and their values
    $g(z)$ (n,; rad, `-inf` where no candidate touches on the active flanks), solved as the
    TCA solves its grid: Newton on the three candidates, then the damped fallback on those
    that failed (`analysis._retry_failed`; without it a flank solve that ran past the tip
    leaves the edge as the slice's contact, and $g$ jumps by up to 3e-4 rad)."""
    if accuracy.tca_method == "surface":
        rtol, atol = accuracy.newton_tolerances(jnp.result_type(phi1))
        steps = accuracy.newton_max_steps

        def one(zz):
            return solve_candidates(make_problem(pair, depth, k, zz, phi1), optx.Newton(rtol=rtol, atol=atol), steps)

        candidates = jax.tree_util.tree_map(lambda x: x[None, None], jax.vmap(one)(zs))
        candidates = _retry_failed(pair, depth, phi1[None], k[None], zs, candidates,
                                   SafeguardedNewton(rtol=rtol, atol=atol), fallback_steps(steps))
        contact = jax.vmap(ft.partial(select_contact, pair))(*(x[0, 0] for x in candidates))
    else:
        contact = jax.vmap(lambda zz: _plane_of_action_slice(pair, depth, k, zz, phi1))(zs)
    return contact, jnp.where(contact.valid, contact.offset + jax.vmap(ft.partial(_lead_correction, pair))(zs),
                              -jnp.inf)


def face_peak(pair, depth, accuracy, k, phi1, z_best, te_best, spacing) -> FacePeak:
    """Maximise pair `k`'s slice value over `[z_best - spacing, z_best + spacing]` clipped to
    the face (see the module docstring); `z_best`, `te_best` are the best slice's position
    and value, kept where the search finds nothing higher."""
    half = 0.5 * pair.face_width
    k = as_float(k)
    fixed_phi, z0, g0 = jax.lax.stop_gradient((phi1, z_best, te_best))
    frozen = jax.lax.stop_gradient((pair, depth))

    lo = jnp.clip(z0 - spacing, -half, half)
    hi = jnp.clip(z0 + spacing, -half, half)
    fractions = jnp.linspace(0.0, 1.0, GRID_POINTS, dtype=z0.dtype)

    def refine(_, state):
        lo, hi, z_best, g_best = state
        zs = lo + fractions * (hi - lo)
        gs = slice_values(frozen[0], frozen[1], accuracy, k, fixed_phi, zs)[1]
        i = jnp.argmax(gs)
        better = gs[i] > g_best
        z_best, g_best = jnp.where(better, zs[i], z_best), jnp.where(better, gs[i], g_best)
        return zs[jnp.maximum(i - 1, 0)], zs[jnp.minimum(i + 1, GRID_POINTS - 1)], z_best, g_best

    # the best slice competes with the search
    _, _, z_found, _ = jax.lax.fori_loop(0, GRID_ROUNDS, refine, (lo, hi, z0, g0))
    z_star = jax.lax.stop_gradient(z_found)
    contact, te = jax.tree_util.tree_map(lambda x: x[0], slice_values(pair, depth, accuracy, k, phi1, z_star[None]))
    x1, x2, n, v12, _ = contact_point(pair, depth, phi1, k, z_star, contact.pinion_parameter,
                                      contact.gear_parameter, jnp.where(jnp.isfinite(te), te, 0.0))
    return FacePeak(z_star, te, contact, x1, x2, n, v12)
