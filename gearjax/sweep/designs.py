"""Design sweeps: a batch of designs over torques (and speeds), one compiled call."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import ArrayLike
from ..impact import ImpactResult
from ..ltca import LTCAResult
from ..pipeline import SimulationResult, check_results, launched, over_loads
from ..scene import Scene, check_loaded_accuracy, check_one_zone, stack_scenes
from ..units import rad_per_s_to_rpm
from ._axes import _speeds, _torques
from .devices import _devices, _per_device, _rows


class DesignSweep(eqx.Module):
    """Loaded contact (and impact) of a batch of designs over a torque list (and speeds),
    in engine units.

    Attributes:
        ltca: per design and torque (leading axes `[design, torque]`).
        impact: per design, torque and speed (`[design, torque, speed]`), or None when no
            speeds were given.
        torque: the swept pinion torques (N·mm).
        speed: the swept pinion speeds (rad/s), or None.
    """

    ltca: LTCAResult
    impact: ImpactResult | None
    torque: jax.Array
    speed: jax.Array | None

    @property
    def torques_Nm(self):
        """The swept pinion torques in N·m."""
        return self.torque / 1000.0

    @property
    def speeds_rpm(self):
        """The swept pinion speeds in rev/min (None without speeds)."""
        return None if self.speed is None else rad_per_s_to_rpm(self.speed)


def design_sweep(
    scenes: list[Scene] | Scene,
    torques: ArrayLike | None = None,
    speeds: ArrayLike | None = None,
    *,
    torques_Nm: ArrayLike | None = None,
    speeds_rpm: ArrayLike | None = None,
    throw: bool = True,
    devices=None,
) -> DesignSweep:
    """A batch of designs over a torque list (the Harris map: loaded TE peak-to-peak per
    design and load) and, with speeds, their mesh-in impact (the regime map: surface or
    edge contact and force per design and load), in one compiled call.

    The designs run one after another inside the program (`lax.map`; on a CPU a `vmap` of
    the solver loops would run every design to the slowest one's iteration count), each as
    `load_sweep` / `impact_sweep` do: TCA once, the loads `vmap`ped, the speeds closing
    formulas only.

    Args:
        scenes: scenes of one structure (e.g. the same pair with different modifications),
            as a list (stacked with `stack_scenes`) or already stacked; their own operating
            points are ignored.
        torques / torques_Nm: pinion torques (N·mm / N·m), a non-empty 1-D array of finite
            values >= 0; give exactly one.
        speeds / speeds_rpm: pinion speeds (rad/s / rpm), optional; with them the scenes
            need "impact" in their effects.
        throw: raise `SimulationError` if an entry failed (as `simulate`).
        devices: split the design axis over these devices (`"all"` for `jax.devices()`):
            each device runs its share of the designs one after another, all devices at
            the same time (`_per_device`). None (default) runs on the default device.

    Returns:
        `DesignSweep` with leading axes `[design, torque(, speed)]`.
    """
    torques = _torques(torques, torques_Nm)
    if speeds is None and speeds_rpm is None:
        speeds = None
    else:
        speeds = _speeds(speeds, speeds_rpm)
    if isinstance(scenes, Scene):
        stacked = scenes
    else:
        scenes = list(scenes)
        if not all(isinstance(sc, Scene) for sc in scenes):
            raise ValueError("scenes must be a list of Scene objects or a stacked Scene")
        stacked = stack_scenes(scenes)
    if speeds is not None and "impact" not in stacked.effects:
        raise ValueError("design_sweep with speeds needs scenes with effects including 'impact' (and so a torque)")
    if speeds is not None:
        check_one_zone(stacked, "design_sweep with speeds")
    devices = _devices(devices)
    check_loaded_accuracy(stacked.compliance, stacked.accuracy)
    with launched(stacked, what="design_sweep", loads=torques.shape[0]) as stacked:
        arrays, static = eqx.partition(stacked, eqx.is_array)
        count = jax.tree_util.tree_leaves(arrays)[0].shape[0]
        dtype = jnp.result_type(float)
        torques = torques.astype(dtype)
        speeds = None if speeds is None else speeds.astype(dtype)
        if devices is None:
            ltca, impact = _design_rows(arrays, static, torques, speeds)
        else:
            _, (ltca, impact) = _per_device(lambda a, rep: _design_rows(a, static, *rep), arrays, (torques, speeds),
                                            devices, batched=lambda out: out)
            ltca, impact = _rows(count, (ltca, impact))
    sweep = DesignSweep(ltca=ltca, impact=impact, torque=torques, speed=speeds)
    if throw:
        check_results(SimulationResult(tca=None, ltca=sweep.ltca, impact=sweep.impact))
    return sweep


def _design_rows_body(arrays, static, torques, speeds):
    def one(design_arrays):
        _, ltca, impact = over_loads(eqx.combine(design_arrays, static), torques, speeds)
        return ltca, impact

    return jax.lax.map(one, arrays)


@eqx.filter_jit
def _design_rows(arrays, static, torques, speeds):
    """(ltca, impact) of the designs (leading axis of `arrays`), one after another."""
    return _design_rows_body(arrays, static, torques, speeds)


@eqx.filter_jit
def _design_sweep(stacked: Scene, torques, speeds) -> DesignSweep:
    """The unsharded design sweep of a prepared, stacked scene, as one jitted function
    (benchmarks time its compilation and run)."""
    arrays, static = eqx.partition(stacked, eqx.is_array)
    ltca, impact = _design_rows_body(arrays, static, torques, speeds)
    return DesignSweep(ltca=ltca, impact=impact, torque=torques, speed=speeds)
