"""Batched sweeps over operating points, in one compiled call.

The unloaded contact (TCA) does not depend on the load, so a load sweep runs it once and
maps the loaded stage over the torques with `vmap`; the compliance matrices, which do not
depend on the load either, are not batched by `vmap` and are built once as well.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ._custom_types import ArrayLike
from ._numerics import as_float
from ._validate import check_range
from .ltca import LTCAResult, loaded_contact_analysis
from .scene import Scene, _prepare, simulate
from .tca import TCAResult, tooth_contact_analysis


class LoadSweep(eqx.Module):
    """TCA of the scene and LTCA for every torque (leading axis of `ltca`)."""

    tca: TCAResult
    ltca: LTCAResult


def load_sweep(scene: Scene, torques: ArrayLike) -> LoadSweep:
    """LTCA of `scene` at every pinion torque in `torques` (N·mm, 1-D), one compiled call.

    The scene's own torque is ignored; its other settings (compliance, accuracy, hub radius,
    extended contact) apply.
    """
    check_range("torques", torques, 0.0, 1e12, unit="N·mm")
    scene = _prepare(scene)
    torques = as_float(torques)
    if torques.ndim != 1:
        raise ValueError(f"torques must be a 1-D array of pinion torques (N·mm); got shape {torques.shape}")
    if scene.accuracy.dtype == "float32":
        with jax.enable_x64(False):
            return _load_sweep(scene, torques.astype("float32"))
    return _load_sweep(scene, torques)


@eqx.filter_jit
def _load_sweep(scene: Scene, torques) -> LoadSweep:
    tca = tooth_contact_analysis(scene.pair, scene.depth, accuracy=scene.accuracy, pairs=scene.pairs, pitches=scene.pitches)

    def one(torque):
        return loaded_contact_analysis(
            scene.pair,
            tca,
            torque,
            compliance=scene.compliance,
            material=scene.material,
            hub_radius=scene.hub_radius,
            accuracy=scene.accuracy,
            extended_contact=scene.extended_contact,
        )

    return LoadSweep(tca=tca, ltca=jax.vmap(one)(torques))


def regime_transition(scene: Scene, low: float, high: float, *, tolerance: float = 1e-3) -> tuple[float, float]:
    """Torque bracket (N·mm) of the switch from surface to edge mesh-in contact.

    Bisection on the impact regime between `low` (surface) and `high` (edge), each step a
    `simulate` of the same compiled program, until the bracket is narrower than
    `tolerance` times `high`. The transition load is where the loaded approach of the
    pairs in mesh closes the modification's clearance exactly at the gear's tip edge
    (seed 001: TE = LTE at the start of engagement).

    Returns:
        `(below, above)`: the largest torque found with surface contact and the smallest
        with edge contact.
    """
    if "impact" not in scene.effects:
        raise ValueError("regime_transition needs a scene with effects including 'impact'")

    def regime(torque: float) -> int:
        s = eqx.tree_at(lambda sc: sc.operating.torque, scene, jnp.asarray(torque, jnp.result_type(float)))
        return int(simulate(s).impact.regime)

    if regime(low) != 0 or regime(high) != 1:
        raise ValueError(
            f"regime_transition needs surface contact at low = {low} and edge contact at "
            f"high = {high} N·mm; got {regime(low)} and {regime(high)} (0 surface, 1 edge)"
        )
    while high - low > tolerance * high:
        mid = 0.5 * (low + high)
        if regime(mid) == 0:
            low = mid
        else:
            high = mid
    return low, high
