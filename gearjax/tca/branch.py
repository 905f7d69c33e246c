r"""One tooth pair's slice contacts held to one branch of the mesh-in regime switch.

At mesh-in the incoming pair first touches either with its flanks or with the gear's tip
edge on the pinion's flank. Along the curve of coincident points of a slice the offset
$\Delta$ has its stationary point (the flank candidate) inside the gear's active flank or
beyond its tip; in the second case the tip edge, the end of that curve, is the slice's
first contact (`_slice.edge_is_first`). The two candidates meet, with the same offset and
the same rate of it, where the flank point reaches the tip: the slice value is continuous
and smooth, but the contact point stops at the edge, so what depends on it (normal,
velocity, local stiffness, impact force) kinks there.

A `Branch` makes each side a smooth function on both sides of that switch, for pair $k$
only (the other pairs' contacts are unchanged):

* `"flank"`: the flank candidate counts wherever its solve converged on the flanks'
  parameter domain (`AbstractFlankPair.parameter_domain`: the gear flank continued beyond
  its tip, the pinion's below its start of active profile, the modifications' formulas
  continued with it); the gear's tip edge is left out. Where the flank point lies inside
  the active flanks this is the pair's ordinary contact.
* `"edge"`: the flank candidate is left out; the gear's tip edge counts wherever it meets
  the pinion's flank continued below its start of active profile. Where the gear's tip
  edge strikes first this is the pair's ordinary contact.

The gear roll-length margin $s = u_{\text{tip},2} - u_2^*$ of the flank branch's contact
is the switching function: positive where the flanks strike, negative where the edge does,
zero at the switch (`gearjax.impact.branches`).
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from .._custom_types import Array, Int
from ._slice_problem import _parameter_tolerance, _within

#: The branches of the mesh-in regime switch (see the module docstring).
BRANCHES = ("flank", "edge")


class Branch(eqx.Module):
    """Pair `pair_index` (the window's value $k$) held to branch `side` (`BRANCHES`)."""

    pair_index: Int[Array, ""]
    side: str = eqx.field(static=True)

    def __check_init__(self):
        if self.side not in BRANCHES:
            raise ValueError(f"Branch.side must be one of {BRANCHES}; got {self.side!r}")

    def rule(self, k) -> tuple[Array, Array]:
        """For the slices of pair `k`: which of the three candidates (flank, gear's tip
        edge, pinion's tip edge) may count (3,), and which count wherever their contact
        lies on the flanks continued over their parameter domain (3,;
        `on_extended_flanks`): the branch's own candidate, whose contact crosses the end
        of an active flank where the other branch strikes first."""
        mine = jnp.asarray(k).astype(jnp.result_type(self.pair_index)) == self.pair_index  # k: int or float
        own = jnp.array([True, False, False]) if self.side == "flank" else jnp.array([False, True, False])
        allowed = own | jnp.array([False, False, True])
        return allowed | ~mine, own & mine


def on_extended_flanks(pair, values):
    """Candidates (..., 3) whose contact $(u_1, u_2)$ lies on the flanks continued over
    their parameter domain at the start of engagement: the pinion's from its domain's
    lower end to its tip (the gear's tip edge meets the pinion below its start of active
    profile where the flanks strike first), the gear's from its start of active profile
    to its domain's upper end (the flank point beyond the tip where the edge strikes
    first)."""
    (lo1, hi1), (lo2, hi2) = pair.profile_limits(0), pair.profile_limits(1)
    dom1, dom2 = pair.parameter_domain(0), pair.parameter_domain(1)
    tol = _parameter_tolerance(hi1)
    return _within(values[..., 0], (dom1[0], hi1), tol) & _within(values[..., 1], (lo2, dom2[1]), tol)

