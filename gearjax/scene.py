"""Scenes: what one simulation needs, checked when it is built.

A `Scene` is a pytree holding the gear pair, optional flank modifications and mesh errors,
the operating point, the material, and static configuration: the effects to simulate and
the `Accuracy`. Its constructor checks every concrete input (one `ValueError` naming the
field and its allowed range); `gearjax.pipeline` runs the stages it calls for (`simulate`).
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._custom_types import ArrayLike
from ._numerics import as_float
from ._validate import check_range, is_concrete
from .accuracy import Accuracy
from .geometry._base import EFFECTS, AbstractGearPair
from .geometry.depth import FlankDepth
from .geometry.errors import MeshErrors
from .geometry.modification import FlankModification
from .ltca import AbstractCompliance, ContactModel, default_compliance
from .tca import pair_window
from .tca.grid import MAX_PAIRS
from .operating import OperatingPoint
from .units import Material

#: Most angular pitches a scene's cycle covers: each adds a tooth pair to the TCA's window,
#: which holds at most `tca.grid.MAX_PAIRS`.
MAX_PITCHES = MAX_PAIRS // 2


class Scene(eqx.Module):
    """Everything one simulation needs.

    Attributes:
        pair: the gear pair (any tooth family).
        modification: pinion flank modification, or None.
        gear_modification: gear flank modification, or None.
        errors: mesh errors, or None.
        operating: torque and speed.
        material: both gears' material.
        compliance: LTCA compliance model, any `AbstractCompliance` for the pair's family:
            by default the first of `COMPLIANCE_MODELS` that models it (`SliceCompliance()`
            for the involute families, `ToothSectionCompliance()` for double-circular-arc
            gears).
        hub_radius: inner radius of each gear body (mm), shape (2,); it enters the fillet
            foundation ($h_f = r_f/r_\\text{hub}$) and the gear inertias. Default half the
            root radius.
        inertia: $(J_1, J_2)$ of the whole rotating assemblies (t·mm²; 1 kg·m² = 1e3 t·mm²)
            for the impact's equivalent mass, or None for the gear bodies as solid discs
            $\\pi\\rho b(r_b^4 - r_h^4)/2$ (seed 001).
        effects: stages beyond TCA (static): subset of {"ltca", "impact"}; "ltca" is added
            whenever a torque is given, and "impact" needs it.
        accuracy: discretisation and solver settings (static).
        pairs: tooth-pair window of the TCA (static; derived from the geometry).
        pitches: angular pitches covered by the positions (static).
        extended_contact: loaded teeth may also touch by their tip edges beyond the active
            profile (static; see `loaded_contact_analysis`).
    """

    pair: AbstractGearPair
    modification: FlankModification | None
    gear_modification: FlankModification | None
    errors: MeshErrors | None
    operating: OperatingPoint
    material: Material
    compliance: AbstractCompliance
    hub_radius: jax.Array
    inertia: jax.Array | None
    effects: frozenset = eqx.field(static=True)
    accuracy: Accuracy = eqx.field(static=True)
    pairs: tuple[int, ...] = eqx.field(static=True)
    pitches: int = eqx.field(static=True)
    extended_contact: bool = eqx.field(static=True)

    def __init__(
        self,
        pair: AbstractGearPair,
        modification: FlankModification | None = None,
        *,
        gear_modification: FlankModification | None = None,
        errors: MeshErrors | None = None,
        operating: OperatingPoint | None = None,
        material: Material | None = None,
        compliance: AbstractCompliance | None = None,
        hub_radius: ArrayLike | None = None,
        inertia: ArrayLike | None = None,
        effects: tuple[str, ...] | frozenset = (),
        accuracy: Accuracy | str = "default",
        pairs: tuple[int, ...] | None = None,
        pitches: int = 1,
        extended_contact: bool = True,
    ):
        if not isinstance(pair, AbstractGearPair):
            raise ValueError(f"pair must be a gear pair (e.g. InvoluteGearPair); got {type(pair).__name__}")
        operating = OperatingPoint() if operating is None else operating
        effects = _effects(pair, operating, effects)
        if isinstance(accuracy, str):
            accuracy = Accuracy.preset(accuracy)
        if isinstance(pitches, bool) or not isinstance(pitches, int) or not 1 <= pitches <= MAX_PITCHES:
            raise ValueError(f"pitches must be an integer in [1, {MAX_PITCHES}]; got {pitches!r}")
        # The checks read the pair's derived geometry, resolved once (each quantity would
        # otherwise evaluate the chain of those it depends on); the scene keeps the pair as
        # given, so derivatives flow through its parameters.
        checked = pair.resolve() if is_concrete(pair) else pair
        for name, mod in (("modification", modification), ("gear_modification", gear_modification)):
            if mod is not None:
                check_modification_fits(checked, mod, 0 if name == "modification" else 1, name)
        if pairs is None:
            if not is_concrete(checked):
                raise ValueError("pairs must be given when the scene is built inside a transformation")
            try:
                pairs = pair_window(checked, pitches)
            except ValueError as err:
                raise ValueError(f"[pair] {err}") from None
        self.pair = pair
        self.modification = modification
        self.gear_modification = gear_modification
        self.errors = errors
        self.operating = operating
        self.material = Material() if material is None else material
        self.compliance = _compliance(pair, compliance, effects, accuracy)
        self.hub_radius = _hub_radius(checked, hub_radius)
        self.inertia = _inertia(inertia)
        self.effects = effects
        self.accuracy = accuracy
        self.pairs = tuple(int(k) for k in pairs)
        self.pitches = pitches
        self.extended_contact = bool(extended_contact)

    @property
    def contact_model(self) -> ContactModel:
        """The loaded-contact model: compliance, material, hub radii, accuracy and
        `extended_contact` (the LTCA's, the impact's and the sweeps' common input)."""
        return ContactModel(self.compliance, self.material, self.hub_radius, self.accuracy, self.extended_contact)

    @property
    def depth(self) -> FlankDepth:
        """Modifications and errors as one flank-depth function."""
        return FlankDepth(pinion=self.modification, gear=self.gear_modification, errors=self.errors)


def stack_scenes(scenes: list[Scene]) -> Scene:
    """Stack scenes of one structure into a batched scene (leading axis = design), ready
    for `jax.vmap(simulate)`. Their tooth-pair windows are unified; accuracy, effects and
    the presence of each optional part must agree."""
    if not scenes:
        raise ValueError("scenes must hold at least one Scene")
    window = sorted(set().union(*(s.pairs for s in scenes)))
    pairs = tuple(range(window[0], window[-1] + 1))
    scenes = [dataclasses.replace(s, pairs=pairs) for s in scenes]
    structures = {jax.tree_util.tree_structure(s) for s in scenes}
    if len(structures) != 1:
        raise ValueError(
            "scenes must share one structure to be stacked: same family, accuracy, effects, "
            "and the same optional parts (modification, errors, torque) present"
        )
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *scenes)


def _effects(pair: AbstractGearPair, operating: OperatingPoint, effects) -> frozenset:
    """The scene's stages beyond the TCA: "ltca" whenever there is a torque; each one
    checked against the torque and against the family's `supported_effects`."""
    effects = frozenset(effects)
    unknown = effects - set(EFFECTS)
    if unknown:
        raise ValueError(f"effects must be a subset of {EFFECTS}; got unknown {sorted(unknown)}")
    if operating.torque is not None:
        effects = effects | {"ltca"}
    for effect in ("ltca", "impact"):
        if effect in effects and operating.torque is None:
            raise ValueError(f"effects '{effect}' needs a torque: OperatingPoint(torque=...), in a scene file "
                             "[operating] torque_Nm")
    unsupported = effects - pair.supported_effects
    if unsupported:
        raise ValueError(
            f"effects {sorted(effects)} (a torque) are not available for "
            f"{pair.scene_file.description if pair.scene_file else type(pair).__name__}, "
            f"which supports {sorted(pair.supported_effects) or 'the rigid TCA only'}"
            + (f": {pair.effects_note}" if pair.effects_note else "")
        )
    return effects


def _compliance(pair: AbstractGearPair, compliance, effects: frozenset, accuracy: Accuracy) -> AbstractCompliance:
    """The compliance model (default: `default_compliance`), checked against the family
    and, for a loaded scene, against the model's `min_face_slices` and `needs_float64`
    (`check_loaded_accuracy`)."""
    if compliance is None:
        compliance = default_compliance(pair)()
    if not isinstance(compliance, AbstractCompliance):
        raise ValueError(
            "compliance must be a compliance model (an AbstractCompliance, e.g. IsoCompliance() or "
            f"SliceCompliance()); got {type(compliance).__name__}"
        )
    if "ltca" in effects and not isinstance(pair, compliance.families):
        raise ValueError(
            f"compliance {type(compliance).__name__} models the teeth of "
            f"{', '.join(f.__name__ for f in compliance.families)} only; got {type(pair).__name__}"
        )
    if "ltca" in effects:
        check_loaded_accuracy(compliance, accuracy)
    return compliance


def check_loaded_accuracy(compliance: AbstractCompliance, accuracy: Accuracy) -> None:
    """Raise `ValueError` where `accuracy` is coarser than the loaded contact of `compliance`
    needs: fewer face slices than `min_face_slices`, or float32 where it `needs_float64`."""
    if compliance.needs_float64 and accuracy.dtype != "float64":
        raise ValueError(
            f"accuracy.dtype must be 'float64' for the loaded contact of {type(compliance).__name__} "
            f"(its float32 results are far from float64's; decision 0009); got {accuracy.dtype!r}"
        )
    if accuracy.face_slices < compliance.min_face_slices:
        raise ValueError(
            f"accuracy.face_slices must be at least {compliance.min_face_slices} for the loaded contact of "
            f"{type(compliance).__name__} (its results do not converge on fewer); got {accuracy.face_slices} "
            "(use accuracy='default' or finer)"
        )


def check_one_zone(scene: Scene, what: str) -> None:
    """Raise `ValueError` where `what` (a batched impact study that keeps one impact per
    design, load and speed) gets a pair of several contact zones, whose zones strike each
    on their own (`impact_analysis`: a zone axis)."""
    zones = len(scene.pair.contact_zones())
    if zones > 1:
        raise ValueError(
            f"{what} needs a pair of one contact zone; {type(scene.pair).__name__} has {zones}, each with its own "
            "mesh-in impact: run simulate for each load and speed"
        )


def _hub_radius(pair: AbstractGearPair, hub_radius) -> jax.Array:
    """Hub radii (mm), shape (..., 2), default half the root radii; inside the root circles."""
    if hub_radius is None:
        return 0.5 * pair.root_radius
    hub_radius = as_float(hub_radius)
    if hub_radius.ndim == 0 or hub_radius.shape[-1] != 2:
        hub_radius = jnp.stack([hub_radius, hub_radius], -1)
    check_range("hub_radius", hub_radius, 0.0, None, low_inclusive=False, unit="mm")
    if is_concrete(hub_radius, pair.root_radius):
        root = np.asarray(pair.root_radius)
        if np.any(np.asarray(hub_radius) >= root):
            raise ValueError(
                f"hub_radius must be in (0, r_f) = (0, {np.min(root[..., 0]):.3f}) / (0, "
                f"{np.min(root[..., 1]):.3f}) mm, inside the root circles; got {np.asarray(hub_radius)}"
            )
    return hub_radius


def _inertia(inertia) -> jax.Array | None:
    """$(J_1, J_2)$ (t·mm²), positive, or None."""
    if inertia is None:
        return None
    inertia = as_float(inertia)
    if inertia.shape[-1:] != (2,):
        raise ValueError(f"inertia must be (J1, J2) in t·mm²; got shape {inertia.shape}")
    check_range("inertia", inertia, 0.0, None, low_inclusive=False, unit="t·mm²")
    return inertia


def check_modification_fits(pair, modification, gear, name, relief_coordinates=None):
    """`FlankModification.check_fits` on every contact zone of a concrete pair;
    `relief_coordinates(zone, gear)` computes the relief's span (default: eagerly)."""
    if not is_concrete(pair):
        return
    for zone in pair.contact_zones():
        start, tip = zone.relief_coordinates(gear) if relief_coordinates is None else relief_coordinates(zone, gear)
        if is_concrete(start, tip, zone.face_width):  # not when built inside a transformation
            modification.check_fits(np.asarray(tip) - np.asarray(start), zone.face_width, name)
