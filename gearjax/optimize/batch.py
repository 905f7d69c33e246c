"""The objective over a batch of designs, as compiled programs shared by every caller.

The objective's batch (values, or values and gradients) is one compiled program per
objective structure and batch shape, shared by the GA, the gradient descent,
`sensitivities`, certification and the tests; the optimisers' own steps are small programs
of their own, so changing a GA setting does not recompile the objective.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..runtime.cache import exclude_from_persistent_cache
from .objective import QUANTITIES, Objective
from .space import DesignSpace


def batch_objective(objective: Objective, designs):
    """$J$ of designs (mm), shape (P, 6)."""
    return batch_evaluation(objective, designs).objective


def batch_evaluation(objective: Objective, designs):
    """`Objective.evaluate` of designs (mm), shape (P, 6): an `Evaluation` with a leading
    design axis, every quantity of every load and sample (`Objective.aggregated` gives any
    quantity's aggregate from it); the program `batch_objective` runs."""
    # A fixed dtype without weak typing, so every caller hits the same compiled program.
    return _objective_jit(objective, jnp.asarray(designs, objective.torques.dtype))


def batch_objective_in_chunks(objective: Objective, designs, rows: int) -> np.ndarray:
    """$J$ of designs (mm), shape (n, 6), as host values: `batch_objective` on `rows` designs
    per call, the last call padded by repeating its last design, so that every n shares
    the one program of `rows` designs."""
    out = [np.asarray(batch_objective(objective, padded))[:n] for padded, n in _chunks(designs, rows)]
    return np.concatenate(out) if out else np.zeros((0,))


def batch_quantities(objective: Objective, designs, quantities, rows: int) -> np.ndarray:
    """Aggregates over the objective's duty cycle of `quantities` (`(name, aggregate)` pairs,
    `Objective.aggregated`) of designs (mm), shape (n, 6), as host values of shape (n, Q) in
    their units and natural sense (the stiffness positive), $+\\infty$ where a stage failed;
    `rows` designs per call of `batch_evaluation`, padded as in `batch_objective_in_chunks`."""
    out = []
    for padded, n in _chunks(designs, rows):
        evaluation = batch_evaluation(objective, padded)
        q = np.stack([QUANTITIES[name].sense * np.asarray(jax.vmap(
            lambda e, name=name, a=a: objective.aggregated(e, name, a))(evaluation)) for name, a in quantities], axis=-1)
        out.append(np.where((np.asarray(evaluation.failed) == 0)[:, None], q, np.inf)[:n])
    return np.concatenate(out) if out else np.zeros((0, len(quantities)))


def _chunks(designs, rows: int):
    """`(padded, n)`: `rows` designs at a time, the last chunk's n padded by its last design."""
    designs = np.atleast_2d(np.asarray(designs, dtype=float))
    for start in range(0, designs.shape[0], rows):
        part = designs[start:start + rows]
        yield np.concatenate([part, np.repeat(part[-1:], rows - part.shape[0], axis=0)]), part.shape[0]


def batch_gradients(objective: Objective, designs):
    """$J$ of designs (mm), shape (K, 6), and its gradients with respect to the design (mm),
    the loads (N·mm), the pinion speed at each load (rad/s) and the mesh errors (mm), one
    program.

    Gradient descent and `sensitivities` share it: reverse mode costs about the same for
    the four arguments as for the design alone, and one program compiles once (minutes).
    With jaxlib < 0.12 it is kept out of JAX's persistent cache
    (`gearjax.runtime.cache.exclude_from_persistent_cache`).
    """
    dtype = objective.torques.dtype
    return _gradients_jit(objective, jnp.asarray(designs, dtype), objective.torques, objective.speeds, objective.errors)


def batch_value_and_grad(objective: Objective, space: DesignSpace, units):
    """$J$ and $\\partial J/\\partial x = w\\,\\partial J/\\partial y$ at unit-cube points, shape
    (K, 6), through `batch_gradients`."""
    values, (grads, *_) = batch_gradients(objective, space.to_design(jnp.asarray(units, objective.torques.dtype)))
    return values, grads * space.width


@eqx.filter_jit
def _objective_jit(objective, designs):
    return objective.batch(designs)


@eqx.filter_jit
def _gradients_jit(objective, designs, torques, speeds, errors):
    exclude_from_persistent_cache()

    def J(design, torques, speeds, errors):
        o = eqx.tree_at(lambda o: (o.torques, o.speeds, o.errors), objective, (torques, speeds, errors))
        return o(design)

    def one(design):
        return jax.value_and_grad(J, argnums=(0, 1, 2, 3))(design, torques, speeds, errors)

    return jax.lax.map(one, designs, batch_size=objective.map_batch_size)
