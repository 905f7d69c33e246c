"""The load at which the mesh-in impact switches from surface to edge contact: one
compiled bisection per design."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import pipeline
from .._solution import RESULTS, SimulationError, enum_name
from .._validate import check_range
from ..impact import ImpactRegime
from ..pipeline import launched
from ..scene import Scene, check_one_zone, stack_scenes
from ._axes import _one_of


def regime_transition(
    scene: Scene | list[Scene],
    low: float | None = None,
    high: float | None = None,
    *,
    low_Nm: float | None = None,
    high_Nm: float | None = None,
    tolerance: float = 1e-3,
    throw: bool = True,
):
    """Torque bracket of the switch from surface to edge mesh-in contact, for one scene or
    a batch of designs in one compiled call.

    Bisection on the impact regime between the torques `low` (surface) and `high` (edge),
    until the bracket is narrower than `tolerance` times its upper end. The whole search is
    one program: TCA once per design (it does not depend on the load), then a
    `lax.while_loop` whose steps are one LTCA and one impact analysis at a torque (the
    first two steps check the ends, then the midpoints); a batch of designs runs the
    designs' searches one after another inside the program (`lax.map`, as `design_sweep`),
    each stopping at its own tolerance. The transition load is where the loaded approach of
    the pairs in mesh closes the modification's clearance exactly at the gear's tip edge
    (seed 001: TE = LTE at the start of engagement).

    Args:
        scene: a scene with `"impact"` in its effects (its own torque is ignored), or a
            list of such scenes of one structure (designs, stacked with `stack_scenes`).
        low, high: pinion torques (N·mm), finite, $0 \\le$ low < high; or
        low_Nm, high_Nm: the same in N·m. Give each bound once, in either form.
        tolerance: relative width of the returned bracket, in (0, 1).
        throw: raise `SimulationError` if an LTCA or impact solve of the search failed;
            with False such a search returns NaN.

    Returns:
        For one scene, `(below, above)` in N·mm (engine units, whichever form the bounds
        were given in): the largest torque found with surface contact and the smallest
        with edge contact; a `ValueError` if `low` is not surface or `high` not edge
        contact. For a list, `(below, above)` as arrays over the designs, NaN for a design
        whose regime does not switch between `low` and `high` (or whose search failed,
        with `throw=False`).
    """
    bounds = {}
    for key, engine, usual in (("low", low, low_Nm), ("high", high, high_Nm)):
        name, value, unit, factor = _one_of(key, engine, f"{key}_Nm", usual, "N·mm", "N·m")
        if np.ndim(value) != 0:
            raise ValueError(f"{name} must be a scalar torque ({unit}); got shape {np.shape(value)}")
        check_range(name, value, 0.0, 1e12 / factor, unit=unit)
        bounds[key] = (name, float(value), unit, float(value) * factor)
    (low_name, low_given, low_unit, low), (high_name, high_given, high_unit, high) = bounds["low"], bounds["high"]
    if not low < high:
        raise ValueError(f"{low_name} must be below {high_name}; got {low} and {high} N·mm")
    check_range("tolerance", tolerance, 0.0, 1.0, low_inclusive=False, high_inclusive=False)
    single = isinstance(scene, Scene)
    scenes = [scene] if single else list(scene)
    if not scenes or not all(isinstance(sc, Scene) for sc in scenes):
        raise ValueError("scene must be a Scene or a non-empty list of Scene objects")
    if any("impact" not in sc.effects for sc in scenes):
        raise ValueError("regime_transition needs a scene with effects including 'impact'")
    for sc in scenes:
        check_one_zone(sc, "regime_transition")
    # the designs run one after another (`lax.map`), each over one load at a time
    with launched(stack_scenes(scenes), what="regime_transition") as stacked:
        arrays, static = eqx.partition(stacked, eqx.is_array)
        dtype = jnp.result_type(float)
        search = _transition(arrays, static, jnp.asarray(low, dtype), jnp.asarray(high, dtype),
                             jnp.asarray(tolerance, dtype))
    below, above, edge_low, edge_high, ltca_code, impact_code = search
    below, above, edge_low, edge_high = (np.asarray(a) for a in (below, above, edge_low, edge_high))
    ltca_failed, impact_failed = (np.asarray(c != RESULTS.successful) for c in (ltca_code, impact_code))
    failed = ltca_failed | impact_failed
    if throw and failed.any():
        stage, codes, bad = ("ltca", ltca_code, ltca_failed) if ltca_failed.any() else ("impact", impact_code, impact_failed)
        names = sorted(set(np.asarray(enum_name(codes))[bad].tolist()))
        raise SimulationError(
            stage, codes,
            f"regime_transition: the {stage.upper()} stage failed in the search of {int(failed.sum())} of "
            f"{failed.size} designs ({', '.join(names)}). Pass throw=False to get NaN for those designs.",
        )
    if single:
        if edge_low[0] or not edge_high[0]:
            raise ValueError(
                f"regime_transition needs surface contact at {low_name} = {low_given:g} {low_unit} and edge "
                f"contact at {high_name} = {high_given:g} {high_unit}; got {int(edge_low[0])} and "
                f"{int(edge_high[0])} (0 surface, 1 edge)"
            )
        return float(below[0]), float(above[0])
    found = ~edge_low & edge_high & ~failed
    return np.where(found, below, np.nan), np.where(found, above, np.nan)


#: Most steps of one bisection (the two end checks included); 2^-62 of the first bracket.
_MAX_BISECTION_STEPS = 64


@eqx.filter_jit
def _transition(arrays, static, low, high, tolerance):
    """The bisection of `regime_transition` for each design (leading axis of `arrays`):
    below, above, regime at low and high is edge, and the first failed LTCA and impact
    result codes (successful when none failed)."""

    def one(design_arrays):
        scene = eqx.combine(design_arrays, static)
        pair = scene.pair.resolve()
        modified = pipeline.modification_checks(scene, pair)
        tca = pipeline.unloaded(scene, pair, modified)

        def running(c):
            step, lo, hi, edge_lo, edge_hi, ltca_code, impact_code = c
            sound = (ltca_code == RESULTS.successful) & (impact_code == RESULTS.successful)
            bracket = ~edge_lo & edge_hi & (hi - lo > tolerance * hi)
            return sound & ((step < 2) | bracket) & (step < _MAX_BISECTION_STEPS)

        def bisect(c):
            step, lo, hi, edge_lo, edge_hi, ltca_code, impact_code = c
            torque = jnp.where(step == 0, low, jnp.where(step == 1, high, 0.5 * (lo + hi)))
            speed = scene.operating.speed
            checks = modified + pipeline.operating_checks(torque, speed)
            ltca = pipeline.loaded(scene, pair, tca, torque, checks)
            impact = pipeline.impact(scene, pair, tca, ltca, torque, speed, checks)
            edge = impact.regime == ImpactRegime.edge
            middle = step >= 2
            lo = jnp.where(middle & ~edge, torque, lo)
            hi = jnp.where(middle & edge, torque, hi)
            edge_lo = jnp.where(step == 0, edge, edge_lo)
            edge_hi = jnp.where(step == 1, edge, edge_hi)
            return step + 1, lo, hi, edge_lo, edge_hi, ltca.result, impact.result

        ok = RESULTS.where(jnp.asarray(True), RESULTS.successful, RESULTS.successful)
        start = (jnp.asarray(0), low, high, jnp.asarray(False), jnp.asarray(True), ok, ok)
        _, lo, hi, edge_lo, edge_hi, ltca_code, impact_code = jax.lax.while_loop(running, bisect, start)
        return lo, hi, edge_lo, edge_hi, ltca_code, impact_code

    return jax.lax.map(one, arrays)
