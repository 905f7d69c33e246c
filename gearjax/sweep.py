"""Batched sweeps over operating points, in one compiled call.

The unloaded contact (TCA) does not depend on the load, so a load sweep runs it once and
maps the loaded stage over the torques with `vmap`; the compliance matrices, which do not
depend on the load either, are not batched by `vmap` and are built once as well.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._custom_types import ArrayLike
from ._numerics import as_float
from ._validate import check_range
from .impact import ImpactRegime
from .ltca import LTCAResult, loaded_contact_analysis
from .scene import Scene, _prepare, simulate
from .tca import TCAResult, tooth_contact_analysis


class LoadSweep(eqx.Module):
    """TCA of the scene and LTCA for every torque (leading axis of `ltca`), in engine units.

    Attributes:
        tca: the unloaded contact, computed once.
        ltca: the loaded contact per torque; `ltca.torque` holds the torques (N·mm).
    """

    tca: TCAResult
    ltca: LTCAResult

    @property
    def torques_Nm(self):
        """The swept pinion torques in N·m (`ltca.torque` / 1000)."""
        return self.ltca.torque / 1000.0


def _one_of(engine_name: str, engine_value, usual_name: str, usual_value, unit: str, usual_unit: str):
    """The argument given in exactly one of its two forms, as (name, value, unit, factor to
    engine units)."""
    if (engine_value is None) == (usual_value is None):
        got = "both" if engine_value is not None else "neither"
        raise ValueError(f"give exactly one of {engine_name} ({unit}) and {usual_name} ({usual_unit}); got {got}")
    if engine_value is not None:
        return engine_name, engine_value, unit, 1.0
    return usual_name, usual_value, usual_unit, 1000.0


def load_sweep(scene: Scene, torques: ArrayLike | None = None, *, torques_Nm: ArrayLike | None = None) -> LoadSweep:
    """LTCA of `scene` at every pinion torque, one compiled call.

    The scene's own torque is ignored; its other settings (compliance, accuracy, hub radius,
    extended contact) apply.

    Args:
        scene: the scene (any effects; only its TCA and LTCA settings are used).
        torques: pinion torques (N·mm), a non-empty 1-D array of finite values >= 0; or
        torques_Nm: the same in N·m ($T = 1000\\,T_\\text{Nm}$ N·mm). Give exactly one.

    Returns:
        `LoadSweep`: the scene's TCA once and the LTCA per torque (leading axis of `ltca`),
        in engine units (`ltca.torque` in N·mm).
    """
    name, values, unit, factor = _one_of("torques", torques, "torques_Nm", torques_Nm, "N·mm", "N·m")
    shape = np.shape(values)
    if len(shape) != 1 or shape[0] == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array of pinion torques ({unit}); got shape {shape}")
    check_range(name, values, 0.0, 1e12 / factor, unit=unit)
    torques = as_float(values) * factor
    scene = _prepare(scene)
    if scene.accuracy.dtype == "float32":
        with jax.enable_x64(False):
            return _load_sweep(scene, torques.astype("float32"))
    return _load_sweep(scene, torques)


@eqx.filter_jit
def _load_sweep(scene: Scene, torques) -> LoadSweep:
    pair = scene.pair.resolve()  # once, for the TCA and every load's LTCA
    tca = tooth_contact_analysis(pair, scene.depth, accuracy=scene.accuracy, pairs=scene.pairs, pitches=scene.pitches)

    def one(torque):
        return loaded_contact_analysis(pair, tca, torque, scene.contact_model)

    return LoadSweep(tca=tca, ltca=jax.vmap(one)(torques))


def regime_transition(
    scene: Scene,
    low: float | None = None,
    high: float | None = None,
    *,
    low_Nm: float | None = None,
    high_Nm: float | None = None,
    tolerance: float = 1e-3,
) -> tuple[float, float]:
    """Torque bracket of the switch from surface to edge mesh-in contact.

    Bisection on the impact regime between the torques `low` (surface) and `high` (edge),
    each step a `simulate` of the same compiled program, until the bracket is narrower than
    `tolerance` times `high`. The transition load is where the loaded approach of the
    pairs in mesh closes the modification's clearance exactly at the gear's tip edge
    (seed 001: TE = LTE at the start of engagement).

    Args:
        scene: a scene with `"impact"` in its effects; its own torque is ignored.
        low, high: pinion torques (N·mm), finite, $0 \\le$ low < high; or
        low_Nm, high_Nm: the same in N·m. Give each bound once, in either form.
        tolerance: relative width of the returned bracket, in (0, 1).

    Returns:
        `(below, above)` in N·mm (engine units, whichever form the bounds were given in):
        the largest torque found with surface contact and the smallest with edge contact.
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
    if "impact" not in scene.effects:
        raise ValueError("regime_transition needs a scene with effects including 'impact'")

    def regime(torque: float) -> int:
        s = eqx.tree_at(lambda sc: sc.operating.torque, scene, jnp.asarray(torque, jnp.result_type(float)))
        return int(simulate(s).impact.regime == ImpactRegime.edge)

    at_low, at_high = regime(low), regime(high)
    if at_low != 0 or at_high != 1:
        raise ValueError(
            f"regime_transition needs surface contact at {low_name} = {low_given:g} {low_unit} and edge "
            f"contact at {high_name} = {high_given:g} {high_unit}; got {at_low} and {at_high} (0 surface, 1 edge)"
        )
    while high - low > tolerance * high:
        mid = 0.5 * (low + high)
        if regime(mid) == 0:
            low = mid
        else:
            high = mid
    return low, high
