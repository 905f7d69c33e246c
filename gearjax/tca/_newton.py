r"""Newton's method with a backtracking safeguard: an optimistix root finder.

`optimistix.Newton` takes every full step. Where the residual's Jacobian jumps (the flank
of a parabolic relief has a continuous tangent but a curvature that jumps where the relief
starts), full steps can cycle between two iterates on either side of the jump and never
converge: seen in the TCA's flank-contact solves of random designs with short, deep
reliefs. The TCA solves every candidate with `optimistix.Newton` and the few
that fail again with `SafeguardedNewton` (`gearjax.tca.analysis._retry_failed`): backtracking
spends steps where plain Newton's overshoots would still have converged, so it needs
more steps than Newton on the problems Newton solves. `SafeguardedNewton` takes the same full Newton steps while they
decrease the merit $\tfrac12\lVert F\rVert_2^2$ enough (Armijo's condition along the
Newton direction, whose predicted decrease is $\lVert F\rVert^2$ per unit step), and halves
the step back from the last accepted iterate otherwise (Nocedal & Wright, *Numerical
Optimization*, 2nd ed., Algorithm 3.1 with the merit of §11.2). A NaN residual (an iterate
off the flanks' parameter domain) fails the condition like any increase.

Per step it costs what a Newton step costs (one linearisation, one linear solve): a
rejected trial spends its step on the evaluation that rejects it. Where every full step
decreases the merit the iterates are Newton's. Termination is Newton's Cauchy test (step
and residual both below tolerance), on accepted steps; `lower`/`upper` options bound the
iterates as in `optimistix.Newton`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import optimistix as optx

from .._custom_types import Array, Scalar


class _State(eqx.Module):
    f: Array  # residual at the last accepted iterate
    diff: Array  # the last step (previous iterate - new iterate)
    anchor: Array  # last accepted iterate
    direction: Array  # Newton step at the anchor (anchor - Newton point)
    merit: Scalar  # |F(anchor)|^2 (inf before the first evaluation)
    step_size: Scalar  # fraction of the Newton step of the current trial
    accepted: Array  # whether the last evaluated iterate was accepted
    result: optx.RESULTS


class SafeguardedNewton(optx.AbstractRootFinder):
    """Newton's method for $F(y) = 0$ ($y$ a 1-D array) with Armijo backtracking on
    $\\lVert F\\rVert_2^2$.

    Attributes:
        rtol, atol: Cauchy termination tolerances, as for `optimistix.Newton`.
        slope: Armijo constant $c$: a trial at fraction $\\alpha$ of the Newton step is
            accepted when $\\lVert F\\rVert^2$ falls to at most $(1 - 2c\\alpha)$ times its value.
    """

    rtol: float
    atol: float
    norm: Callable = optx.max_norm
    slope: float = 1e-4
    linear_solver: lx.AbstractLinearSolver = lx.AutoLinearSolver(well_posed=None)

    def init(self, fn, y, args, options, f_struct, aux_struct, tags) -> _State:
        del fn, args, options, aux_struct, tags
        return _State(
            f=jnp.full(f_struct.shape, jnp.inf, f_struct.dtype),
            diff=jnp.full_like(y, jnp.inf),
            anchor=y,
            direction=jnp.zeros_like(y),
            merit=jnp.array(jnp.inf, f_struct.dtype),
            step_size=jnp.array(1.0, f_struct.dtype),
            accepted=jnp.array(False),
            result=optx.RESULTS.successful,
        )

    def step(self, fn, y, args, options: dict[str, Any], state: _State, tags):
        fx, lin_fn, aux = jax.linearize(lambda _y: fn(_y, args), y, has_aux=True)
        merit = jnp.sum(jnp.square(fx))
        # The first evaluation meets an infinite merit and is accepted unless NaN.
        accept = merit <= (1.0 - 2.0 * self.slope * state.step_size) * state.merit
        jac = lx.FunctionLinearOperator(lin_fn, jax.eval_shape(lambda: y), tags=tags)
        sol = lx.linear_solve(jac, fx, self.linear_solver, throw=False)
        anchor = jnp.where(accept, y, state.anchor)
        direction = jnp.where(accept, sol.value, state.direction)
        # A rejected trial: the minimiser of the quadratic through the merit at the anchor,
        # its slope there (-|F|^2 along the Newton step) and the trial's merit, kept within
        # [0.1, 0.5] of the trial's step (Dennis & Schnabel, Algorithm A6.3.1); half the
        # step where the trial's merit is not finite.
        alpha = state.step_size
        curvature = (merit - state.merit * (1.0 - 2.0 * alpha)) / (2.0 * alpha**2)
        interpolated = jnp.clip(state.merit / (2.0 * curvature), 0.1 * alpha, 0.5 * alpha)
        backtrack = jnp.where(jnp.isfinite(interpolated), interpolated, 0.5 * alpha)
        step_size = jnp.where(accept, 1.0, backtrack)
        new_y = anchor - step_size * direction
        if options.get("lower") is not None:
            new_y = jnp.maximum(new_y, options["lower"])
        if options.get("upper") is not None:
            new_y = jnp.minimum(new_y, options["upper"])
        new_state = _State(
            f=jnp.where(accept, fx, state.f),
            diff=anchor - new_y,
            anchor=anchor,
            direction=direction,
            merit=jnp.where(accept, merit, state.merit),
            step_size=step_size.astype(state.step_size.dtype),
            accepted=accept,
            result=optx.RESULTS.where(accept, optx.RESULTS.promote(sol.result), optx.RESULTS.successful),
        )
        return new_y, new_state, aux

    def terminate(self, fn, y, args, options, state: _State, tags):
        del fn, args, options, tags
        # optimistix's Cauchy test as `Newton` applies it: the step relative to
        # atol + rtol |y|, the residual against atol.
        step_small = self.norm(jnp.abs(state.diff) / (self.atol + self.rtol * jnp.abs(y))) < 1
        residual_small = self.norm(jnp.abs(state.f)) < self.atol
        small = step_small & residual_small
        linsolve_fail = state.result != optx.RESULTS.successful
        return (state.accepted & small) | linsolve_fail, state.result

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        return y, aux, {}
