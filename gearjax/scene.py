"""Scenes and the pipeline that simulates them.

A `Scene` is a pytree holding the gear pair, optional flank modifications and mesh errors,
the operating point, the material, and static configuration: the effects to simulate and
the `Accuracy`. `simulate(scene)` composes only the stages the scene calls for, decided at
trace time (Python level), so the compiled program contains nothing else:

* always: geometry and unloaded TCA;
* a torque (`OperatingPoint.torque` not None): loaded TCA (LTCA) after TCA;
* `"impact"` in the effects: the first-contact search and impact force.

Each stage runs inside `jax.named_scope("stage_<name>")` and each flank term inside
`"term_<name>"`, so the lowered program can be inspected (`program_text`, used by
`tests/test_scene.py`).
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
from .impact import ImpactResult, impact_analysis
from .ltca import AbstractCompliance, ContactModel, LTCAResult, SliceCompliance, loaded_contact_analysis
from .tca import TCAResult, pair_window, tooth_contact_analysis
from .tca.grid import MAX_PAIRS
from .operating import OperatingPoint
from .program_cache import cached_call
from .resources import check_memory
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
        compliance: LTCA compliance model, any `AbstractCompliance` (`SliceCompliance()`
            by default, or `IsoCompliance()`).
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
        for name, mod in (("modification", modification), ("gear_modification", gear_modification)):
            if mod is not None:
                _check_modification_fits(pair, mod, 0 if name == "modification" else 1, name)
        if pairs is None:
            if not is_concrete(pair):
                raise ValueError("pairs must be given when the scene is built inside a transformation")
            try:
                pairs = pair_window(pair, pitches)
            except ValueError as err:
                raise ValueError(f"[pair] {err}") from None
        self.pair = pair
        self.modification = modification
        self.gear_modification = gear_modification
        self.errors = errors
        self.operating = operating
        self.material = Material() if material is None else material
        self.compliance = _compliance(pair, compliance, effects)
        self.hub_radius = _hub_radius(pair, hub_radius)
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
            raise ValueError(f"effects '{effect}' needs a torque: give operating=OperatingPoint(torque=...)")
    unsupported = effects - pair.supported_effects
    if unsupported:
        raise ValueError(
            f"effects {sorted(effects)} (a torque) are not available for {type(pair).__name__}, "
            f"which supports {sorted(pair.supported_effects) or 'the rigid TCA only'}"
            + (f": {pair.effects_note}" if pair.effects_note else "")
        )
    return effects


def _compliance(pair: AbstractGearPair, compliance, effects: frozenset) -> AbstractCompliance:
    """The compliance model (default `SliceCompliance()`), checked against the family."""
    compliance = SliceCompliance() if compliance is None else compliance
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
    return compliance


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


def _check_modification_fits(pair, modification, gear, name, relief_coordinates=None):
    """`FlankModification.check_fits` on every contact zone of a concrete pair;
    `relief_coordinates(zone, gear)` computes the relief's span (default: eagerly)."""
    if not is_concrete(pair):
        return
    for zone in pair.contact_zones():
        start, tip = zone.relief_coordinates(gear) if relief_coordinates is None else relief_coordinates(zone, gear)
        if is_concrete(start, tip, zone.face_width):  # not when built inside a transformation
            modification.check_fits(np.asarray(tip) - np.asarray(start), zone.face_width, name)


class SimulationResult(eqx.Module):
    """Results of `simulate`: one entry per stage, None where the scene did not ask for it."""

    tca: TCAResult
    ltca: LTCAResult | None = None
    impact: ImpactResult | None = None


def _x64_enabled() -> bool:
    return bool(jax.config.jax_enable_x64)


def _prepare(scene: Scene) -> Scene:
    """Check the precision and cast every floating leaf to the accuracy's dtype."""
    if scene.accuracy.dtype == "float64":
        if not _x64_enabled():
            raise ValueError(
                "accuracy.dtype='float64' needs 64-bit JAX: call "
                "jax.config.update('jax_enable_x64', True) at start-up, or use "
                "accuracy.replace(dtype='float32')"
            )
        return scene
    return _in_precision(scene, scene.accuracy)


def _in_precision(tree, accuracy: Accuracy):
    """`tree` with every floating array leaf cast to `accuracy.dtype` (unchanged in
    float64, the dtype gearjax builds its arrays in)."""
    if accuracy.dtype == "float64":
        return tree

    def cast(x):
        if eqx.is_array(x) and jnp.issubdtype(x.dtype, jnp.floating):
            return x.astype(jnp.float32)
        return x

    return jax.tree_util.tree_map(cast, tree)


def simulate(scene: Scene, *, throw: bool = True) -> SimulationResult:
    """Run the stages the scene calls for; jit-compiled once per scene structure.

    A float32 scene (`Accuracy.dtype`) is traced with 64-bit types switched off, so every
    constant of the program follows the requested precision.

    Solver outcomes are named results (`RESULTS`) in each stage's `result` field, computed
    in the compiled program (no host callback, so the program stays cacheable).

    With the program cache on (`gearjax.program_cache`; the command line's default, opt-in in
    Python) a top-level call loads the traced program of a scene of the same structure
    from disk instead of tracing it again.

    Args:
        scene: the `Scene`.
        throw: check the results once they are concrete: a failed LTCA or impact stage
            raises `SimulationError` (a `RuntimeError` naming the stage, what failed and
            how to fix it). Unconverged TCA candidate solves are not an error: they are
            common for edge candidates of pairs entering or leaving the window and are
            reported in `result.tca.unconverged` and `result.tca.result`. With False (or when called inside `jit`/`vmap`/`grad`, where the results are
            traced) nothing is checked: inspect `result.<stage>.result`.

    Returns:
        `SimulationResult` with `tca` always and `ltca` / `impact` when requested.

    Raises:
        MemoryEstimateError: (a `ValueError`) before anything is compiled, when the
            program's estimated memory exceeds what the device has
            (`gearjax.resources`); it names the knobs and the face-slice count that fits.
    """
    check_memory(scene)
    scene = _prepare(scene)
    if scene.accuracy.dtype == "float32":
        with jax.enable_x64(False):
            result = cached_call(_simulate, scene, name="simulate")
    else:
        result = cached_call(_simulate, scene, name="simulate")
    if throw:
        _check_results(result)
    return result


#: the stages of `simulate`, in the order they run
STAGES = ("tca", "ltca", "impact")


def _check_results(result: SimulationResult) -> None:
    """Raise `SimulationError` for the first failed stage (the TCA only for out-of-range
    traced inputs: its unconverged candidates are a code, not an error); skipped when the
    results are traced (inside a transformation)."""
    _check_codes({stage: getattr(result, stage).result for stage in STAGES if getattr(result, stage) is not None})


def _check_codes(by_stage: dict) -> None:
    """`_check_results` on the result codes alone, `{stage: codes}` for the stages run."""
    from ._solution import RESULTS, SimulationError, enum_message, enum_name

    if not is_concrete(by_stage):
        return
    for stage in STAGES:
        if stage not in by_stage:
            continue
        codes = by_stage[stage]
        if stage == "tca":  # an unconverged TCA candidate is a code, not an error
            failed = np.asarray((codes == RESULTS.invalid_modification) | (codes == RESULTS.invalid_operating_point))
        else:
            failed = np.asarray(codes != RESULTS.successful)
        if not failed.any():
            continue
        names = sorted(set(np.atleast_1d(enum_name(codes))[np.atleast_1d(failed)].tolist()))
        details = " ".join(f"[{name}] {enum_message(getattr(RESULTS, name))}" for name in names)
        where = f" in {int(failed.sum())} of {failed.size} batch entries" if failed.ndim else ""
        text = (
            f"simulate: the {stage.upper()} stage failed{where}. {details} "
            f"Pass throw=False to get the results with their codes (result.{stage}.result)."
        )
        raise SimulationError(stage, codes, text)


@eqx.filter_jit
def _simulate(scene: Scene) -> SimulationResult:
    # The pair's derived geometry is resolved once for every stage (each stage's own
    # `resolve()` then returns it as it is).
    pair = scene.pair.resolve()
    with jax.named_scope("stage_tca"):
        tca = tooth_contact_analysis(
            pair, scene.depth, accuracy=scene.accuracy, pairs=scene.pairs, pitches=scene.pitches
        )
    ltca = None
    if "ltca" in scene.effects:
        with jax.named_scope("stage_ltca"):
            ltca = loaded_contact_analysis(pair, tca, scene.operating.torque, scene.contact_model)
    impact = None
    if "impact" in scene.effects:
        with jax.named_scope("stage_impact"):
            impact = impact_analysis(
                pair,
                scene.depth,
                tca,
                ltca,
                torque=scene.operating.torque,
                speed=scene.operating.speed,
                model=scene.contact_model,
                pairs=scene.pairs,
                inertia=scene.inertia,
            )
    return _guard_traced_inputs(scene, pair, SimulationResult(tca=tca, ltca=ltca, impact=impact))


def _guard_traced_inputs(scene: Scene, pair, result: SimulationResult) -> SimulationResult:
    """NaN outputs and a named result code where an input that the constructors could not
    check (traced values) is out of range: the modifications (`FlankModification.in_range`
    on every contact zone) and the operating point (torque, speed >= 0 and finite). For
    concrete inputs the checks always pass (the constructors ran them), and the program
    keeps no host callback, so it stays cacheable."""
    from ._solution import RESULTS

    codes = []
    for gear, modification in ((0, scene.modification), (1, scene.gear_modification)):
        if modification is None:
            continue
        for zone in pair.contact_zones():
            start, tip = zone.relief_coordinates(gear)
            codes.append((modification.in_range(tip - start, zone.face_width), RESULTS.invalid_modification))
    for value in (scene.operating.torque, scene.operating.speed):
        if value is not None:
            codes.append((jnp.isfinite(value) & (value >= 0), RESULTS.invalid_operating_point))
    if not codes:
        return result
    ok = jnp.asarray(True)
    for good, _ in codes:
        ok = ok & good
    stages = {}
    for name in ("tca", "ltca", "impact"):
        stage = getattr(result, name)
        if stage is None:
            stages[name] = None
            continue
        code = stage.result
        for good, failure in reversed(codes):  # the first failed check names the failure
            code = RESULTS.where(good, code, failure)
        nan = jax.tree_util.tree_map(
            lambda x: jnp.where(ok, x, jnp.nan) if eqx.is_inexact_array(x) else x, stage)
        stages[name] = eqx.tree_at(lambda s: s.result, nan, code)
    return SimulationResult(**stages)


def program_text(scene: Scene) -> str:
    """The lowered (StableHLO) program of `simulate(scene)` with its debug locations, in
    which the named scopes of the stages and flank terms appear."""
    lowered = _simulate.lower(_prepare(scene)).lowered
    return lowered.compiler_ir().operation.get_asm(enable_debug_info=True)
