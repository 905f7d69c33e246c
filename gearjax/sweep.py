"""Batched sweeps over operating points, in one compiled call.

The unloaded contact (TCA) does not depend on the load, so a load sweep runs it once and
maps the loaded stage over the torques with `vmap`; the compliance matrices, which do not
depend on the load either, are not batched by `vmap` and are built once as well.
"""

from __future__ import annotations

import equinox as eqx
import jax

from ._custom_types import ArrayLike
from ._numerics import as_float
from ._validate import check_range
from .ltca import LTCAResult, loaded_contact_analysis
from .scene import Scene, _prepare
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
