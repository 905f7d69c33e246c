r"""Contact of one tooth pair in one transverse slice: the Newton problems of the general TCA.

In the transverse section at axial position $z$, the pinion flank is the planar curve
$X_1(u_1)$ turned by $\Phi_1$ (its rotation plus lead rotation at $z$) and the gear flank is
$X_2(u_2)$ turned by $\Phi_2 = \tfrac{z_1}{z_2}\Phi_1 + \Delta$. For a pinion position, the
slice *touches* at the gear offset $\Delta$ at which the gear flank, coming back towards the
pinion flank, first meets it. Three kinds of first contact are possible:

* **flank** (surface-to-surface): $X_1(u_1) = X_2(u_2)$ and the tangents are parallel,
  $\hat t_1 \times \hat t_2 = 0$ (3 equations in $u_1, u_2, \Delta$). In 3-D this is
  Litvin's contact condition: coincident points and collinear normals, and it implies
  the meshing equation $n\cdot v^{(12)} = 0$ for continuous tangency.
* **gear-tip edge** on the pinion flank: $X_1(u_1) = X_2(u_{2,\text{tip}})$ (2 equations in
  $u_1, \Delta$).
* **pinion-tip edge** on the gear flank: $X_1(u_{1,\text{tip}}) = X_2(u_2)$.
"""

from __future__ import annotations

import functools as ft

import equinox as eqx
import jax.numpy as jnp

from .._custom_types import Array, Float, Scalar
from .._numerics import as_float, cross2, safe_divide, safe_norm
from .._solution import enum_select
from ..geometry._base import AbstractFlankPair
from ..geometry.depth import FlankDepth


class ContactKind(eqx.Enumeration):
    """What touches at a slice contact (items are pytrees: they pass `jit` and `vmap`)."""

    flank = "flank contact: surface to surface"
    gear_tip_edge = "the gear's tip edge on the pinion flank"
    pinion_tip_edge = "the pinion's tip edge on the gear flank"


#: The three candidates of a slice in the order of their solves (rows of the one-hot
#: selector of `_contact_residual`); `SliceContact.kind` is an index into it.
CANDIDATES = (ContactKind.flank, ContactKind.gear_tip_edge, ContactKind.pinion_tip_edge)
#: index of the flank candidate in `CANDIDATES`
FLANK = 0


def contact_kind(index) -> ContactKind:
    """The `ContactKind` of candidate indices (integer array of any shape; traceable)."""
    return enum_select(index, CANDIDATES)


def kind_index(kind: ContactKind):
    """The candidate indices of `ContactKind`s (the inverse of `contact_kind`; traceable)."""
    return sum(i * (kind == c).astype(jnp.int32) for i, c in enumerate(CANDIDATES))


class SliceProblem(eqx.Module):
    """Data of one (tooth pair, slice, pinion position) contact problem."""

    pair: AbstractFlankPair
    depth: FlankDepth
    pair_index: Scalar  # k: pair k meshes k pitches after pair 0
    z: Scalar  # axial position of the slice (mm)
    pinion_rotation: Scalar  # Phi_1, lead rotation included (rad)

    def _depth_at(self, gear, u):
        """The depth (mm) of `gear`'s flank in this slice at $u$ (`FlankDepth`: a Python 0.0
        where nothing is applied to it)."""
        return self.depth(self.pair, gear, self.pair_index, u, self.z)

    def _depth(self, gear):
        """`_depth_at` as a function of $u$; None where nothing is applied to the flank (then
        the tangent traces no depth)."""
        return ft.partial(self._depth_at, gear) if self.depth.applies_to(gear) else None

    def _gear_rotation(self, offset):
        return self.pinion_rotation / self.pair.gear_ratio + offset

    def pinion_point(self, u1):
        return self.pair.slice_point(0, u1, self.z, self.pinion_rotation, self._depth_at(0, u1))

    def gear_point(self, u2, offset):
        return self.pair.slice_point(1, u2, self.z, self._gear_rotation(offset), self._depth_at(1, u2))

    def pinion_tangent(self, u1):
        """Point and $\\mathrm{d}X_1/\\mathrm{d}u_1$ (`AbstractFlankPair.slice_point_tangent`)."""
        return self.pair.slice_point_tangent(0, u1, self.z, self.pinion_rotation, self._depth(0))

    def gear_tangent(self, u2, offset):
        """Point and $\\mathrm{d}X_2/\\mathrm{d}u_2$ at gear offset `offset`."""
        return self.pair.slice_point_tangent(1, u2, self.z, self._gear_rotation(offset), self._depth(1))


def _contact_residual(y, args):
    """One residual for all three candidate kinds (3 equations in $u_1, u_2, \\Delta$):
    coincident points, and a third equation chosen by the one-hot `selector`: parallel
    tangents (flank), $u_2 = u_{2,\\text{tip}}$ (gear-tip edge) or $u_1 = u_{1,\\text{tip}}$
    (pinion-tip edge). One residual means one Newton solve to trace, vmapped over kinds."""
    problem, selector, start, relevant = args
    u1, u2, offset = y[0], y[1], y[2]
    x1, t1 = problem.pinion_tangent(u1)
    x2, t2 = problem.gear_tangent(u2, offset)
    parallel = safe_divide(cross2(t1, t2), safe_norm(t1) * safe_norm(t2))
    u1_tip = problem.pair.profile_limits(0)[1]
    u2_tip = problem.pair.profile_limits(1)[1]
    third = selector[0] * parallel + selector[1] * (u2 - u2_tip) + selector[2] * (u1 - u1_tip)
    # A candidate screened out as irrelevant solves y = start in one step.
    return jnp.where(relevant, jnp.concatenate([x1 - x2, third[None]]), y - start)


#: Rounding floor of the coincidence residual $X_1 - X_2$, in units in the last place of
#: the centre distance (`_coincidence_weight`).
COINCIDENCE_ULPS = 4


def _coincidence_weight(pair: AbstractFlankPair, atol):
    """Weights (3,) of the residual's rows for a solve with absolute tolerance `atol`: the
    coincidence rows (mm) are scaled by $\\text{atol}/\\max(\\text{atol}, 4\\varepsilon a)$
    ($a$ the centre distance, $\\varepsilon$ the dtype's machine epsilon), the parallel row
    keeps 1.

    The points $X_1$, $X_2$ are computed from coordinates as large as the centre distance,
    so their difference cannot fall below a few units in the last place of $a$. In float64
    that floor (6e-14 mm per ulp at $a$ = 282 mm) lies below the presets' tolerances and the
    weights are exactly 1 (`reference`, 1e-13, is reached from $a$ = 113 mm, where the
    weight becomes 0.4 at 282 mm); in float32 the floored atol (`floored_tolerances`, 7.6e-6)
    is one ulp of a 64-128 mm coordinate, which converged solves of the seed pair missed by
    one to six ulps (the float32 seed pair of `tests/test_hard_cases.py`), and their
    contacts were dropped. Scaling a row changes neither the root nor its implicit derivative."""
    eps = float(jnp.finfo(jnp.result_type(pair.center_distance)).eps)
    floor = COINCIDENCE_ULPS * eps * jnp.abs(pair.center_distance)
    coincidence = atol / jnp.maximum(atol, floor)
    return jnp.stack([coincidence, coincidence, jnp.ones_like(coincidence)])


def _weighted_residual(y, args):
    """`_contact_residual` with its rows scaled (`_coincidence_weight`)."""
    weight, inner = args
    return weight * _contact_residual(y, inner)


class SliceContact(eqx.Module):
    """The first contact of one slice (arrays broadcast over any batch axes).

    Attributes:
        offset: gear offset $\\Delta$ at which the slice touches (rad); the slice's
            transmission error up to the lead correction.
        pinion_parameter, gear_parameter: $u_1$, $u_2$ of the contact (mm).
        kind: index of the touching candidate in `CANDIDATES` (0 flank, 1 gear-tip edge,
            2 pinion-tip edge); `contact_kind` turns it into a `ContactKind`.
        valid: some candidate converged on the active flanks.
        unconverged: number of relevant candidates whose Newton solve, and then the
            analysis's damped fallback (`tca.analysis._retry_failed`), failed with the
            last iterate on the active flanks (0 to 3).
    """

    offset: Float[Array, "..."]
    pinion_parameter: Float[Array, "..."]
    gear_parameter: Float[Array, "..."]
    kind: Array
    valid: Array
    unconverged: Array


def _parameter_tolerance(scale):
    """Tolerance on profile parameters of magnitude `scale` (mm): 1e-9 relative, or 64
    units in the last place where the dtype is coarser (float32: a Newton solution pinned
    at a tip differs from it by an ulp or two, which a 1e-9 tolerance would turn into a
    missing contact, and so into a jump of the TE at the tip)."""
    eps = float(jnp.finfo(jnp.result_type(scale)).eps)
    return max(1e-9, 64 * eps) * (1.0 + jnp.abs(scale))


def _within(u, limits, tol):
    lo, hi = limits
    return (u >= lo - tol) & (u <= hi + tol)


def make_problem(pair, depth, pair_index, z, pinion_angle) -> SliceProblem:
    """Slice problem of pair `pair_index` at axial `z` for pinion angle `pinion_angle`."""
    k = as_float(pair_index)
    rotation = pinion_angle - k * pair.angular_pitch(0) + pair.lead_rotation(0, z)
    return SliceProblem(pair=pair, depth=depth, pair_index=k, z=as_float(z), pinion_rotation=rotation)
