"""Batched sweeps over operating points, in one compiled call.

The unloaded contact (TCA) does not depend on the load, so a load sweep runs it once and
maps the loaded stage over the torques with `vmap`; the compliance matrices, which do not
depend on the load either, are not batched by `vmap` and are built once as well.

The speed enters the impact only through the velocities (`gearjax.impact`): the
first-contact search, the contact found and its local stiffness fit do not depend on it.
An impact sweep `vmap`s the impact stage over the speeds inside the map over loads; what
does not depend on the speed is not batched by `vmap`, so it is computed once per load
and the speed axis costs only the closing formulas
($v_n = \\omega_1 v_n^{(1)}$, $F_s = K_s^{1/(n+1)}((n+1) m v_n^2/2)^{n/(n+1)}$).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._custom_types import ArrayLike
from ._numerics import as_float
from ._solution import RESULTS, SimulationError, enum_name
from ._validate import check_range
from . import pipeline
from .impact import ImpactRegime, ImpactResult
from .ltca import LTCAResult
from .operating import _MAX_SPEED
from .pipeline import SimulationResult, check_results, over_loads, precision, prepare
from .resources import check_memory
from .scene import Scene, stack_scenes
from .tca import TCAResult
from .units import rad_per_s_to_rpm, rpm_to_rad_per_s


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


def _one_of(
    engine_name: str, engine_value, usual_name: str, usual_value, unit: str, usual_unit: str, factor: float = 1000.0
):
    """The argument given in exactly one of its two forms, as (name, value, unit, factor to
    engine units); `factor` converts the usual unit (default N·m to N·mm)."""
    if (engine_value is None) == (usual_value is None):
        got = "both" if engine_value is not None else "neither"
        raise ValueError(f"give exactly one of {engine_name} ({unit}) and {usual_name} ({usual_unit}); got {got}")
    if engine_value is not None:
        return engine_name, engine_value, unit, 1.0
    return usual_name, usual_value, usual_unit, factor


def _axis(engine_name, engine_value, usual_name, usual_value, unit, usual_unit, *, factor, largest, what):
    """A checked sweep axis in engine units: a non-empty 1-D array of finite values in
    [0, largest] (engine units), given in exactly one of its two forms."""
    name, values, given_unit, to_engine = _one_of(
        engine_name, engine_value, usual_name, usual_value, unit, usual_unit, factor
    )
    shape = np.shape(values)
    if len(shape) != 1 or shape[0] == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array of {what} ({given_unit}); got shape {shape}")
    check_range(name, values, 0.0, largest / to_engine, unit=given_unit)
    return as_float(values) * to_engine


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
    check_memory(scene, loads=torques.shape[0], what="load_sweep")
    scene = prepare(scene)
    with precision(scene.accuracy):
        return _load_sweep(scene, torques.astype(jnp.result_type(float)))


def _torques(torques, torques_Nm):
    return _axis("torques", torques, "torques_Nm", torques_Nm, "N·mm", "N·m",
                 factor=1000.0, largest=1e12, what="pinion torques")


def _speeds(speeds, speeds_rpm):
    return _axis("speeds", speeds, "speeds_rpm", speeds_rpm, "rad/s", "rpm",
                 factor=float(rpm_to_rad_per_s(1.0)), largest=_MAX_SPEED, what="pinion speeds")


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

    TCA once; LTCA and the first-contact search once per torque (`vmap` over the torques);
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
    devices = _devices(devices)
    check_memory(scene, loads=-(-torques.shape[0] // (1 if devices is None else len(devices))), what="impact_sweep")
    scene = prepare(scene)
    count = torques.shape[0]
    with precision(scene.accuracy):
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
    devices = _devices(devices)
    check_memory(stacked, loads=torques.shape[0], what="design_sweep")
    stacked = prepare(stacked)
    arrays, static = eqx.partition(stacked, eqx.is_array)
    count = jax.tree_util.tree_leaves(arrays)[0].shape[0]
    with precision(stacked.accuracy):
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


def shard_batch(values, devices):
    """`values` with its leading (batch) axis split over `devices`: a one-axis `Mesh`
    ("batch") and `NamedSharding(mesh, P("batch"))`. The leading axis is padded to a
    multiple of the device count by repeating its last entry; the sweeps drop the padded
    rows from their results.

    On several hosts, start one process per host with `jax.distributed.initialize()` and
    pass `jax.devices()` (all hosts' devices): the same code then shards across hosts."""
    from jax.sharding import NamedSharding, PartitionSpec

    padded = _pad(jnp.asarray(values), -(-values.shape[0] // len(devices)) * len(devices))
    return jax.device_put(padded, NamedSharding(_mesh(devices), PartitionSpec("batch")))


def _mesh(devices):
    """The one-axis ("batch") mesh over `devices`."""
    from jax.sharding import Mesh

    return Mesh(np.asarray(devices), ("batch",))


def _per_device(call, batch, replicated, devices, batched):
    """`call(block, replicated)` on every device of this process, with the device's block
    of `batch`'s leading axis as `shard_batch` lays it out, and `replicated` copied there.

    Each device runs the sweep's ordinary program on its own block, so no loop of it
    waits for another device. (A `jit` of the whole batch partitioned by GSPMD must agree
    on every `vmap`ped solver loop's stopping test across devices at each iteration; with
    two forced CPU host devices jaxlib 0.10.2's runtime hung in such a program, and
    equinox's closure conversion inside `jax.shard_map` raises.) JAX dispatches each call
    asynchronously, so the devices run at once; each compiles the program for itself.

    Returns:
        The first device's output, and `batched(output)` of all devices joined into global
        arrays sharded over the mesh (`NamedSharding(mesh, P("batch"))`).
    """
    from jax.sharding import NamedSharding, PartitionSpec

    sharding = NamedSharding(_mesh(devices), PartitionSpec("batch"))
    placed = jax.tree_util.tree_map(lambda a: shard_batch(a, devices), batch)
    local = [d for d in devices if d.process_index == jax.process_index()]
    outputs = []
    for device in local:
        block = jax.tree_util.tree_map(lambda a, d=device: next(s.data for s in a.addressable_shards if s.device == d), placed)
        outputs.append(call(block, jax.device_put(replicated, device)))
    parts = [batched(out) for out in outputs]
    length = -(-jax.tree_util.tree_leaves(batch)[0].shape[0] // len(devices)) * len(devices)
    joined = jax.tree_util.tree_map(
        lambda *leaves: jax.make_array_from_single_device_arrays((length, *leaves[0].shape[1:]), sharding, list(leaves)),
        *parts)
    return outputs[0], joined


def _pad(a, length: int):
    """`a` with its leading axis padded to `length` by repeating the last entry."""
    extra = length - a.shape[0]
    return a if extra == 0 else jnp.concatenate([a, jnp.repeat(a[-1:], extra, axis=0)])


def _rows(count: int, tree):
    """The first `count` entries of every array's leading axis (drops padded rows)."""
    return jax.tree_util.tree_map(lambda a: a[:count], tree)


def _devices(devices):
    """None, or the list of devices to shard over ("all": `jax.devices()`)."""
    if devices is None:
        return None
    if isinstance(devices, str):
        if devices != "all":
            raise ValueError(f"devices must be None, 'all' or a list of jax devices; got {devices!r}")
        return jax.devices()
    devices = list(devices)
    if not devices or not all(isinstance(d, jax.Device) for d in devices):
        raise ValueError(f"devices must be None, 'all' or a non-empty list of jax devices; got {devices!r}")
    return devices


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
    stacked = prepare(stack_scenes(scenes))
    arrays, static = eqx.partition(stacked, eqx.is_array)
    with precision(stacked.accuracy):
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
        tca = pipeline.unloaded(scene, pair, pipeline.input_checks(scene, pair))

        def running(c):
            step, lo, hi, edge_lo, edge_hi, ltca_code, impact_code = c
            sound = (ltca_code == RESULTS.successful) & (impact_code == RESULTS.successful)
            bracket = ~edge_lo & edge_hi & (hi - lo > tolerance * hi)
            return sound & ((step < 2) | bracket) & (step < _MAX_BISECTION_STEPS)

        def bisect(c):
            step, lo, hi, edge_lo, edge_hi, ltca_code, impact_code = c
            torque = jnp.where(step == 0, low, jnp.where(step == 1, high, 0.5 * (lo + hi)))
            speed = scene.operating.speed
            checks = pipeline.input_checks(scene, pair, torque, speed)
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
