r"""Both branches of the mesh-in regime switch and the switching function, differentiable.

On a modified pair the incoming tooth pair strikes either with its flanks or with the
gear's tip edge (`ImpactRegime`). The first-contact offset and its rate are continuous and
smooth across the switch, but the strike point stops at the edge on one side, so the
impact force has a kink there: a V where the lowest designs sit (`docs/landscape.md`).
Each side alone is smooth, and it continues smoothly across the switch:

* $F_\text{flank}$: the impact of the first flank contact, the gear's flank continued
  beyond its tip (`tca.branch`, side `"flank"`), also where the edge strikes first;
* $F_\text{edge}$: the impact of the first tip-edge contact, the flank candidate left out
  (side `"edge"`), also where the flanks strike first;
* the switching function $s = u_{\text{tip},2} - u_2^*$ (mm): the gear roll length between
  its tip and the flank branch's first contact point, positive where the flanks strike,
  negative where the edge does, zero at the switch (a smooth function: the root of the
  flank branch's first-contact search, $u_2^*$ from its slice root, both with implicit
  derivatives, `search.first_contact`).

The force is $F = F_\text{flank}$ where $s \ge 0$ and $F_\text{edge}$ where $s < 0$, and
both branches give it there with the search's exact derivatives. An optimiser can then
write the kink as smooth constrained programs: min $F_\text{flank}$ subject to $s \ge 0$,
and min $F_\text{edge}$ subject to $s \le 0$.

Each branch runs its own first-contact search (bracketed on the scene's cycle grid; a
branch's first contact can lie outside the grid's bracket, and the search moves the
bracket outwards to it) and its own local stiffness fit; the impact velocity, mass and
force follow as in `analysis`. Line-contact (involute) families only: a point-contact pair
has no flank point that runs onto a tip edge in this way.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from .._custom_types import Bool, Scalar
from ..ltca.analysis import LTCAResult
from ..ltca.model import ContactModel
from ..tca import TCAResult
from .analysis import ImpactResult, _impact_at
from .search import SearchContext, bracket, first_contact


class ImpactBranches(eqx.Module):
    """The mesh-in impact on both branches of the regime switch (see the module docstring).

    Attributes:
        flank: the impact of the flank branch (`ImpactResult`; `regime` surface).
        edge: the impact of the tip-edge branch (`ImpactResult`; `regime` edge), or None
            where it was not asked for (`impact_branches(..., edge=False)`).
        switch: $s = u_{\\text{tip},2} - u_2^*$ of the flank branch (mm of the gear's roll
            length): > 0 where the flanks strike first, < 0 where the tip edge does.
    """

    flank: ImpactResult
    edge: ImpactResult | None
    switch: Scalar

    @property
    def flank_strikes(self) -> Bool:
        """Whether the flanks strike first ($s \\ge 0$)."""
        return self.switch >= 0.0

    @property
    def force(self) -> Scalar:
        """The impact force of the branch that strikes (N): the scene's `ImpactResult.force`."""
        if self.edge is None:
            raise ValueError("the force of the branch that strikes needs both branches (impact_branches(..., edge=True))")
        return jnp.where(self.flank_strikes, self.flank.force, self.edge.force)


def impact_branches(
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
    edge: bool = True,
) -> ImpactBranches:
    """The impact on both branches of the regime switch and the switching function, with
    the arguments of `impact_analysis` (a pair of one contact zone, line contact); with
    `edge=False` the flank branch and the switch only (one first-contact search)."""
    if ltca.point_contact is not None or len(pair.contact_zones()) != 1:
        raise ValueError(f"impact_branches needs a line-contact pair of one contact zone (an involute family); "
                         f"got {type(pair).__name__}")
    pair = pair.resolve()
    found, column, lower, upper, gap_lower, gap_upper = bracket(tca, ltca)

    def side(branch: str) -> ImpactResult:
        ctx = SearchContext(pair, depth, jnp.asarray(torque, ltca.rotation.dtype), model, tuple(pairs), branch)
        search = first_contact(ctx, column, lower, upper, gap_lower, gap_upper, found)
        return _impact_at(ctx, column, search, speed, inertia, found)

    flank = side("flank")
    tip = pair.profile_limits(1)[1]
    return ImpactBranches(flank, side("edge") if edge else None, tip - flank.gear_parameter)
