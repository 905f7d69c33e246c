r"""A trust-region SQP on the flank branch of the mesh-in regime switch, with exact gradients.

The impact force is smooth on each side of the switch between a flank strike and a
tip-edge strike, and the lowest designs of seed 001's space sit on the switch, on its
flank side (`docs/landscape.md`, decision 0017). Written with the flank branch
$J_\text{flank}$ (the objective of the flank branch's force, `Objective.evaluate(...,
flank_branch=True)`) and the switching function $s_{l,e}$ of every load $l$ and error
sample $e$ (mm of the gear's roll length, `gearjax.impact.branches`), the search is the
smooth program

$$\min_{x \in [0,1]^6} J_\text{flank}(x) \quad\text{subject to}\quad
  s_{l,e}(x) \ge m \;\; \text{for all } l, e ,$$

whose solution is a design where the flanks strike first at every load, a margin $m$
off the switch (the switch moves between accuracies: a design on it at the search's
accuracy can strike with the edge at the certification's).

Each start runs a trust-region SQP (Fletcher's S$\ell_1$QP): at its point $x$ the model
$\tfrac12 d^\top B d + g^\top d + \mu \sum_i (-(c_i + a_i^\top d))_+$ (objective scaled by
its value at the start, $c_i = (s_i - m)/s_0$ with $s_0 = 0.1$ mm, $B$ a damped BFGS
approximation of the Lagrangian's Hessian) is minimised over the box
$\max(-r, -x) \le d \le \min(r, 1 - x)$ (the trust region $r$ in the infinity norm, within
the bounds), a convex piecewise-quadratic program of six variables solved exactly by
enumerating its active sets (`_subproblem`). The step is accepted where the exact penalty $J + \mu\sum_i(-c_i)_+$ falls by at least a tenth of the
model's prediction, and $r$ grows or shrinks with their ratio. The value, gradient,
constraints and their Jacobian of all starts' trial points come from one compiled call
per iteration (`switch_values`: forward mode, six tangents of the first-contact search's
implicit derivatives). A start that has converged (the model predicts no decrease, or
$r$ below `min_radius`), stalled (its penalty function fell by less than `ftol` over
`patience` iterations) or whose first point fails starts again from a random point, so
every evaluation of the budget works; each start slot keeps its best design with
$s \ge m - $`feasibility` mm.

The program knows only the flank side: a design whose best lies on the tip-edge side of
the switch is not sought (none does in seed 001's space), and a start on the edge side is
pulled across by the penalty.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, Bool, Float, Int
from .._validate import check_int, check_range
from .gradient import latin_hypercube
from .objective import Objective
from .space import DesignSpace

#: mm of roll length per unit of the scaled constraints
SWITCH_SCALE = 0.1
#: constraints held by the quadratic subproblem (the nearest to violation; `_subproblem`)
SUBPROBLEM_ROWS = 3


class SwitchConfig(eqx.Module):
    """Static settings of the switching-aware SQP.

    Attributes:
        starts: start slots run together (>= 1).
        iterations: cap on the iterations (>= 1); each evaluates every slot's trial point.
        margin: $m$, the switching function's distance kept from the switch (mm of roll
            length, >= 0).
        radius: the first trust radius (unit coordinates, 0 to 1).
        min_radius: a slot whose radius falls below it starts again (unit coordinates).
        penalty: $\\mu$, the exact penalty's weight on the scaled constraints (> 0; larger
            than the multipliers).
        feasibility: a design counts as on the flank side with $s \\ge m -$ this (mm).
        tolerance: a slot whose model predicts a decrease below this (relative to its
            start's objective) has converged and starts again.
        ftol, patience: a slot whose penalty function has not fallen by `ftol` (relative to
            its start's objective) for `patience` iterations has stalled and starts again.
    """

    starts: int = eqx.field(static=True, default=6)
    iterations: int = eqx.field(static=True, default=30)
    margin: float = eqx.field(static=True, default=0.05)
    radius: float = eqx.field(static=True, default=0.2)
    min_radius: float = eqx.field(static=True, default=1e-4)
    penalty: float = eqx.field(static=True, default=10.0)
    feasibility: float = eqx.field(static=True, default=1e-4)
    tolerance: float = eqx.field(static=True, default=1e-7)
    ftol: float = eqx.field(static=True, default=1e-2)
    patience: int = eqx.field(static=True, default=5)

    def __check_init__(self):
        check_int("starts", self.starts, 1)
        check_int("iterations", self.iterations, 1)
        check_range("switch margin", self.margin, 0.0, 1.0, unit="mm")
        check_range("trust radius", self.radius, 0.0, 1.0, low_inclusive=False)
        check_range("min_radius", self.min_radius, 0.0, self.radius, low_inclusive=False)
        check_range("penalty", self.penalty, 0.0, None, low_inclusive=False)
        check_range("feasibility", self.feasibility, 0.0, 1.0, unit="mm")
        check_range("tolerance", self.tolerance, 0.0, 1.0)
        check_range("ftol", self.ftol, 0.0, 1.0)
        check_int("patience", self.patience, 1)


class SwitchState(eqx.Module):
    """State of the SQP's start slots (a pytree; the run directory saves and restores it).

    Attributes:
        iteration: iterations done.
        x: each slot's accepted point (unit coordinates), shape (K, 6); `f`, `g` (scaled
            objective and gradient), `c`, `a` (scaled constraints and Jacobian) there.
        scale: the objective at the slot's start (what `f` is relative to).
        hessian: $B$, shape (K, 6, 6); `multipliers` of the constraints at `x`.
        radius: trust radius; `predicted`: the model's decrease of the penalty to `trial`.
        trial: the point each slot evaluates next; `fresh`: the slot's point is a start
            not evaluated yet.
        best, best_value: each slot's best design on the flank side and its $J$ (in the
            objective's unit; $+\\infty$ before one is found).
        stalled: iterations since the slot's penalty function last fell by `ftol`; `anchor`:
            its value then.
        restarts: starts each slot has begun after its first; `key`: the random key.
    """

    iteration: Int[Array, ""]
    x: Float[Array, "K d"]
    f: Float[Array, " K"]
    g: Float[Array, "K d"]
    c: Float[Array, "K m"]
    a: Float[Array, "K m d"]
    scale: Float[Array, " K"]
    hessian: Float[Array, "K d d"]
    multipliers: Float[Array, "K m"]
    radius: Float[Array, " K"]
    predicted: Float[Array, " K"]
    trial: Float[Array, "K d"]
    fresh: Bool[Array, " K"]
    best: Float[Array, "K d"]
    best_value: Float[Array, " K"]
    stalled: Int[Array, " K"]
    anchor: Float[Array, " K"]
    restarts: Int[Array, " K"]
    key: Array


def switch_values(objective: Objective, space: DesignSpace, units):
    """$J_\\text{flank}$ (objective's unit), its gradient in unit coordinates, the switching
    functions $s$ (mm, flattened over loads and samples) and their Jacobian, at unit-cube
    points of shape (K, 6): `(J (K,), dJ (K, 6), s (K, m), ds (K, m, 6))`, one program."""
    return _switch_jit(objective, space, jnp.asarray(units, objective.torques.dtype))


@eqx.filter_jit
def _switch_jit(objective, space, units):
    def branch(x):
        evaluation = objective.evaluate(space.to_design(x), flank_branch=True)
        values = jnp.concatenate([evaluation.objective[None], evaluation.switch.reshape(-1)])
        return values, values

    def one(x):
        jacobian, values = jax.jacfwd(branch, has_aux=True)(x)  # six tangents beside the values
        return values[0], jacobian[0], values[1:], jacobian[1:]

    return jax.lax.map(one, units, batch_size=objective.map_batch_size)


def switch_init(key, config: SwitchConfig, constraints: int, starts=None, dtype=jnp.float64) -> SwitchState:
    """The first state: `config.starts` slots at a Latin hypercube (the first rows replaced
    by `starts`, unit coordinates, where given), `constraints` switching functions each."""
    key, sub = jax.random.split(key)
    x = latin_hypercube(sub, config.starts, 6)
    if starts is not None:
        given = jnp.asarray(starts, x.dtype)[: config.starts]
        x = x.at[: given.shape[0]].set(given)
    x = x.astype(dtype)
    k, m = config.starts, constraints
    zeros = lambda *shape: jnp.zeros(shape, dtype)  # noqa: E731
    return SwitchState(
        iteration=jnp.zeros((), jnp.int32), x=x, f=zeros(k), g=zeros(k, 6), c=zeros(k, m), a=zeros(k, m, 6),
        scale=jnp.ones(k, dtype), hessian=jnp.broadcast_to(jnp.eye(6, dtype=dtype), (k, 6, 6)),
        multipliers=zeros(k, m), radius=jnp.full(k, config.radius, dtype), predicted=zeros(k), trial=x,
        fresh=jnp.ones(k, bool), best=x, best_value=jnp.full(k, jnp.inf, dtype),
        stalled=jnp.zeros(k, jnp.int32), anchor=jnp.full(k, jnp.inf, dtype), restarts=jnp.zeros(k, jnp.int32),
        key=key)


def switch_update(state: SwitchState, values, config: SwitchConfig) -> SwitchState:
    """One SQP iteration of every slot from `switch_values` at its trial point."""
    key, sub = jax.random.split(state.key)
    fresh_points = jax.random.uniform(sub, state.x.shape, state.x.dtype)
    slots = jax.vmap(_slot, in_axes=(0, 0, 0, 0, 0, 0, None))
    slot_state = {name: getattr(state, name) for name in _SLOT_FIELDS}
    updated = slots(slot_state, *values, fresh_points, config)
    return SwitchState(iteration=state.iteration + 1, key=key, **updated)


_SLOT_FIELDS = ("x", "f", "g", "c", "a", "scale", "hessian", "multipliers", "radius", "predicted", "trial", "fresh",
                "best", "best_value", "stalled", "anchor", "restarts")


def _slot(st: dict, J, dJ, s, ds, fresh_point, config: SwitchConfig) -> dict:
    """One slot's iteration: accept or reject its trial, update $B$ and $r$, solve the next
    subproblem (or start again)."""
    mu = config.penalty
    ok = jnp.isfinite(J) & jnp.all(jnp.isfinite(dJ)) & jnp.all(jnp.isfinite(s)) & jnp.all(jnp.isfinite(ds))
    scale = jnp.where(st["fresh"] & ok, jnp.maximum(jnp.abs(J), 1e-12), st["scale"])
    f_t, g_t = J / scale, dJ / scale
    c_t, a_t = (s - config.margin) / SWITCH_SCALE, ds / SWITCH_SCALE
    merit = lambda f, c: f + mu * jnp.sum(jnp.maximum(-c, 0.0))  # noqa: E731
    ratio = (merit(st["f"], st["c"]) - merit(f_t, c_t)) / jnp.maximum(st["predicted"], 1e-30)
    accept = ok & (st["fresh"] | (ratio > 0.1))
    step = st["trial"] - st["x"]
    length = jnp.max(jnp.abs(step))
    grow = accept & ~st["fresh"] & (ratio > 0.75) & (length > 0.9 * st["radius"])
    radius = jnp.where(grow, jnp.minimum(2.0 * st["radius"], 1.0),
                       jnp.where(accept, st["radius"], 0.25 * jnp.maximum(length, config.min_radius)))
    hessian = jnp.where(accept & ~st["fresh"], _bfgs(st["hessian"], step, st["g"], st["a"], g_t, a_t,
                                                    st["multipliers"]), st["hessian"])
    pick = lambda new, old: jnp.where(accept, new, old)  # noqa: E731
    x, f, g, c, a = pick(st["trial"], st["x"]), pick(f_t, st["f"]), pick(g_t, st["g"]), pick(c_t, st["c"]), \
        pick(a_t, st["a"])
    on_flank = accept & jnp.all(s >= config.margin - config.feasibility)
    better = on_flank & (J < st["best_value"])
    best, best_value = jnp.where(better, st["trial"], st["best"]), jnp.where(better, J, st["best_value"])
    d, multipliers = _subproblem(hessian, g, c, a, jnp.maximum(-radius, -x), jnp.minimum(radius, 1.0 - x), mu)
    linear = c + a @ d
    predicted = -(g @ d + 0.5 * d @ hessian @ d) + mu * (jnp.sum(jnp.maximum(-c, 0.0)) -
                                                          jnp.sum(jnp.maximum(-linear, 0.0)))
    progress = merit(f, c) < st["anchor"] - config.ftol
    anchor = jnp.where(progress | st["fresh"], merit(f, c), st["anchor"])
    stalled = jnp.where(progress | st["fresh"], 0, st["stalled"] + 1)
    again = ((st["fresh"] & ~ok) | (~st["fresh"] & (radius < config.min_radius)) | (stalled >= config.patience)
             | (~(st["fresh"] & ~ok) & (predicted < config.tolerance)))
    eye = jnp.eye(6, dtype=x.dtype)
    return dict(
        x=jnp.where(again, fresh_point, x), f=f, g=g, c=c, a=a, scale=scale,
        hessian=jnp.where(again, eye, hessian), multipliers=jnp.where(again, 0.0, multipliers),
        radius=jnp.where(again, config.radius, radius), predicted=predicted,
        trial=jnp.where(again, fresh_point, jnp.clip(x + d, 0.0, 1.0)), fresh=again,
        best=best, best_value=best_value, stalled=jnp.where(again, 0, stalled), anchor=anchor, restarts=st["restarts"] + again.astype(st["restarts"].dtype))


def _bfgs(hessian, step, g, a, g_new, a_new, multipliers):
    """Powell's damped BFGS update of $B$ with the Lagrangian's gradient change."""
    y = (g_new - a_new.T @ multipliers) - (g - a.T @ multipliers)
    bs = hessian @ step
    sbs, sy = step @ bs, step @ y
    theta = jnp.where(sy >= 0.2 * sbs, 1.0, 0.8 * sbs / jnp.maximum(sbs - sy, 1e-30))
    r = theta * y + (1.0 - theta) * bs
    sr = step @ r
    updated = hessian - jnp.outer(bs, bs) / jnp.maximum(sbs, 1e-30) + jnp.outer(r, r) / jnp.maximum(sr, 1e-30)
    return jnp.where((sbs > 1e-20) & (sr > 1e-20), updated, hessian)


def _subproblem(hessian, g, c, a, lower, upper, mu):
    r"""The S$\ell_1$QP step: the minimiser of the convex model
    $q(d) = \tfrac12 d^\top B d + g^\top d + \mu \sum_i (-(c_i + a_i d))_+$ over
    lower $\le d \le$ upper, and the constraints' multipliers; `(d, multipliers)`.

    Solved exactly by enumeration: the minimiser is the solution of the equality problem
    of its own pattern (each variable at its lower bound, free or at its upper bound; each
    constraint inactive, held at $c_i + a_i d = 0$ or violated, its penalty linear), so the
    patterns' KKT systems are solved at once ($3^6 \cdot 3^m$ of size $6 + m$) and the
    lowest $q$ among the solutions within the box is the step. The subproblem holds the
    `SUBPROBLEM_ROWS` constraints nearest to violation (smallest $c_i$); the penalty
    function that accepts the step holds them all."""
    rows = min(SUBPROBLEM_ROWS, c.shape[0])
    nearest = jnp.argsort(c)[:rows]
    cs, As = c[nearest], a[nearest]
    n, dtype = g.shape[0], g.dtype
    patterns = _patterns(n, rows)  # (P, n + rows) of 0, 1, 2
    box, rows_state = patterns[:, :n], patterns[:, n:]

    def solve(bounds, states):
        free = (bounds == 1).astype(dtype)
        fixed = jnp.where(bounds == 0, lower, jnp.where(bounds == 2, upper, 0.0))
        active, violated = (states == 1).astype(dtype), (states == 2).astype(dtype)
        gradient = g - mu * violated @ As
        H = hessian * free[:, None] * free[None, :] + jnp.diag(1.0 - free)
        A = As * free[None, :] * active[:, None]
        K = jnp.block([[H, A.T], [A, jnp.diag(1.0 - active)]])
        rhs = jnp.concatenate([-(gradient + hessian @ fixed) * free, -(cs + As @ fixed) * active])
        x = jnp.linalg.solve(K, rhs)
        return fixed + free * x[:n], -x[n:] * active + mu * violated

    steps, multipliers = jax.vmap(solve)(box, rows_state)
    model = lambda d: 0.5 * d @ hessian @ d + g @ d + mu * jnp.sum(jnp.maximum(-(c + a @ d), 0.0))  # noqa: E731
    slack = 1e-9 * (1.0 + jnp.max(upper - lower))
    inside = jnp.all((steps >= lower - slack) & (steps <= upper + slack) & jnp.isfinite(steps), axis=-1)
    values = jnp.where(inside, jax.vmap(model)(jnp.where(inside[:, None], steps, 0.0)), jnp.inf)
    best = jnp.argmin(values)
    d = jnp.clip(steps[best], lower, upper)
    full = jnp.zeros_like(c).at[nearest].set(jnp.clip(multipliers[best], 0.0, mu))
    return d, full


def _patterns(n: int, m: int) -> jnp.ndarray:
    """Every pattern of `n` variables and `m` constraints, three states each, shape
    (3^(n + m), n + m) (a constant of the program)."""
    import itertools

    return jnp.asarray(list(itertools.product((0, 1, 2), repeat=n + m)), jnp.int32)
