r"""The optimisation objective: a pure function of the design vector.

For a design $y$ (mm, `gearjax.optimize.space`), a duty cycle of loads $T_l$ at pinion
speeds $\omega_l$ with time shares (weights) $w_l$, and sampled mesh errors $e_s$
($s = 1 \dots S$), the objective is

$$J(y) = \mathop{A}_{l}\Big[\frac{\sigma}{S}\sum_s q(y, T_l, \omega_l, e_s)\Big] + \sum_k \mu_k
         \Big(\frac{p_k(y)}{p_k^\text{lim}} - 1\Big)_+^2 ,$$

where $q$ is one of the `QUANTITIES`: the mesh-in impact force $F_s$ (N, energy method,
`gearjax.impact`), the normal impact velocity $|v_n|$ (mm/s), the loaded TE peak-to-peak
along the line of action (µm), the largest Hertz pressure of the cycle (MPa) or the cycle
mean of the tangent mesh stiffness (N/(mm·µm)); $\sigma = 1$ for a quantity minimised,
$-1$ for one maximised (the stiffness). The aggregate $A$ is the time-weighted mean
$\sum_l w_l(\cdot)/\sum_l w_l$ (the plain mean with equal shares) or the worst case (the
maximum) over the loads, and the optional penalties $p_k$ are the largest Hertz pressure
(MPa) and the loaded TE peak-to-peak along the line of action (mm) over the loads and
samples, with weights $\mu_k$ in the objective's unit. `Objective.aggregated` gives any
quantity's aggregate from one `Evaluation`, so one compiled program serves them all.

For each design and error sample the unloaded TCA runs once (it does not depend on the
load); the LTCA and the first-contact search run per load (`vmap` over the loads), exactly
the stages of `gearjax.simulate` for the same scene, so $q$ equals
`simulate(scene).impact.force` at the same load and design. A design whose loaded contact
or first-contact search fails (`ImpactResult.result` not successful) scores $+\infty$ and
is counted in `Evaluation.failed`.

A batch of designs is evaluated by `Objective.batch` in one compiled call. On a CPU the
designs run one after another inside it (`lax.map`, `batch_size` 1 by default): the
solvers' `while` loops under `vmap` run to the slowest member, which costs more than the
batching saves; on an accelerator set a larger `batch_size`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import Array, ArrayLike, Float, Scalar
from .._solution import RESULTS
from .._validate import check_choice, check_int, check_range
from ..geometry.errors import MeshErrors
from ..geometry.modification import FlankModification
from .. import pipeline
from ..impact import ImpactRegime
from ..runtime.resources import check_memory
from ..scene import Scene, check_one_zone
from .duty import _loads, _speeds, _weights
from .space import modification_from_design

class Quantity(NamedTuple):
    """A quantity the objective can aggregate: its unit, what it is, its sense (1:
    minimised, -1: maximised, the objective holding its negative) and its value per load
    and sample from an `Evaluation`."""

    unit: str
    what: str
    sense: float
    of: Callable[[Evaluation], Array]


#: The objective's quantities $q$ by name. A new quantity is an entry here.
QUANTITIES = {
    "force": Quantity("N", "peak impact force F_s", 1.0, lambda e: e.force),
    "velocity": Quantity("mm/s", "normal impact velocity |v_n|", 1.0, lambda e: jnp.abs(e.velocity)),
    "lte": Quantity("µm", "loaded TE peak-to-peak along the line of action", 1.0, lambda e: 1e3 * e.lte_peak_to_peak),
    "pressure": Quantity("MPa", "largest Hertz pressure of the cycle", 1.0, lambda e: e.pressure),
    "stiffness": Quantity("N/(mm·µm)", "cycle mean of the tangent mesh stiffness per face width (maximised)", -1.0,
                          lambda e: e.stiffness),
}
AGGREGATES = ("mean", "max")


class Penalty(eqx.Module):
    """An exterior penalty $\\mu\\,(p/p^\\text{lim} - 1)_+^2$ on a result quantity.

    Attributes:
        limit: $p^\\text{lim}$ (MPa for the Hertz pressure, mm for the loaded TE peak-to-peak).
        weight: $\\mu$, in the objective's unit (N or mm/s).
    """

    limit: float = eqx.field(static=True)
    weight: float = eqx.field(static=True)

    def __check_init__(self):
        check_range("penalty limit", self.limit, 0.0, None, low_inclusive=False)
        check_range("penalty weight", self.weight, 0.0, None)

    def __call__(self, value: Scalar) -> Scalar:
        return self.weight * jnp.square(jnp.maximum(value / self.limit - 1.0, 0.0))


class Evaluation(eqx.Module):
    """One design's results over the loads (axis 0) and error samples (axis 1).

    Attributes:
        objective: $J(y)$ ($+\\infty$ when a stage failed).
        quantity: the objective's $q$ per load and sample (its `Quantity.unit`).
        force: impact force $F_s$ (N).
        velocity: normal impact velocity $v_n$ (mm/s).
        edge: the first contact is a tip edge (`ImpactRegime.edge`).
        pressure: largest Hertz pressure of the cycle (MPa).
        lte_peak_to_peak: loaded TE peak-to-peak along the line of action (mm).
        stiffness: cycle mean of the tangent mesh stiffness per face width (N/(mm·µm)).
        failed: number of (load, sample) entries whose LTCA or impact stage failed.
        switch: the switching function $s$ of the mesh-in regime switch (mm,
            `gearjax.impact.branches`; > 0 where the flanks strike) of an evaluation on the
            flank branch (`Objective.evaluate(..., flank_branch=True)`), else None.
        actual_force, actual_velocity: of an evaluation on the flank branch with `actual`,
            the impact force (N) and velocity (mm/s) of the regime that strikes first
            (`gearjax.impact`, as without `flank_branch`; $+\\infty$ where that stage
            failed; values only, their derivatives zero), else None.
    """

    objective: Scalar
    quantity: Float[Array, "load sample"]
    force: Float[Array, "load sample"]
    velocity: Float[Array, "load sample"]
    edge: Array
    pressure: Float[Array, "load sample"]
    lte_peak_to_peak: Float[Array, "load sample"]
    stiffness: Float[Array, "load sample"]
    failed: Array
    switch: Float[Array, "load sample"] | None = None
    actual_force: Float[Array, "load sample"] | None = None
    actual_velocity: Float[Array, "load sample"] | None = None

    def actual(self) -> Evaluation:
        """The evaluation with the force and velocity of the regime that strikes first (an
        evaluation on the flank branch made with `actual`; itself otherwise)."""
        if self.actual_force is None:
            return self
        return dataclasses.replace(self, force=self.actual_force, velocity=self.actual_velocity)


class Objective(eqx.Module):
    """The objective $J(y)$ of a scene over a load spectrum and error samples.

    Build it with `Objective.create`; call it on a design vector (mm, shape (6,)) for the
    scalar $J$, `evaluate` for every load's and sample's results, `batch` for a batch of
    designs in one compiled call. All three are pure and `jit`/`vmap`/`grad`-able.

    Attributes:
        scene: the template scene (its modification is replaced by the design, its torque
            and speed by each load's, its errors by each sample).
        torques: the loads $T_l$ (N·mm), shape (L,).
        speeds: the pinion speed $\\omega_l$ at each load (rad/s), shape (L,).
        weights: $w_l$ (time shares), shape (L,), summing to 1.
        errors: the error samples $e_s$ as a batched `MeshErrors` (leading axis S).
        quantity: a name of `QUANTITIES` (static).
        aggregate: "mean" (time-weighted) or "max" (worst case) over the loads (static).
        pressure_penalty, lte_penalty: optional `Penalty` on the largest Hertz pressure
            (MPa) and the loaded TE peak-to-peak (mm).
        batch_size: designs evaluated together inside `batch` (static; see the module).
    """

    scene: Scene
    torques: Float[Array, " load"]
    speeds: Float[Array, " load"]
    weights: Float[Array, " load"]
    errors: MeshErrors
    quantity: str = eqx.field(static=True)
    aggregate: str = eqx.field(static=True)
    pressure_penalty: Penalty | None = None
    lte_penalty: Penalty | None = None
    batch_size: int = eqx.field(static=True, default=1)

    @classmethod
    def create(
        cls,
        scene: Scene,
        *,
        torques: ArrayLike | None = None,
        torques_Nm: ArrayLike | None = None,
        speeds: ArrayLike | None = None,
        speeds_rpm: ArrayLike | None = None,
        weights: ArrayLike | None = None,
        quantity: str = "force",
        aggregate: str = "mean",
        errors: MeshErrors | None = None,
        pressure_penalty: Penalty | None = None,
        lte_penalty: Penalty | None = None,
        batch_size: int = 1,
    ) -> Objective:
        """Check the inputs and build the objective.

        Args:
            scene: a scene with a torque and `"impact"` in its effects (an involute pair); a
                scene without a modification is the unmodified pair (`FlankModification()`:
                zero amounts), its design the initial one.
            torques / torques_Nm: the load spectrum in N·mm or N·m (give at most one; default
                the scene's own torque): a non-empty list of finite torques > 0.
            speeds / speeds_rpm: the pinion speed at each load in rad/s or rpm (give at most
                one; default the scene's own speed at every load): one finite speed >= 0
                per load, or one for all.
            weights: time shares, one weight >= 0 per load, with a positive sum (default
                equal).
            quantity: a name of `QUANTITIES` ("force", "velocity", "lte", "pressure",
                "stiffness").
            aggregate: "mean" (time-weighted) or "max" (worst case) over the loads.
            errors: error samples as a `MeshErrors` with a leading sample axis (see
                `sample_errors`), or None for the scene's own errors (one sample).
            pressure_penalty, lte_penalty: optional penalties.
            batch_size: designs evaluated together in `batch`, >= 1.
        """
        if scene.operating.torque is None or "impact" not in scene.effects:
            raise ValueError(
                "the optimisation needs a scene with a torque and effects including 'impact' "
                "(OperatingPoint(torque_Nm=...), effects=('impact',))"
            )
        check_one_zone(scene, "the optimisation")
        if scene.modification is None:  # an unmodified pair: the search starts from it
            scene = dataclasses.replace(scene, modification=FlankModification())
        check_choice("quantity (objective)", quantity, tuple(QUANTITIES))
        check_choice("aggregate", aggregate, AGGREGATES)
        check_int("batch_size", batch_size, 1)
        values = _loads(scene, torques, torques_Nm)
        w = _weights(weights, values.size)
        rates = _speeds(scene, speeds, speeds_rpm, values.size)
        if errors is None:
            base = scene.errors if scene.errors is not None else MeshErrors()
            errors = jax.tree_util.tree_map(lambda x: jnp.asarray(x)[None], base)
        elif not isinstance(errors, MeshErrors) or jnp.ndim(errors.misalignment) != 1:
            raise ValueError("errors must be a MeshErrors with one leading sample axis (see sample_errors)")
        if scene.errors is None:  # the samples replace the errors: the scene needs the slot
            scene = dataclasses.replace(scene, errors=MeshErrors())
        # every load and error sample of `batch_size` designs at once (`evaluate`, `batch`)
        samples = int(jnp.shape(errors.misalignment)[0])
        check_memory(scene, loads=values.size * samples, what="the objective", batch=batch_size)
        scene = pipeline.prepare(scene)
        dtype = jnp.float32 if scene.accuracy.dtype == "float32" else jnp.float64
        errors = jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype), errors)
        return cls(scene=scene, torques=jnp.asarray(values, dtype), speeds=jnp.asarray(rates, dtype),
                   weights=jnp.asarray(w, dtype), errors=errors, quantity=quantity, aggregate=aggregate,
                   pressure_penalty=pressure_penalty, lte_penalty=lte_penalty, batch_size=batch_size)

    @property
    def samples(self) -> int:
        """Number of error samples $S$."""
        return int(jnp.shape(self.errors.misalignment)[0])

    def scene_for(self, design: ArrayLike, torque: ArrayLike | None = None, errors: MeshErrors | None = None,
                  speed: ArrayLike | None = None) -> Scene:
        """The template scene with the design's modification (and a load, speed and error
        sample)."""
        scene = eqx.tree_at(lambda s: s.modification, self.scene, modification_from_design(design))
        if torque is not None:
            scene = eqx.tree_at(lambda s: s.operating.torque, scene, jnp.asarray(torque, self.torques.dtype))
        if speed is not None:
            scene = eqx.tree_at(lambda s: s.operating.speed, scene, jnp.asarray(speed, self.torques.dtype))
        if errors is not None:
            scene = eqx.tree_at(lambda s: s.errors, scene, errors)
        return scene

    def evaluate(self, design: ArrayLike, flank_branch: bool = False, actual: bool = False) -> Evaluation:
        """Results of one design (mm, shape (6,)) at every load and error sample; with
        `flank_branch`, the impact of the flank branch of the regime switch and the switching
        function (`pipeline.branches`): $J$ of $F_\\text{flank}$, equal to $J$ where every
        load's flanks strike first (`Evaluation.switch` >= 0); with `actual` as well, the
        impact of the regime that strikes first besides (`Evaluation.actual`)."""

        def per_sample(errors):
            scene = self.scene_for(design, errors=errors)
            pair = scene.pair.resolve()
            modified = pipeline.modification_checks(scene, pair)
            tca = pipeline.unloaded(scene, pair, modified)

            def per_load(torque, speed):
                checks = modified + pipeline.operating_checks(torque, speed)
                ltca = pipeline.loaded(scene, pair, tca, torque, checks)
                true = None
                if not flank_branch:
                    true = pipeline.impact(scene, pair, tca, ltca, torque, speed, checks)
                elif actual:  # its value only: no tangents through a second search
                    true = pipeline.impact(*_constant((scene, pair, tca, ltca, torque, speed)), checks)
                if flank_branch:
                    both = pipeline.branches(scene, pair, tca, ltca, torque, speed, checks, edge=False)
                    impact, switch = both.flank, both.switch
                else:
                    impact, switch = true, jnp.zeros_like(true.force)
                ok = (impact.result == RESULTS.successful) & (ltca.result == RESULTS.successful)
                if not (flank_branch and actual):
                    true_force = true_velocity = jnp.zeros_like(impact.force)
                else:
                    fine = (true.result == RESULTS.successful) & (ltca.result == RESULTS.successful)
                    true_force, true_velocity = (jnp.where(fine, v, jnp.inf) for v in (true.force, true.velocity))
                return (
                    impact.force,
                    impact.velocity,
                    (impact if true is None else true).regime == ImpactRegime.edge,
                    jnp.max(ltca.pressure),
                    ltca.lte_peak_to_peak_line,
                    ltca.mean_mesh_stiffness,
                    ok,
                    switch,
                    true_force,
                    true_velocity,
                )

            return _mapped(per_load, self.torques, self.speeds)

        force, velocity, edge, pressure, lte, stiffness, ok, switch, true_force, true_velocity = _mapped(
            per_sample, self.errors, out_axis=1)
        zero = jnp.zeros((), force.dtype)
        both = flank_branch and actual
        evaluation = Evaluation(zero, force, force, velocity, edge, pressure, lte, stiffness, jnp.sum(~ok),
                                switch if flank_branch else None, true_force if both else None,
                                true_velocity if both else None)
        quantity = QUANTITIES[self.quantity].of(evaluation)
        return eqx.tree_at(lambda e: (e.objective, e.quantity), evaluation, (self.value(evaluation), quantity))

    def aggregated(self, evaluation: Evaluation, quantity: str | None = None, aggregate: str | None = None) -> Scalar:
        """The aggregate over the loads (time-weighted mean or worst case: `aggregate`, by
        default the objective's own) of a quantity's sample mean, signed by its sense
        (`Quantity.sense`): the objective's own quantity by default, or any of `QUANTITIES`
        from the same evaluation."""
        q = QUANTITIES[self.quantity if quantity is None else quantity]
        per_load = q.sense * jnp.mean(q.of(evaluation), axis=-1)
        mean = (self.aggregate if aggregate is None else aggregate) == "mean"
        return jnp.sum(self.weights * per_load, axis=-1) if mean else jnp.max(per_load, axis=-1)

    def value(self, evaluation: Evaluation) -> Scalar:
        """$J$ from an evaluation's results: the aggregate of the objective's quantity plus the
        penalties; $+\\infty$ where a stage failed."""
        value = self.aggregated(evaluation)
        if self.pressure_penalty is not None:
            value = value + self.pressure_penalty(jnp.max(evaluation.pressure, axis=(-2, -1)))
        if self.lte_penalty is not None:
            value = value + self.lte_penalty(jnp.max(evaluation.lte_peak_to_peak, axis=(-2, -1)))
        return jnp.where(evaluation.failed == 0, value, jnp.inf)

    def __call__(self, design: ArrayLike) -> Scalar:
        """$J(y)$ for one design (mm, shape (6,))."""
        return self.evaluate(design).objective

    def batch(self, designs: ArrayLike) -> Evaluation:
        """`evaluate` for designs of shape (P, 6), in one program (leading axis P)."""
        designs = jnp.asarray(designs, self.torques.dtype)
        return jax.lax.map(self.evaluate, designs, batch_size=self.map_batch_size)

    @property
    def map_batch_size(self) -> int | None:
        """`lax.map`'s `batch_size` for `batch_size` designs at once: None for one, a plain
        `scan` (`batch_size=1` would `vmap` each design, with the costs `_mapped` avoids)."""
        return None if self.batch_size == 1 else self.batch_size


def _constant(tree):
    """`tree` with `jax.lax.stop_gradient` on its array leaves (forward mode carries no tangents)."""
    return jax.tree_util.tree_map(lambda v: jax.lax.stop_gradient(v) if eqx.is_array(v) else v, tree)


def _mapped(fn, *xs, out_axis: int = 0):
    """`jax.vmap(fn, out_axes=out_axis)(*xs)`, or, where the mapped axis has one entry (one
    load, one error sample), `fn` of that entry with the axis put back. A `vmap` makes every
    solver's condition a batched one, even over one entry: each `cond` then runs both
    branches (the TCA's fallback solves among them) and each `while_loop` selects in its
    body, which costs equations and time for nothing."""
    if jax.tree_util.tree_leaves(xs)[0].shape[0] != 1:
        return jax.vmap(fn, out_axes=out_axis)(*xs)
    out = fn(*jax.tree_util.tree_map(lambda x: x[0], xs))
    return jax.tree_util.tree_map(lambda y: jnp.expand_dims(y, out_axis), out)


def sample_errors(
    count: int,
    *,
    misalignment: float = 0.0,
    base_pitch_deviation: float = 0.0,
    pitch_deviation: float = 0.0,
    seed: int = 0,
) -> MeshErrors:
    """`count` mesh-error samples drawn uniformly within symmetric tolerances (mm):
    $f \\sim U(-t, t)$ for each tolerance $t$ (0 keeps that error at zero). A fixed `seed`
    makes the objective deterministic."""
    check_int("error samples", count, 1)
    for name, value in (("misalignment", misalignment), ("base_pitch_deviation", base_pitch_deviation),
                        ("pitch_deviation", pitch_deviation)):
        check_range(f"{name} tolerance", value, 0.0, 1.0, unit="mm")
    keys = jax.random.split(jax.random.PRNGKey(seed), 3)
    draw = lambda key, t: t * jax.random.uniform(key, (count,), minval=-1.0, maxval=1.0)  # noqa: E731
    return MeshErrors(
        base_pitch_deviation=draw(keys[1], base_pitch_deviation),
        pitch_deviation=draw(keys[2], pitch_deviation),
        misalignment=draw(keys[0], misalignment),
    )


def design_of(scene: Scene) -> Float[Array, 6]:
    """The scene's pinion modification as a design vector (mm)."""
    return scene.modification.as_vector()



