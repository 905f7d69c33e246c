r"""Flank modifications: parabolic tip/root relief and lead crowning (seed 001's y1...y6).

The depth $\delta$ (mm) is material removed along the flank normal,
$R_\text{mod} = r - \delta\,n$ with $n$ the outward normal. With $s$ the transverse roll
length of the flank (mm), $s_\text{start}$ the start of the active profile (where the
mating tip circle meets the line of action), $s_a$ the roll length at the tip circle, and
$w$ the axial position from mid-face (mm):

$$\delta = y_2\Big(\frac{s - (s_a - y_4)}{y_4}\Big)_+^2 + y_1\Big(\frac{s_\text{start} + y_3 - s}{y_3}\Big)_+^2
        + y_5\Big(\frac{|w| - y_6/2}{(b - y_6)/2}\Big)_+^2 .$$

Each term is $C^1$ at its start point and they add. These are the standard forms; seed
001's printed formulas are garbled (as printed its profile relief vanishes at the tip and
its crowning peaks at mid-face, the opposite of what its text and figures describe).
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._custom_types import Array, ArrayLike, Bool, Scalar
from .._numerics import as_float
from .._validate import check_range, is_concrete


class FlankModification(eqx.Module):
    """Six-parameter flank modification of seed 001 (all lengths mm).

    Attributes:
        root_relief: $y_1$, relief amount at the start of the active profile (mm).
        tip_relief: $y_2$, relief amount at the tip (mm).
        root_relief_length: $y_3$, roll length of the root relief zone (mm).
        tip_relief_length: $y_4$, roll length of the tip relief zone (mm).
        crowning: $y_5$, lead crowning amount at the face ends (mm).
        unmodified_length: $y_6$, unmodified central part of the face width (mm).
    """

    root_relief: Scalar
    tip_relief: Scalar
    root_relief_length: Scalar
    tip_relief_length: Scalar
    crowning: Scalar
    unmodified_length: Scalar

    def __init__(
        self,
        root_relief: ArrayLike = 0.0,
        tip_relief: ArrayLike = 0.0,
        root_relief_length: ArrayLike = 1.0,
        tip_relief_length: ArrayLike = 1.0,
        crowning: ArrayLike = 0.0,
        unmodified_length: ArrayLike = 0.0,
    ):
        check_range("root_relief (y1)", root_relief, 0.0, 1.0, unit="mm")
        check_range("tip_relief (y2)", tip_relief, 0.0, 1.0, unit="mm")
        check_range(
            "root_relief_length (y3)", root_relief_length, 0.0, None, low_inclusive=False, unit="mm"
        )
        check_range(
            "tip_relief_length (y4)", tip_relief_length, 0.0, None, low_inclusive=False, unit="mm"
        )
        check_range("crowning (y5)", crowning, 0.0, 1.0, unit="mm")
        check_range("unmodified_length (y6)", unmodified_length, 0.0, None, unit="mm")
        self.root_relief = as_float(root_relief)
        self.tip_relief = as_float(tip_relief)
        self.root_relief_length = as_float(root_relief_length)
        self.tip_relief_length = as_float(tip_relief_length)
        self.crowning = as_float(crowning)
        self.unmodified_length = as_float(unmodified_length)

    @classmethod
    def from_vector(cls, y: ArrayLike) -> "FlankModification":
        """From $(y_1, \\dots, y_6)$ in mm (the seed's order)."""
        y = as_float(y)
        return cls(*(y[..., i] for i in range(6)))

    @classmethod
    def from_micrometres(cls, y_um: ArrayLike) -> "FlankModification":
        """From $(y_1, \\dots, y_6)$ in micrometres, as printed in seed 001's Table 2."""
        return cls.from_vector(as_float(y_um) / 1000.0)

    def as_vector(self) -> jnp.ndarray:
        """$(y_1, \\dots, y_6)$ in mm, stacked on the last axis."""
        return jnp.stack(
            [
                self.root_relief,
                self.tip_relief,
                self.root_relief_length,
                self.tip_relief_length,
                self.crowning,
                self.unmodified_length,
            ],
            axis=-1,
        )

    def depth(
        self,
        roll_length: ArrayLike,
        axial: ArrayLike,
        start_of_active_profile: ArrayLike,
        tip_roll_length: ArrayLike,
        face_width: ArrayLike,
    ) -> Scalar:
        """Material removed normal to the flank (mm) at roll length `roll_length` (mm) and
        axial position `axial` from mid-face (mm)."""
        s = as_float(roll_length)
        w = as_float(axial)
        tip_start = tip_roll_length - self.tip_relief_length
        tip = self.tip_relief * jnp.square(
            jnp.maximum(s - tip_start, 0.0) / self.tip_relief_length
        )
        root_end = start_of_active_profile + self.root_relief_length
        root = self.root_relief * jnp.square(jnp.maximum(root_end - s, 0.0) / self.root_relief_length)
        half_free = 0.5 * self.unmodified_length
        half_crowned = 0.5 * (face_width - self.unmodified_length)
        crown = self.crowning * jnp.square(jnp.maximum(jnp.abs(w) - half_free, 0.0) / half_crowned)
        return tip + root + crown

    def in_range(self, flank_length: ArrayLike, face_width: ArrayLike) -> Bool[Array, "..."]:
        """Traced counterpart of the constructor's checks and `check_fits`: True where every
        parameter is finite, $y_1, y_2, y_5 \\in [0, 1]$ mm, $y_3, y_4 \\in (0, L]$ ($L$ =
        `flank_length`, the active flank's roll length, mm) and $y_6 \\in [0, b)$ ($b$ =
        `face_width`, mm). `simulate` uses it for values that were traced when the
        modification was built (inside jit, vmap or grad), where the constructor's checks
        cannot run."""
        y1, y2, y3, y4, y5, y6 = (self.root_relief, self.tip_relief, self.root_relief_length,
                                  self.tip_relief_length, self.crowning, self.unmodified_length)
        finite = jnp.all(jnp.isfinite(self.as_vector()), axis=-1)
        amounts = (y1 >= 0) & (y1 <= 1) & (y2 >= 0) & (y2 <= 1) & (y5 >= 0) & (y5 <= 1)
        lengths = (y3 > 0) & (y3 <= flank_length + 1e-12) & (y4 > 0) & (y4 <= flank_length + 1e-12)
        return finite & amounts & lengths & (y6 >= 0) & (y6 < face_width)

    def check_fits(self, flank_length: ArrayLike, face_width: ArrayLike, name: str = "modification") -> None:
        """Reject relief zones longer than the active flank and a central unmodified length
        beyond the face width (concrete values only)."""
        if not is_concrete(self, flank_length, face_width):
            return
        length = np.asarray(flank_length)
        for label, value in (
            ("root_relief_length (y3)", self.root_relief_length),
            ("tip_relief_length (y4)", self.tip_relief_length),
        ):
            if np.any(np.asarray(value) > length + 1e-12):
                raise ValueError(
                    f"{name}.{label} must be in (0, {np.min(length):.4f}] mm, the roll length of "
                    f"the active flank; got {np.max(np.asarray(value)):.4f} mm"
                )
        if np.any(np.asarray(self.unmodified_length) >= np.asarray(face_width)):
            raise ValueError(
                f"{name}.unmodified_length (y6) must be in [0, {np.min(np.asarray(face_width)):.4f}) "
                f"mm, less than the face width; got {np.max(np.asarray(self.unmodified_length)):.4f} mm"
            )
