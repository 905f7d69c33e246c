r"""Involute helical gear pairs (spur when $\beta = 0$), ISO 21771 / Litvin & Fuentes (2004).

The flank is Litvin's involute helicoid: each transverse section is the involute of the
base circle (`involute_section.py`), turned by $z\tan\beta_b/r_b$ (right hand pinion, left
hand gear for `hand="right"`).
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp

from .._custom_types import ArrayLike, Scalar
from .._numerics import as_float
from .._validate import check_choice
from ._base import SceneFileSpec
from .involute_checks import SECTION_SCENE_KEYS
from .involute_section import AbstractInvolutePair


class InvoluteGearPair(AbstractInvolutePair):
    """External involute helical gear pair (spur for zero helix angle), ISO 21771.

    All lengths mm, angles stored in rad. Construct with degrees:

    >>> pair = InvoluteGearPair(teeth=(29, 71), normal_module=5.0, pressure_angle_deg=20.0,
    ...                         helix_angle_deg=27.5, face_width=42.0)

    Attributes (besides those of `AbstractInvolutePair`):
        hand: +1 if the pinion is right hand (gear left hand), -1 otherwise (static).
    """

    linear_lead: ClassVar[bool] = True
    scene_file: ClassVar[SceneFileSpec] = SceneFileSpec(
        "involute", "involute helical gear pair",
        {**SECTION_SCENE_KEYS, "helix_angle_deg": ("helix_angle_deg", "number", "deg", 1.0), "hand": ("hand", "text", "", 1.0)},
    )

    hand: int = eqx.field(static=True)

    def __init__(
        self,
        teeth: tuple[int, int],
        normal_module: ArrayLike,
        pressure_angle_deg: ArrayLike = 20.0,
        helix_angle_deg: ArrayLike = 0.0,
        face_width: ArrayLike = 20.0,
        profile_shift: ArrayLike = (0.0, 0.0),
        center_distance: ArrayLike | None = None,
        *,
        hand: str = "right",
        addendum_coefficient: ArrayLike = 1.0,
        dedendum_coefficient: ArrayLike = 1.25,
        root_radius_coefficient: ArrayLike = 0.38,
    ):
        check_choice("hand", hand, ("right", "left"))
        self._init_section(
            teeth,
            normal_module,
            pressure_angle_deg,
            helix_angle_deg,
            face_width,
            profile_shift,
            addendum_coefficient,
            dedendum_coefficient,
            root_radius_coefficient,
        )
        self.hand = 1 if hand == "right" else -1
        self._check_section(center_distance)

    def geometry_report(self) -> dict[str, ArrayLike]:
        return self._section_report()

    def transverse_normal_fraction(self, gear: int, u: ArrayLike, z: ArrayLike) -> Scalar:
        """$|n_t| = \\cos\\beta_b$ everywhere on an involute helicoid."""
        shape = jnp.broadcast_shapes(jnp.shape(u), jnp.shape(z))
        return jnp.broadcast_to(jnp.cos(self.base_helix_angle), shape)

    @property
    def contact_line_length(self) -> Scalar:
        """$b/\\cos\\beta_b$ (mm): a contact line across the whole face."""
        return self.face_width / jnp.cos(self.base_helix_angle)

    def lead_rotation(self, gear: int, z: ArrayLike) -> Scalar:
        """$\\psi_i(z) = \\pm z\\tan\\beta_b/r_{bi}$: right-hand pinion (left-hand gear) for
        `hand = +1`; both turn their sections in their own sense of rotation."""
        return self.hand * as_float(z) * jnp.tan(self.base_helix_angle) / self.base_radius[..., gear]
