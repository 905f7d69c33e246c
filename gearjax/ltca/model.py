"""`ContactModel`: how the loaded contact is modelled and resolved, in one pytree.

The LTCA, the impact's first-contact search and the sweeps all need the same five things
beside the pair and the load: the compliance model, the material, the gear bodies' hub
radii, the accuracy settings and whether tip edges may carry load. `Scene.contact_model`
builds it from a scene.
"""

from __future__ import annotations

import equinox as eqx
import jax

from ..accuracy import Accuracy
from ..units import Material
from .compliance import AbstractCompliance


class ContactModel(eqx.Module):
    """The loaded-contact model of a scene.

    Attributes:
        compliance: the compliance model (`AbstractCompliance`).
        material: both gears' material.
        hub_radius: inner radius of each gear body (mm), shape (..., 2).
        accuracy: discretisation and solver settings (static).
        extended_contact: loaded teeth may also touch by their tip edges beyond the active
            profile (static; see `loaded_contact_analysis`).
    """

    compliance: AbstractCompliance
    material: Material
    hub_radius: jax.Array
    accuracy: Accuracy = eqx.field(static=True)
    extended_contact: bool = eqx.field(static=True, default=True)
