"""Named results: solver outcomes as an `equinox.Enumeration`, and helpers for enumerations.

Every result object of the pipeline (`TCAResult`, `LTCAResult`, `ImpactResult`,
`LocalStiffness`) carries a `result` field, an item of `RESULTS`, computed inside the traced
program from the solvers' own outcomes (no host callback, so a compiled program stays
cacheable by JAX's persistent compilation cache). Items are pytrees: they pass through
`jit` and `vmap` (a batched result holds one code per batch entry) and compare with `==`
against an item of the same enumeration, e.g. `result.impact.result == RESULTS.successful`.
`simulate(scene, throw=True)` turns a failed LTCA or impact stage into a `SimulationError`
once the values are concrete (unconverged TCA candidates stay a code); nested stages never
throw (as in optimistix's `_solution.py`).
"""

from __future__ import annotations

import functools as ft
from typing import Any, TypeVar

import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.custom_derivatives
import jax.flatten_util
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from ._custom_types import ArrayLike

Item = TypeVar("Item")


class RESULTS(eqx.Enumeration):
    """Outcome of a stage of the pipeline. The message says what failed and how to fix it."""

    successful = ""
    tca_unconverged = (
        "Some relevant contact candidate solves of the unloaded TCA did not converge "
        "(TCAResult.unconverged counts them per slice); their candidates were left out, so a "
        "contact may have been missed. Raise Accuracy.newton_max_steps, or loosen "
        "newton_rtol/newton_atol."
    )
    ltca_unconverged = (
        "The loaded contact solve did not converge at some position (LTCAResult.converged). "
        "The active set did not settle (or, for Palmgren's law, Newton did not reach "
        "newton_rtol/newton_atol) within Accuracy.contact_max_steps: raise it."
    )
    first_contact_not_bracketed = (
        "No first contact of an incoming tooth pair was bracketed on the cycle grid: the "
        "gap of no pair of the window crosses from open to closed between two positions. "
        "Widen the tooth-pair window (Scene(pairs=...)), cover more of the mesh "
        "(Scene(pitches=...)) or refine the grid (Accuracy.positions_per_pitch)."
    )
    first_contact_jump = (
        "The incoming pair's gap jumps from open to closed at one pinion angle instead of "
        "closing, so there is no quasi-static first contact: e.g. the loaded TE of the pairs "
        "in mesh drops there below the incoming pair's offset (a pair's contact leaves its "
        "flank), and the gear swings through the step until the incoming pair stops it, a "
        "dynamic strike that gearjax does not model. result.impact.pinion_angle locates the "
        "jump. Seen with pitch errors (a double-circular-arc pair's axial pitch error); a "
        "jump from a missed TCA candidate shows in result.tca.unconverged, one from the grid "
        "moves on a finer Accuracy."
    )
    first_contact_unconverged = (
        "The first-contact root search (safeguarded Newton on the gap along the pinion "
        "angle) did not converge. Raise Accuracy.impact_max_steps."
    )
    impact_contact_unconverged = (
        "The loaded contact solve of the pairs in mesh did not converge at the first-contact "
        "position. Raise Accuracy.contact_max_steps."
    )
    invalid_modification = (
        "A flank modification given as traced values (built inside jit, vmap or grad, where "
        "its constructor cannot check them) is out of range: y1, y2, y5 must be in [0, 1] mm, "
        "y3 and y4 in (0, the roll length of the active flank], y6 in [0, the face width), "
        "all finite. The outputs of the stage are NaN. Check the values with the "
        "FlankModification constructor outside the transformation."
    )
    invalid_operating_point = (
        "A torque or speed given as traced values (inside jit, vmap or grad) is negative or "
        "not finite; the outputs of the stage are NaN."
    )
    stiffness_fit_failed = (
        "A contact solve of the local force-approach curve at the impact point did not "
        "converge, so the stiffness fit F = K_s delta^n is unreliable. Raise "
        "Accuracy.contact_max_steps, or narrow Accuracy.impact_fit_range."
    )


class SimulationError(RuntimeError):
    """A stage of `simulate` failed (raised with `throw=True`).

    Attributes:
        stage: "tca", "ltca" or "impact".
        result: the `RESULTS` item(s) of that stage.
    """

    def __init__(self, stage: str, result, message: str):
        super().__init__(message)
        self.stage = stage
        self.result = result


def _leaf(item) -> Any:
    (value,) = jax.tree_util.tree_leaves(item)
    return value


def _concrete_value(item, what: str) -> np.ndarray:
    value = _leaf(item)
    if isinstance(value, jax.core.Tracer):
        raise ValueError(f"{what} needs a concrete enumeration item (outside jit/vmap); got a traced one")
    return np.asarray(value)


def enum_name(item) -> str | np.ndarray:
    """Name(s) of a concrete enumeration item, e.g. `"edge"` for `ImpactRegime.edge`.

    Args:
        item: an item of any `equinox.Enumeration`, scalar or batched (e.g. returned by a
            `vmap`), holding concrete values.

    Returns:
        the name (str) for a scalar item; for a batched one a NumPy array of names of the
        item's shape.
    """
    value = _concrete_value(item, "enum_name")
    # equinox keeps the name -> item table on the enumeration class (`_name_to_item`); it
    # has no public accessor, so this is the one place that reads it.
    table = item._enumeration._name_to_item
    names = {int(np.asarray(_leaf(v))): k for k, v in table.items()}
    if value.ndim == 0:
        return names[int(value)]
    return np.vectorize(lambda v: names[int(v)], otypes=[object])(value).astype(str)


def enum_message(item) -> str | np.ndarray:
    """Message(s) of a concrete enumeration item (`RESULTS`: what failed and how to fix
    it); str for a scalar item, a NumPy array of str for a batched one."""
    value = _concrete_value(item, "enum_message")
    messages = item._enumeration._index_to_message
    if value.ndim == 0:
        return messages[int(value)]
    return np.vectorize(lambda v: messages[int(v)], otypes=[object])(value).astype(str)


def enum_select(index: ArrayLike, items: tuple[Item, ...]) -> Item:
    """`items[index]` elementwise for an integer array `index` (traceable): one enumeration
    item of `index`'s shape. `items` are items of one enumeration."""
    index = jnp.asarray(index)
    return jax.tree_util.tree_map(lambda *values: jnp.stack([jnp.asarray(v) for v in values])[index], *items)


def enum_where(pred: ArrayLike, a: Item, b: Item) -> Item:
    """`a` where `pred` else `b`, elementwise for any shape of `pred` (`Enumeration.where`
    takes a scalar predicate only)."""
    return jax.tree_util.tree_map(lambda x, y: jnp.where(pred, x, y), a, b)


def first_failure(*checks: tuple[ArrayLike, Any]):
    """The first `RESULTS` item whose failure flag is set, else `RESULTS.successful`.

    Args:
        checks: `(failed, item)` pairs in order of priority; `failed` is a boolean array
            (all of one shape).
    """
    result = RESULTS.successful
    for failed, item in reversed(checks):
        result = enum_where(failed, item, result)
    return result


class ImplicitAdjoint(optx.AbstractAdjoint):
    r"""`optimistix.ImplicitAdjoint` whose tangent solve puts no host callback in the program.

    Forward-mode differentiation through a root find gives the tangent of the root by the
    implicit function theorem, $\dot y = -(\partial_y F)^{-1}\,\partial_\theta F\,\dot\theta$
    at $F(y, \theta) = 0$. optimistix solves this with `lineax.linear_solve(..., throw=True)`
    (there is nowhere to report its failure), whose check is an `equinox.error_if`, a host
    callback; lineax's own derivative rule adds more of them at second order. A compiled
    program with a host callback is never stored by JAX's persistent compilation cache, so
    this adjoint solves the (small, dense) system with `jnp.linalg.solve` on the
    materialised Jacobian instead: the same tangents (optimistix's default linear solver
    factorises the same matrix by LU), derivatives of any order, no callback. A singular
    Jacobian gives non-finite tangents instead of an error.
    """

    def apply(self, primal_fn, rewrite_fn, inputs, tags):
        del tags
        inputs = inputs + (ft.partial(eqxi.while_loop, kind="lax"),)
        root, residual = _implicit(primal_fn, rewrite_fn, inputs)
        return root, jax.tree_util.tree_map(eqxi.nondifferentiable_backward, residual)


@eqx.filter_custom_jvp
def _implicit(fn_primal, fn_rewrite, inputs):
    del fn_rewrite
    return jax.tree_util.tree_map(jnp.asarray, fn_primal(inputs))


def _is_none(x):
    return x is None


@_implicit.def_jvp
def _implicit_jvp(primals, tangents):
    fn_primal, fn_rewrite, inputs = primals
    t_inputs = tangents[2]
    no_tangent = jax.tree_util.tree_map(_is_none, t_inputs, is_leaf=_is_none)
    nondiff, diff = eqx.partition(inputs, no_tangent, is_leaf=_is_none)
    # The primal through `_implicit` again, so that higher derivatives use this rule too.
    root, residual = _implicit(fn_primal, fn_rewrite, inputs)

    def rewrite(d):
        return fn_rewrite(root, residual, eqx.combine(d, nondiff))

    _, t_rewrite = jax.jvp(rewrite, (diff,), (t_inputs,))
    flat_root, unravel = jax.flatten_util.ravel_pytree(root)

    def residual_of(flat):
        return jax.flatten_util.ravel_pytree(fn_rewrite(unravel(flat), residual, inputs))[0]

    jacobian = jax.jacfwd(residual_of)(flat_root)
    t_flat = -jnp.linalg.solve(jacobian, jax.flatten_util.ravel_pytree(t_rewrite)[0])
    t_residual = jax.custom_derivatives.zero_from_primal(residual, symbolic_zeros=True)
    return (root, residual), (unravel(t_flat), t_residual)


#: The adjoint of every root find of the engine (see `ImplicitAdjoint`).
ADJOINT = ImplicitAdjoint()


def _given_root(inputs):
    _, root, _ = inputs
    return root, None


def _given_residual(root, _, inputs):
    residual, _, args = inputs
    return residual(root, args)


def implicit_root(residual, root, args):
    r"""`root`, a root of `residual(y, args) = 0` found elsewhere, with the derivatives of
    the implicit function theorem, $\dot y = -(\partial_y F)^{-1}\,\partial_\theta F\,\dot\theta$,
    of any order (the rule of `ImplicitAdjoint`).

    Lets a solve run on stop-gradient'ed data, so that no derivative traces its iteration,
    its restarts or the choice between several solves, and gives the chosen root its
    derivatives once. The value is `root` unchanged.

    Args:
        residual: `F(y, args)`, a module-level function (a static input); `y` and its value
            are 1-D arrays of one length.
        root: the root (its derivatives are discarded).
        args: the data $\theta$ (a pytree) the derivatives are taken along.
    """
    value, _ = _implicit(_given_root, _given_residual, (residual, jax.lax.stop_gradient(root), args))
    return value
