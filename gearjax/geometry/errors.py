r"""Mesh errors (deviations from the nominal geometry), as equivalent flank depths.

All three enter the contact analysis exactly like a modification of the pinion flank of
tooth pair $k$ (material removed along the normal, mm), so every stage handles them without
special cases:

$$\delta_\text{err}(k, z) = k\,f_{pb} - [k = 0]\,f_{p} + f_{ma}\,\frac{z}{b}.$$

* `base_pitch_deviation` $f_{pb}$: pinion normal base pitch minus gear normal base pitch
  (mm). Pair $k$ (which comes into mesh $k$ pitches later) is shifted back by $k f_{pb}$;
  $f_{pb} < 0$ makes the next pair touch early, the classic cause of mesh-in impact.
* `pitch_deviation` $f_p$: the tooth of pair 0 stands proud by $f_p$ (mm, along the normal).
* `misalignment` $f_{ma}$: equivalent mesh misalignment in the plane of action (ISO 6336-1),
  a linear lead deviation of $f_{ma}$ (mm) over the face width, zero at mid-face.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from .._custom_types import ArrayLike, Scalar
from .._numerics import as_float
from .._validate import check_range


class MeshErrors(eqx.Module):
    """Pitch and alignment errors of a pair (mm, along the flank normal).

    Attributes:
        base_pitch_deviation: $f_{pb}$, pinion minus gear normal base pitch (mm).
        pitch_deviation: $f_p$, single pitch deviation of the tooth of pair 0 (mm).
        misalignment: $f_{ma}$, linear lead deviation across the face width (mm).
    """

    base_pitch_deviation: Scalar
    pitch_deviation: Scalar
    misalignment: Scalar

    def __init__(
        self,
        base_pitch_deviation: ArrayLike = 0.0,
        pitch_deviation: ArrayLike = 0.0,
        misalignment: ArrayLike = 0.0,
    ):
        check_range("base_pitch_deviation", base_pitch_deviation, -1.0, 1.0, unit="mm")
        check_range("pitch_deviation", pitch_deviation, -1.0, 1.0, unit="mm")
        check_range("misalignment", misalignment, -1.0, 1.0, unit="mm")
        self.base_pitch_deviation = as_float(base_pitch_deviation)
        self.pitch_deviation = as_float(pitch_deviation)
        self.misalignment = as_float(misalignment)

    def depth(self, pair_index: ArrayLike, axial: ArrayLike, face_width: ArrayLike) -> Scalar:
        """Equivalent depth (mm) on the pinion flank of pair `pair_index` at axial `axial`."""
        k = as_float(pair_index)
        return (
            k * self.base_pitch_deviation
            - jnp.where(k == 0, self.pitch_deviation, 0.0)
            + self.misalignment * as_float(axial) / face_width
        )
