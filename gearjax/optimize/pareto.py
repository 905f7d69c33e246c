r"""Pareto fronts with gradients: many scalarisations solved together by the switching-aware SQP.

The quantities $q_i$ (`QUANTITIES`, each aggregated over the duty cycle by the
time-weighted mean or the worst case: `"force"`, `"lte"`, `"pressure:max"`, ...) are
traded against each other. Each of $K$ start slots minimises one augmented Chebyshev
scalarisation (an achievement function, Wierzbicki; Miettinen, *Nonlinear Multiobjective
Optimization*, 1999, sec. 3.5), smoothed by a log-sum-exp of temperature $\tau$:

$$J_k(x) = 1 + \tau \log \sum_i \exp\Big(\frac{\lambda_{ki}\,\hat q_i(x)}{\tau}\Big)
          + \rho \sum_i \lambda_{ki}\,\hat q_i(x), \qquad
  \hat q_i = \frac{q_i - z_i}{w_i},$$

with weights $\lambda_k$ on the simplex (a Das–Dennis lattice of `divisions`), the ideal
point $z$ and span $w$ fixed from the first batch ($z = \min - 0.1\,w$, $w$ its range).
Where the impact force (or velocity) is a quantity, its flank branch is used and every
load's switching function is held at $s \ge m$ (`gearjax.optimize.switch`) in the slots
that weigh it (the others, whose $J_k$ does not depend on it, search both sides of the
switch): each slot is the switching-aware SQP on its own $J_k$, and all slots' trial points are evaluated in one
compiled call per iteration (`pareto_values`: the quantities, the switching functions and
their Jacobians by forward mode, and the quantities with the impact of the regime that
strikes first). Every point evaluated enters the archive with the latter (a tip-edge strike
with its own force), from which `gearjax.optimize.front` filters the front.
"""

from __future__ import annotations

import itertools

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, Bool, Float
from .._validate import check_int, check_range
from .objective import AGGREGATES, QUANTITIES, Objective
from .space import DesignSpace
from .switch import SwitchConfig, SwitchState, switch_init, switch_update

#: quantities whose flank branch and switching function the program uses
IMPACT_QUANTITIES = ("force", "velocity")


def parse_quantity(spec: str, default_aggregate: str = "mean") -> tuple[str, str]:
    """`"pressure:max"` → `("pressure", "max")`; `"lte"` → `("lte", default_aggregate)`.
    Raises `ValueError` naming the allowed names."""
    if not isinstance(spec, str):
        raise ValueError(f"pareto quantity must be a string such as 'force' or 'pressure:max'; got {spec!r}")
    name, _, aggregate = spec.partition(":")
    if name not in QUANTITIES:
        raise ValueError(f"pareto quantity {spec!r}: the name must be one of {', '.join(QUANTITIES)}")
    aggregate = aggregate or default_aggregate
    if aggregate not in AGGREGATES:
        raise ValueError(f"pareto quantity {spec!r}: the aggregate after ':' must be one of {', '.join(AGGREGATES)}")
    return name, aggregate


def simplex_lattice(quantities: int, divisions: int) -> jnp.ndarray:
    """The Das–Dennis weights: every $\\lambda$ with entries $j/H$ ($H$ = `divisions`)
    summing to 1, shape $(\\binom{H + Q - 1}{Q - 1}, Q)$."""
    rows = [c for c in itertools.product(range(divisions + 1), repeat=quantities) if sum(c) == divisions]
    return jnp.asarray(sorted(rows, reverse=True), jnp.float64) / divisions


class ParetoConfig(eqx.Module):
    """Static settings of the front search.

    Attributes:
        quantities: the traded quantities, `"name"` or `"name:aggregate"` (names of
            `QUANTITIES`; aggregate "mean" (time-weighted) or "max" (worst case) over the
            loads, default the objective's), at least two, no name twice.
        divisions: $H$ of the weight lattice: $\\binom{H + Q - 1}{Q - 1}$ scalarisations
            (21 for three quantities and $H = 5$), each a start slot.
        iterations: cap on the iterations (each evaluates every slot's trial point).
        margin: the switching function's distance kept from the switch (mm; as
            `SwitchConfig.margin`), where the force or velocity is a quantity.
        temperature: $\\tau$ of the smoothed maximum (on quantities scaled by their span).
        augmentation: $\\rho$, the augmentation's weight (> 0: only Pareto-optimal points
            minimise $J_k$).
        front_size: at most this many front designs are certified (spread out by
            `gearjax.optimize.front.spread`).
    """

    quantities: tuple[str, ...] = eqx.field(static=True, default=("force", "lte", "pressure:max"))
    divisions: int = eqx.field(static=True, default=5)
    iterations: int = eqx.field(static=True, default=40)
    margin: float = eqx.field(static=True, default=0.05)
    temperature: float = eqx.field(static=True, default=0.02)
    augmentation: float = eqx.field(static=True, default=0.05)
    front_size: int = eqx.field(static=True, default=40)

    def __check_init__(self):
        if not isinstance(self.quantities, tuple) or len(self.quantities) < 2:
            raise ValueError(f"pareto quantities: at least two are traded; got {self.quantities!r}")
        names = [parse_quantity(q)[0] for q in self.quantities]
        if len(set(names)) != len(names):
            raise ValueError(f"pareto quantities: each quantity once; got {self.quantities!r}")
        check_int("pareto divisions", self.divisions, 1, 12)
        check_int("pareto iterations", self.iterations, 1)
        check_range("switch margin", self.margin, 0.0, 1.0, unit="mm")
        check_range("pareto temperature", self.temperature, 0.0, 1.0, low_inclusive=False)
        check_range("pareto augmentation", self.augmentation, 0.0, 1.0, low_inclusive=False)
        check_int("pareto front_size", self.front_size, 2)

    def parsed(self, default_aggregate: str = "mean") -> tuple[tuple[str, str], ...]:
        """The quantities as `(name, aggregate)` pairs."""
        return tuple(parse_quantity(q, default_aggregate) for q in self.quantities)

    @property
    def weights(self) -> jnp.ndarray:
        """The scalarisations' weights $\\lambda_k$, shape (K, Q)."""
        return simplex_lattice(len(self.quantities), self.divisions)

    @property
    def slots(self) -> int:
        """K, the scalarisations (start slots)."""
        return int(self.weights.shape[0])

    @property
    def sqp(self) -> SwitchConfig:
        """The SQP's settings: one slot per scalarisation."""
        return SwitchConfig(starts=self.slots, iterations=self.iterations, margin=self.margin)


class ParetoState(eqx.Module):
    """The front search's state (a pytree; the run directory saves and restores it).

    Attributes:
        sqp: the SQP's slots (`SwitchState`), one per scalarisation.
        weights: $\\lambda$, shape (K, Q).
        ideal, span: $z$ and $w$ of the scaling (in the quantities' units); `scaled`:
            whether they are set (after the first iteration).
    """

    sqp: SwitchState
    weights: Float[Array, "K Q"]
    ideal: Float[Array, " Q"]
    span: Float[Array, " Q"]
    scaled: Bool[Array, ""]


def pareto_init(key, config: ParetoConfig, starts=None, dtype=jnp.float64) -> ParetoState:
    """The first state: one SQP slot per scalarisation at a Latin hypercube (the first rows
    replaced by `starts`, unit coordinates, where given)."""
    q = len(config.quantities)
    return ParetoState(sqp=switch_init(key, config.sqp, 0, starts, dtype), weights=config.weights.astype(dtype),
                       ideal=jnp.zeros(q, dtype), span=jnp.ones(q, dtype), scaled=jnp.zeros((), bool))


def with_constraints(state: ParetoState, constraints: int) -> ParetoState:
    """The state with room for `constraints` switching functions per slot (set at the first
    step, from the objective's loads and samples)."""
    sqp = state.sqp
    k = sqp.x.shape[0]
    if sqp.c.shape[-1] == constraints:
        return state
    zeros = lambda *shape: jnp.zeros(shape, sqp.c.dtype)  # noqa: E731
    sqp = eqx.tree_at(lambda s: (s.c, s.a, s.multipliers), sqp,
                      (zeros(k, constraints), zeros(k, constraints, 6), zeros(k, constraints)))
    return eqx.tree_at(lambda s: s.sqp, state, sqp)


def pareto_values(objective: Objective, space: DesignSpace, units, quantities: tuple[tuple[str, str], ...]):
    """The quantities' aggregates (their units, signed by `Quantity.sense`; $+\\infty$ where a
    stage failed; the impact's of the flank branch where an impact quantity is traded) and
    their Jacobian in unit coordinates, the switching functions $s$ (mm, flattened over loads
    and samples; ones where no impact quantity is traded) and their Jacobian, and the
    quantities with the impact of the regime that strikes first (`Evaluation.actual`), at
    unit-cube points of shape (K, 6): `(q (K, Q), dq (K, Q, 6), s (K, m), ds (K, m, 6),
    actual (K, Q))`, one program."""
    return _values_jit(objective, space, jnp.asarray(units, objective.torques.dtype), quantities)


@eqx.filter_jit
def _values_jit(objective, space, units, quantities):
    flank = any(name in IMPACT_QUANTITIES for name, _ in quantities)
    count = len(quantities)

    def aggregates(evaluation):
        q = jnp.stack([objective.aggregated(evaluation, name, aggregate) for name, aggregate in quantities])
        return jnp.where(evaluation.failed == 0, q, jnp.inf)

    def values(x):
        evaluation = objective.evaluate(space.to_design(x), flank_branch=flank, actual=flank)
        q = aggregates(evaluation)
        switch = evaluation.switch if flank else jnp.ones_like(evaluation.force)
        out = jnp.concatenate([q, switch.reshape(-1)])
        return out, (out, aggregates(evaluation.actual()))

    def one(x):
        jacobian, (out, actual) = jax.jacfwd(values, has_aux=True)(x)
        return out[:count], jacobian[:count], out[count:], jacobian[count:], actual

    return jax.lax.map(one, units, batch_size=objective.map_batch_size)


def scalarised(q, dq, weights, ideal, span, config: ParetoConfig):
    """$J_k$ and its gradient for one slot from its quantities `q` (Q,) and their Jacobian
    `dq` (Q, 6): the smoothed augmented Chebyshev function of the module."""
    used = weights > 0  # a quantity of weight 0 (also where it failed) does not enter
    q, dq = jnp.where(used, q, ideal), jnp.where(used[:, None], dq, 0.0)
    scaled = weights * (q - ideal) / span
    tau, rho = config.temperature, config.augmentation
    J = 1.0 + tau * jax.nn.logsumexp(scaled / tau) + rho * jnp.sum(scaled)
    coefficient = (jax.nn.softmax(scaled / tau) + rho) * weights / span
    return jnp.where(jnp.all(jnp.isfinite(q)), J, jnp.inf), coefficient @ dq


def pareto_update(state: ParetoState, values, config: ParetoConfig) -> ParetoState:
    """One iteration of every slot from `pareto_values` at its trial point; the first sets
    the scaling from the batch's finite values."""
    q, dq, s, ds = values[:4]
    finite = jnp.all(jnp.isfinite(q), axis=-1, keepdims=True)
    low = jnp.min(jnp.where(finite, q, jnp.inf), axis=0)
    high = jnp.max(jnp.where(finite, q, -jnp.inf), axis=0)
    ok = jnp.any(finite)
    width = jnp.where(ok, jnp.maximum(high - low, 1e-6 * jnp.maximum(jnp.abs(high), 1e-12)), 1.0)
    first = ~state.scaled & ok
    ideal = jnp.where(first, low - 0.1 * width, state.ideal)
    span = jnp.where(first, width, state.span)
    J, dJ = jax.vmap(scalarised, in_axes=(0, 0, 0, None, None, None))(q, dq, state.weights, ideal, span, config)
    # a slot whose J_k has no impact quantity does not keep to the flank side
    impact = jnp.asarray([name in IMPACT_QUANTITIES for name, _ in config.parsed()])
    free = ~jnp.any((state.weights > 0) & impact, axis=-1)
    s, ds = jnp.where(free[:, None], jnp.ones_like(s), s), jnp.where(free[:, None, None], 0.0, ds)
    sqp = switch_update(state.sqp, (J, dJ, s, ds), config.sqp)
    return ParetoState(sqp=sqp, weights=state.weights, ideal=ideal, span=span, scaled=state.scaled | ok)
