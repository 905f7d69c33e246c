"""The discretisation of a TCA: pinion positions, face slices and the tooth-pair window, and
`vmap` over their grid."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import jax
import numpy as np
import jax.numpy as jnp

from .._custom_types import Array, Float
from .._numerics import as_float
from ..accuracy import Accuracy
from ..geometry._base import AbstractGearPair


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


#: Most tooth pairs a TCA follows at once (`pair_window`, margins included): every pair is a
#: column of every contact array and of the compiled program.
MAX_PAIRS = 32


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
    lo, hi = (phi_lo + leads.min() - angle_hi) / p, (phi_hi + leads.max() - angle_lo) / p
    if not (math.isfinite(lo) and math.isfinite(hi) and hi - lo < MAX_PAIRS - 2 * margin):
        raise ValueError(
            f"face_width: over a cycle of {pitches} pitch(es) the contact spans {hi - lo:.4g} tooth pairs "
            f"(face width {b:.6g} mm and its lead); at most {MAX_PAIRS - 2 * margin} are analysed: reduce "
            f"face_width or the helix angle")
    return tuple(range(math.ceil(lo) - margin, math.floor(hi) + margin + 1))


def nested_vmap(f: Callable, in_axes: Sequence[Sequence[int | None]], *args):
    """`jax.vmap(...jax.vmap(f, in_axes[-1])..., in_axes[0])(*args)`, traced as one `vmap`.

    The TCA maps its slice solves over positions × tooth pairs × face slices. As nested
    `vmap`s every operation is batched once per level while tracing (each `jax.numpy`
    function is a small `jit`, whose program each `vmap` level batches anew); one `vmap`
    over the flattened grid does the same operations on each element (values equal up to
    XLA's choice of fusion), traced in less time and to fewer equations
    (`benchmarks/trace_compile.py`; docs/performance.md).

    `in_axes[level][i]` is 0 where argument `i` is mapped at that level (outermost first)
    and None where it is not; an argument's leading axes are its mapped levels in order (as
    for nested `vmap`s with axis 0). Arguments mapped at some levels only are broadcast over
    the others, so a computation that depends on them alone runs once per grid point instead
    of once per value; arguments mapped at no level stay unbatched. Arguments may be pytrees
    (every leaf mapped alike). Outputs have the grid's axes (outermost first) in front."""
    levels = len(in_axes)
    mapped = [[level for level in range(levels) if in_axes[level][i] is not None] for i in range(len(args))]
    if any(all(axis is None for axis in level) for level in in_axes):
        raise ValueError(f"nested_vmap: every level must map an argument; got in_axes {in_axes}")
    sizes = [0] * levels
    for arg, where in zip(args, mapped):
        leaf = jax.tree_util.tree_leaves(arg)[0] if where else None
        for position, level in enumerate(where):
            sizes[level] = jnp.shape(leaf)[position]

    def flatten(x, where):
        x = jnp.asarray(x)
        trailing = x.shape[len(where):]
        lead = [x.shape[where.index(level)] if level in where else 1 for level in range(levels)]
        return jnp.broadcast_to(x.reshape(*lead, *trailing), (*sizes, *trailing)).reshape(-1, *trailing)

    flat = [jax.tree_util.tree_map(lambda x, w=where: flatten(x, w), arg) if where else arg
            for arg, where in zip(args, mapped)]
    out = jax.vmap(f, [0 if where else None for where in mapped])(*flat)
    return jax.tree_util.tree_map(lambda x: x.reshape(*sizes, *x.shape[1:]), out)
