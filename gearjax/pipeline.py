r"""The stage chain TCA → LTCA → impact: the one place that runs it.

`simulate(scene)` composes only the stages the scene calls for, decided at trace time
(Python level), so the compiled program contains nothing else:

* always: geometry and unloaded TCA (`unloaded`);
* a torque (`OperatingPoint.torque` not None): loaded TCA (LTCA) after TCA (`loaded`);
* `"impact"` in the effects: the first-contact search and impact force (`impact`).

Everything that runs the chain comes through here: `simulate`, `simulate_designs`, the
sweeps (`over_loads`: TCA once, the loaded stages mapped over torques and speeds),
`regime_transition` and the optimiser's objective (`unloaded`, then `loaded` and `impact`
per load). They add only their own `vmap`/`lax.map` around these functions. Each stage
function applies the **traced-input guard** (`modification_checks` once per scene,
`operating_checks` per load and speed): where an input that the constructors could not
check (a traced modification or operating point) is out of range, the stage's outputs are
NaN and its `result` names the failure (`invalid_modification`,
`invalid_operating_point`), with no host callback, so programs stay cacheable. For
concrete inputs the checks always pass (the constructors ran them).

Each stage runs inside `jax.named_scope("stage_<name>")` and each flank term inside
`"term_<name>"`, so the lowered program can be inspected (`program_text`).

Host-side helpers: `launched` (the set-up every entry that calls a compiled program shares:
the memory guard, `prepare`'s precision check and casts, the precision the program is
traced in) and `check_results` / `check_codes` (raise `SimulationError` for failed stages
once results are concrete).
"""

from __future__ import annotations

import contextlib

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._solution import RESULTS, SimulationError, enum_message, enum_name
from ._validate import is_concrete
from .accuracy import Accuracy
from .impact import ImpactBranches, ImpactResult, impact_analysis, impact_branches
from .ltca import LTCAResult, loaded_contact_analysis
from .runtime.program_cache import cached_call
from .runtime.resources import check_memory
from .scene import Scene
from .tca import TCAResult, tooth_contact_analysis

#: the stages of `simulate`, in the order they run
STAGES = ("tca", "ltca", "impact")


class SimulationResult(eqx.Module):
    """Results of `simulate`: one entry per stage, None where the scene did not ask for it."""

    tca: TCAResult
    ltca: LTCAResult | None = None
    impact: ImpactResult | None = None


# ----------------------------------------------------------------------------- the stages
def unloaded(scene: Scene, pair, checks=()) -> TCAResult:
    """The TCA stage over the scene's cycle, guarded by `checks` (`modification_checks`, `operating_checks`)."""
    with jax.named_scope("stage_tca"):
        tca = tooth_contact_analysis(pair, scene.depth, accuracy=scene.accuracy, pairs=scene.pairs,
                                     pitches=scene.pitches)
    return guarded(tca, checks)


def loaded(scene: Scene, pair, tca: TCAResult, torque, checks=()) -> LTCAResult:
    """The LTCA stage at pinion torque `torque` (N·mm; a 1-D array: each, along a leading
    load axis), guarded by `checks`."""
    with jax.named_scope("stage_ltca"):
        ltca = loaded_contact_analysis(pair, tca, torque, scene.contact_model)
    return guarded(ltca, checks)


def impact(scene: Scene, pair, tca: TCAResult, ltca: LTCAResult, torque, speed, checks=()) -> ImpactResult:
    """The impact stage at pinion torque `torque` (N·mm) and speed `speed` (rad/s), guarded by
    `checks`."""
    with jax.named_scope("stage_impact"):
        result = impact_analysis(pair, scene.depth, tca, ltca, torque=torque, speed=speed, model=scene.contact_model,
                                 pairs=scene.pairs, inertia=scene.inertia)
    return guarded(result, checks)


def branches(scene: Scene, pair, tca: TCAResult, ltca: LTCAResult, torque, speed, checks=(),
             edge: bool = True) -> ImpactBranches:
    """The impact on both branches of the mesh-in regime switch and the switching function
    (`impact.branches`; the flank branch and the switch only with `edge=False`), as the
    impact stage, guarded by `checks`."""
    with jax.named_scope("stage_impact_branches"):
        both = impact_branches(pair, scene.depth, tca, ltca, torque=torque, speed=speed, model=scene.contact_model,
                               pairs=scene.pairs, inertia=scene.inertia, edge=edge)
    switch = jnp.where(passed(checks), both.switch, jnp.nan)
    return ImpactBranches(guarded(both.flank, checks), None if both.edge is None else guarded(both.edge, checks),
                          switch)


def run(scene: Scene) -> SimulationResult:
    """The stages the scene calls for at its own operating point (traceable; `simulate`
    compiles it). The pair's derived geometry is resolved once for every stage (each stage's
    own `resolve()` then returns it as it is); every stage is guarded by every check, the
    operating point's included."""
    pair = scene.pair.resolve()
    torque, speed = scene.operating.torque, scene.operating.speed
    checks = modification_checks(scene, pair) + operating_checks(torque, speed)
    tca = unloaded(scene, pair, checks)
    ltca = loaded(scene, pair, tca, torque, checks) if "ltca" in scene.effects else None
    hit = impact(scene, pair, tca, ltca, torque, speed, checks) if "impact" in scene.effects else None
    return SimulationResult(tca=tca, ltca=ltca, impact=hit)


def over_loads(scene: Scene, torques, speeds=None):
    """TCA once, the LTCA at every torque of `torques` (N·mm) and, with `speeds` (rad/s), the
    impact `vmap`ped over the speeds inside a map over torques: `(tca, ltca, impact)`,
    `ltca` with leading axis `[torque]`, `impact` `[torque, speed]` (None without speeds).

    What does not depend on the load (the TCA, the compliance matrices) or on the speed
    (the first-contact search and the stiffness fit) is computed once; the LTCA solves the
    loads in one call (on the CPU in sequence, each warm-started from the load below it:
    `loaded_contact_analysis` with a 1-D torque), and the speed axis costs only the
    impact's closing formulas. The scene's own operating point is ignored."""
    pair = scene.pair.resolve()
    checks = modification_checks(scene, pair)
    tca = unloaded(scene, pair, checks)
    loads = loaded(scene, pair, tca, torques)

    def at_torque(torque, ltca):
        ltca = guarded(ltca, checks + operating_checks(torque))
        if speeds is None:
            return ltca, None

        def at_speed(speed):
            return impact(scene, pair, tca, ltca, torque, speed, checks + operating_checks(torque, speed))

        return ltca, jax.vmap(at_speed)(speeds)

    ltca, hit = jax.vmap(at_torque)(torques, loads)
    return tca, ltca, hit


# ------------------------------------------------------------------ the traced-input guard
def modification_checks(scene: Scene, pair) -> tuple:
    """`((ok, invalid_modification), ...)`: whether the scene's modifications, which a
    constructor cannot check when traced, are in range (`FlankModification.in_range` on
    every contact zone of the resolved `pair`). Built once per scene; the stages of every
    load add `operating_checks`."""
    checks = []
    for gear, modification in ((0, scene.modification), (1, scene.gear_modification)):
        if modification is None:
            continue
        for zone in pair.contact_zones():
            start, tip = zone.relief_coordinates(gear)
            checks.append((modification.in_range(tip - start, zone.face_width), RESULTS.invalid_modification))
    return tuple(checks)


def operating_checks(*values) -> tuple:
    """`((ok, invalid_operating_point), ...)` for each given torque or speed (finite and
    >= 0; None is skipped)."""
    return tuple((jnp.isfinite(v) & (v >= 0), RESULTS.invalid_operating_point) for v in values if v is not None)


def passed(checks):
    """Whether every check of `checks` passes (a boolean array; True without checks)."""
    ok = jnp.asarray(True)
    for good, _ in checks:
        ok = ok & good
    return ok


def guarded(stage, checks):
    """`stage` (a result with a `result` code) with NaN outputs and the first failed check's
    code where any check fails; unchanged without checks. The gradient where every check
    passes is the stage's own."""
    if not checks:
        return stage
    ok = passed(checks)
    code = stage.result
    for good, failure in reversed(checks):  # the first failed check names the failure
        code = RESULTS.where(good, code, failure)
    nan = jax.tree_util.tree_map(lambda x: jnp.where(ok, x, jnp.nan) if eqx.is_inexact_array(x) else x, stage)
    return eqx.tree_at(lambda s: s.result, nan, code)


# ------------------------------------------------------------------------- host side
def simulate(scene: Scene, *, throw: bool = True) -> SimulationResult:
    """Run the stages the scene calls for; jit-compiled once per scene structure.

    A float32 scene (`Accuracy.dtype`) is traced with 64-bit types switched off, so every
    constant of the program follows the requested precision.

    Solver outcomes are named results (`RESULTS`) in each stage's `result` field, computed
    in the compiled program (no host callback, so the program stays cacheable).

    With the program cache on (`gearjax.runtime.program_cache`; the command line's default, opt-in in
    Python) a top-level call loads the traced program of a scene of the same structure
    from disk instead of tracing it again.

    Many designs of one pair: `simulate_designs` (the pair resolved once, only the outputs
    asked for computed). `jax.jit(jax.vmap(simulate))` over `stack_scenes` works too (a copy
    of the pair per design); return only what you read from it, e.g.
    `lambda s: jax.vmap(simulate)(s).tca.transmission_error`, and XLA drops the rest.

    Args:
        scene: the `Scene`.
        throw: check the results once they are concrete: a failed LTCA or impact stage
            raises `SimulationError` (a `RuntimeError` naming the stage, what failed and
            how to fix it). Unconverged TCA candidate solves are not an error: they are
            common for edge candidates of pairs entering or leaving the window and are
            reported in `result.tca.unconverged` and `result.tca.result`. With False (or
            when called inside `jit`/`vmap`/`grad`, where the results are traced) nothing
            is checked: inspect `result.<stage>.result`.

    Returns:
        `SimulationResult` with `tca` always and `ltca` / `impact` when requested.

    Raises:
        MemoryEstimateError: (a `ValueError`) before anything is compiled, when the
            program's estimated memory exceeds what the device has
            (`gearjax.runtime.resources`); it names the knobs and the face-slice count that fits.
    """
    with launched(scene) as prepared:
        result = cached_call(simulate_program, prepared, name="simulate")
    if throw:
        check_results(result)
    return result


#: `run` compiled (one program per scene structure); `simulate` calls it
simulate_program = eqx.filter_jit(run)


def program_text(scene: Scene) -> str:
    """The lowered (StableHLO) program of `simulate(scene)` with its debug locations, in
    which the named scopes of the stages and flank terms appear."""
    lowered = simulate_program.lower(prepare(scene)).lowered
    return lowered.compiler_ir().operation.get_asm(enable_debug_info=True)


@contextlib.contextmanager
def launched(scene: Scene, *, what: str = "simulate", loads: int = 1, batch: int = 1):
    """The set-up shared by every host entry that calls a compiled program of the chain
    (`simulate`, `simulate_designs`, the sweeps, `regime_transition`), before anything is
    traced: the memory guard for `loads` loads and `batch` designs computed at once
    (`check_memory`; `what` names the entry in its error), the precision check and casts
    (`prepare`), and the precision the program is traced in (`precision`). Yields the
    prepared scene::

        with launched(scene, what="load_sweep", loads=len(torques)) as prepared:
            sweep = _load_sweep(prepared, torques)
    """
    check_memory(scene, loads=loads, what=what, batch=batch)
    prepared = prepare(scene)
    with precision(prepared.accuracy):
        yield prepared


def prepare(scene: Scene) -> Scene:
    """Check the precision and cast every floating leaf to the accuracy's dtype."""
    if scene.accuracy.dtype == "float64":
        if not _x64_enabled():
            raise ValueError(
                "accuracy.dtype='float64' needs 64-bit JAX: call "
                "jax.config.update('jax_enable_x64', True) at start-up, or use "
                "accuracy.replace(dtype='float32')"
            )
        return scene
    return in_precision(scene, scene.accuracy)


def _x64_enabled() -> bool:
    return bool(jax.config.jax_enable_x64)


def in_precision(tree, accuracy: Accuracy):
    """`tree` with every floating array leaf cast to `accuracy.dtype` (unchanged in
    float64, the dtype gearjax builds its arrays in)."""
    if accuracy.dtype == "float64":
        return tree

    def cast(x):
        if eqx.is_array(x) and jnp.issubdtype(x.dtype, jnp.floating):
            return x.astype(jnp.float32)
        return x

    return jax.tree_util.tree_map(cast, tree)


def precision(accuracy: Accuracy):
    """A context in which programs of this accuracy are traced: 64-bit types off for
    float32 (so every constant follows the requested precision), nothing for float64."""
    return jax.enable_x64(False) if accuracy.dtype == "float32" else contextlib.nullcontext()


def check_results(result: SimulationResult) -> None:
    """Raise `SimulationError` for the first failed stage (the TCA only for out-of-range
    traced inputs: its unconverged candidates are a code, not an error); skipped when the
    results are traced (inside a transformation)."""
    check_codes({stage: getattr(result, stage).result for stage in STAGES if getattr(result, stage) is not None})


def check_codes(by_stage: dict) -> None:
    """`check_results` on the result codes alone, `{stage: codes}` for the stages run."""
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
        where = f" in {int(failed.sum())} of {failed.size} entries (designs, loads, speeds or contact zones)" if failed.ndim else ""
        text = (
            f"simulate: the {stage.upper()} stage failed{where}. {details} "
            f"Pass throw=False to get the results with their codes (result.{stage}.result)."
        )
        raise SimulationError(stage, codes, text)
