r"""The design space of a modification optimisation: seed 001's six parameters with bounds.

A design is the vector $y = (y_1, \dots, y_6)$ of `FlankModification` in engine units
(mm): root relief amount $y_1$, tip relief amount $y_2$, root relief length $y_3$, tip
relief length $y_4$ (roll lengths), crowning amount $y_5$ and unmodified central length
$y_6$. The optimisers search the unit cube: $y = y_\text{lo} + x\,(y_\text{hi} - y_\text{lo})$,
$x \in [0, 1]^6$, so one mutation scale or step size suits every parameter, and bounds are
enforced by clipping $x$ to the cube (the GA) or projecting onto it (gradient descent).

Default bounds are seed 001's: amounts in $[0.001, 0.015]\,m_n$, lengths in
$[0.1, 0.8]\,m_n$, $y_6 \in [0, 0.5\,b]$. Every bound can be changed; the paper's own
optimum ($y_4$ = 4.3 mm > 0.8 $m_n$ = 4.0 mm) lies outside its bounds.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._custom_types import Array, ArrayLike, Float
from ..geometry.modification import FlankModification

#: Parameter names in the order of the design vector (`FlankModification`'s fields).
PARAMETERS = (
    "root_relief",
    "tip_relief",
    "root_relief_length",
    "tip_relief_length",
    "crowning",
    "unmodified_length",
)

#: The scene file's key and its factor from mm for each parameter (amounts in µm).
SCENE_KEYS = (
    ("root_relief_um", 1e3),
    ("tip_relief_um", 1e3),
    ("root_relief_length", 1.0),
    ("tip_relief_length", 1.0),
    ("crowning_um", 1e3),
    ("unmodified_length", 1.0),
)

#: Seed 001's bounds as multiples of (m_n, m_n, m_n, m_n, m_n, b).
_MODULE_BOUNDS = ((0.001, 0.015), (0.001, 0.015), (0.1, 0.8), (0.1, 0.8), (0.001, 0.015), (0.0, 0.5))


class DesignSpace(eqx.Module):
    """Box bounds of the six modification parameters (mm), checked against the flank.

    Attributes:
        lower, upper: bounds of $(y_1, \\dots, y_6)$ (mm), shape (6,), lower < upper.
    """

    lower: Float[Array, 6]
    upper: Float[Array, 6]

    def __init__(self, lower: ArrayLike, upper: ArrayLike):
        lower = np.asarray(lower, dtype=float)
        upper = np.asarray(upper, dtype=float)
        for name, value in (("lower", lower), ("upper", upper)):
            if value.shape != (6,):
                raise ValueError(f"design space {name} must hold 6 values (y1..y6, mm); got shape {value.shape}")
        for i, parameter in enumerate(PARAMETERS):
            lo, hi = lower[i], upper[i]
            if not (np.isfinite(lo) and np.isfinite(hi)):
                raise ValueError(f"bounds of {parameter} (y{i + 1}) must be finite; got [{lo}, {hi}] mm")
            if not lo < hi:
                raise ValueError(f"bounds of {parameter} (y{i + 1}) must have lower < upper; got [{lo}, {hi}] mm")
            low_limit = 0.0
            if lo < low_limit or (i in (2, 3) and lo <= 0.0):
                allowed = "(0, ...)" if i in (2, 3) else "[0, ...)"
                raise ValueError(f"lower bound of {parameter} (y{i + 1}) must be in {allowed} mm; got {lo} mm")
        for i in (0, 1, 4):
            if upper[i] > 1.0:
                raise ValueError(f"upper bound of {PARAMETERS[i]} (y{i + 1}) must be <= 1 mm (a relief amount); got {upper[i]} mm")
        self.lower = jnp.asarray(lower)
        self.upper = jnp.asarray(upper)

    @classmethod
    def module_scaled(cls, normal_module: float, face_width: float, **overrides) -> DesignSpace:
        """Seed 001's bounds for a pair of normal module $m_n$ and face width $b$ (mm):
        amounts $[0.001, 0.015]\\,m_n$, lengths $[0.1, 0.8]\\,m_n$, $y_6 \\in [0, 0.5\\,b]$.

        `overrides` replace single bounds by parameter name, as (lower, upper) in mm, e.g.
        `tip_relief_length=(0.5, 4.5)`."""
        scale = (normal_module,) * 5 + (face_width,)
        lower = [lo * s for (lo, _), s in zip(_MODULE_BOUNDS, scale)]
        upper = [hi * s for (_, hi), s in zip(_MODULE_BOUNDS, scale)]
        for name, bound in overrides.items():
            if name not in PARAMETERS:
                raise ValueError(f"unknown design parameter {name!r}; known: {', '.join(PARAMETERS)}")
            if len(bound) != 2:
                raise ValueError(f"bound of {name} must be (lower, upper) in mm; got {bound!r}")
            i = PARAMETERS.index(name)
            lower[i], upper[i] = float(bound[0]), float(bound[1])
        return cls(lower, upper)

    @classmethod
    def for_scene(cls, scene, **overrides) -> DesignSpace:
        """Seed 001's bounds for the scene's pair, checked against its flank (`check_fits`)."""
        pair = scene.pair
        space = cls.module_scaled(float(np.min(pair.normal_module)), float(np.min(pair.face_width)), **overrides)
        space.check_fits(scene)
        return space

    @property
    def width(self) -> Float[Array, 6]:
        """Bound widths $y_\\text{hi} - y_\\text{lo}$ (mm)."""
        return self.upper - self.lower

    def to_design(self, unit: ArrayLike) -> Float[Array, "... 6"]:
        """Design vector (mm) from unit-cube coordinates $x \\in [0, 1]^6$."""
        return self.lower + jnp.asarray(unit) * self.width

    def to_unit(self, design: ArrayLike) -> Float[Array, "... 6"]:
        """Unit-cube coordinates of a design vector (mm)."""
        return (jnp.asarray(design) - self.lower) / self.width

    def check_fits(self, scene) -> None:
        """Reject upper bounds the pinion flank cannot hold: relief lengths beyond the active
        flank's roll length, an unmodified length reaching the face width (`ValueError`
        naming the bound and the largest allowed value)."""
        upper = np.asarray(self.upper)
        for zone in scene.pair.contact_zones():
            start, tip = zone.relief_coordinates(0)
            length = float(np.min(np.asarray(tip) - np.asarray(start)))
            width = float(np.min(np.asarray(zone.face_width)))
            for i in (2, 3):
                if upper[i] > length + 1e-12:
                    raise ValueError(
                        f"upper bound of {PARAMETERS[i]} (y{i + 1}) must be <= {length:.4f} mm, the roll "
                        f"length of the pinion's active flank; got {upper[i]:.4f} mm"
                    )
            if upper[5] >= width:
                raise ValueError(
                    f"upper bound of unmodified_length (y6) must be < {width:.4f} mm, the face width; "
                    f"got {upper[5]:.4f} mm"
                )

    def contains(self, design: ArrayLike, tol: float = 1e-12) -> bool:
        """True when every design (mm, shape (..., 6)) lies within the bounds."""
        d = np.asarray(design)
        return bool(np.all(d >= np.asarray(self.lower) - tol) and np.all(d <= np.asarray(self.upper) + tol))


def modification_from_design(design: ArrayLike) -> FlankModification:
    """The `FlankModification` of a design vector (mm), without constructor checks, so it
    can be built from traced values (the bounds already keep them valid)."""
    design = jnp.asarray(design)
    fields = lambda m: [getattr(m, name) for name in PARAMETERS]  # noqa: E731
    return eqx.tree_at(fields, FlankModification(), [design[..., i] for i in range(6)])


def design_dict(design: ArrayLike) -> dict[str, float]:
    """A design (mm) as the scene file's `[modification]` keys and units (µm amounts)."""
    d = np.asarray(design, dtype=float)
    return {key: float(d[i] * factor) for i, (key, factor) in enumerate(SCENE_KEYS)}
