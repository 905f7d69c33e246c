"""Load and impact sweeps of one scene: TCA once, the loaded stages mapped over torques
and speeds (`pipeline.over_loads`), one compiled call."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import ArrayLike
from ..impact import ImpactResult
from ..ltca import LTCAResult
from ..pipeline import SimulationResult, check_results, launched, over_loads
from ..scene import Scene, check_loaded_accuracy, check_one_zone
from ..tca import TCAResult
from ..units import rad_per_s_to_rpm
from ._axes import _speeds, _torques
from .devices import _devices, _per_device, _rows


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
    torques = _torques(torques, torques_Nm)
    check_loaded_accuracy(scene.compliance, scene.accuracy)
    with launched(scene, what="load_sweep", loads=torques.shape[0]) as prepared:
        return _load_sweep(prepared, torques.astype(jnp.result_type(float)))


@eqx.filter_jit
def _load_sweep(scene: Scene, torques) -> LoadSweep:
    return _load_sweep_body(scene, torques)


def _load_sweep_body(scene: Scene, torques) -> LoadSweep:
    tca, ltca, _ = over_loads(scene, torques)
    return LoadSweep(tca=tca, ltca=ltca)


class ImpactSweep(eqx.Module):
    """Mesh-in impact over a torque × speed grid, in engine units.

    Attributes:
        tca: the unloaded contact, computed once.
        ltca: the loaded contact per torque (leading axis); `ltca.torque` in N·mm.
        impact: the impact per torque and speed (leading axes `[torque, speed]`): force
            (N), velocity (mm/s), regime, strike point, stiffness fit, result code.
        speed: the swept pinion speeds (rad/s).
    """

    tca: TCAResult
    ltca: LTCAResult
    impact: ImpactResult
    speed: jax.Array

    @property
    def torques_Nm(self):
        """The swept pinion torques in N·m."""
        return self.ltca.torque / 1000.0

    @property
    def speeds_rpm(self):
        """The swept pinion speeds in rev/min."""
        return rad_per_s_to_rpm(self.speed)


def impact_sweep(
    scene: Scene,
    torques: ArrayLike | None = None,
    speeds: ArrayLike | None = None,
    *,
    torques_Nm: ArrayLike | None = None,
    speeds_rpm: ArrayLike | None = None,
    throw: bool = True,
    devices=None,
) -> ImpactSweep:
    """Mesh-in impact of `scene` at every torque and speed of a grid, one compiled call.

    TCA once; LTCA once per torque (all torques in one call) and the first-contact search
    once per torque (`vmap` over the torques);
    the speed only scales the kinematics, so the impact's closing formulas are `vmap`ped
    over the speeds without repeating the search or the stiffness fit (see the module
    docstring). The scene's own operating point is ignored; its other settings apply.

    Args:
        scene: a scene with "impact" in its effects.
        torques: pinion torques (N·mm), a non-empty 1-D array of finite values >= 0; or
        torques_Nm: the same in N·m. Give exactly one.
        speeds: pinion speeds (rad/s), a non-empty 1-D array of finite values >= 0; or
        speeds_rpm: the same in rev/min ($\\omega = 2\\pi n/60$). Give exactly one.
        throw: raise `SimulationError` if an LTCA or impact entry failed, naming how many
            (as `simulate`); with False inspect `ltca.result` and `impact.result`.
        devices: split the torque axis over these devices (`"all"` for `jax.devices()`):
            each runs the sweep on its share at the same time, and compiles the program
            for itself (`_per_device`). None (default) runs on the default device.

    Returns:
        `ImpactSweep`, `impact` fields with leading axes `[torque, speed]`.
    """
    torques = _torques(torques, torques_Nm)
    speeds = _speeds(speeds, speeds_rpm)
    if "impact" not in scene.effects:
        raise ValueError("impact_sweep needs a scene with effects including 'impact' (and so a torque)")
    check_one_zone(scene, "impact_sweep")
    devices = _devices(devices)
    count = torques.shape[0]
    per_device = -(-count // (1 if devices is None else len(devices)))
    with launched(scene, what="impact_sweep", loads=per_device) as scene:
        dtype = jnp.result_type(float)
        torques, speeds = torques.astype(dtype), speeds.astype(dtype)
        if devices is None:
            sweep = _impact_sweep(scene, torques, speeds)
        else:
            first, (ltca, impact) = _per_device(lambda t, rep: _impact_sweep(rep[0], t, rep[1]), torques, (scene, speeds), devices,
                                                batched=lambda sw: (sw.ltca, sw.impact))
            sweep = ImpactSweep(tca=first.tca, ltca=_rows(count, ltca), impact=_rows(count, impact), speed=speeds)
    if throw:
        check_results(SimulationResult(tca=sweep.tca, ltca=sweep.ltca, impact=sweep.impact))
    return sweep


@eqx.filter_jit
def _impact_sweep(scene: Scene, torques, speeds) -> ImpactSweep:
    return _impact_sweep_body(scene, torques, speeds)


def _impact_sweep_body(scene: Scene, torques, speeds) -> ImpactSweep:
    tca, ltca, impact = over_loads(scene, torques, speeds)
    return ImpactSweep(tca=tca, ltca=ltca, impact=impact, speed=speeds)
