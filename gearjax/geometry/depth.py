"""Total material depth on a flank: modifications plus errors (mm, along the normal)."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import ArrayLike, Scalar
from ._base import AbstractFlankPair
from .errors import MeshErrors
from .modification import FlankModification


class FlankDepth(eqx.Module):
    """Sum of the flank modifications of both gears and the mesh errors.

    `None` entries contribute nothing and are not traced: the depth of a flank with nothing
    applied is a Python `0.0`, so a scene without modification compiles no relief term and
    the geometry skips the flank normal that a depth would need (`generic_slice_point`).

    Attributes:
        pinion: modification of the pinion drive flank, or None.
        gear: modification of the gear drive flank, or None.
        errors: mesh errors (applied to the pinion flank), or None.
    """

    pinion: FlankModification | None = None
    gear: FlankModification | None = None
    errors: MeshErrors | None = None

    def __call__(
        self, pair: AbstractFlankPair, gear: int, pair_index: ArrayLike, u: ArrayLike, z: ArrayLike
    ) -> Scalar | float:
        """Depth (mm) on the flank of `gear` of tooth pair `pair_index` at profile parameter
        `u` (mm) and axial position `z` (mm); `0.0` where nothing is applied to that flank."""
        if not self.applies_to(gear):
            return 0.0
        depth = jnp.zeros(jnp.broadcast_shapes(jnp.shape(u), jnp.shape(z)), dtype=jnp.result_type(float))
        modification = self.pinion if gear == 0 else self.gear
        if modification is not None:
            with jax.named_scope("term_modification"):
                start, tip = pair.relief_coordinates(gear)
                depth = depth + modification.depth(u, z, start, tip, pair.face_width)
        if gear == 0 and self.errors is not None:
            with jax.named_scope("term_errors"):
                depth = depth + self.errors.depth(pair_index, z, pair.face_width)
        return depth

    def transverse(self, pair: AbstractFlankPair, gear: int, pair_index: ArrayLike, u: ArrayLike,
                   z: ArrayLike) -> Scalar | float:
        """The depth in the transverse section (mm): the normal depth over $|n_t|$
        (`transverse_normal_fraction`); `0.0` where nothing is applied to the flank."""
        if not self.applies_to(gear):
            return 0.0
        return self(pair, gear, pair_index, u, z) / pair.transverse_normal_fraction(gear, u, z)

    def applies_to(self, gear: int) -> bool:
        """False when nothing is applied to `gear`'s flank (static): its depth is zero and
        need not be traced."""
        return (self.pinion if gear == 0 else self.gear) is not None or (gear == 0 and self.errors is not None)

    @property
    def is_zero(self) -> bool:
        """True when nothing is applied (static)."""
        return not (self.applies_to(0) or self.applies_to(1))
