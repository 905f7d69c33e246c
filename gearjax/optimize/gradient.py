r"""Projected gradient descent (Adam) from several starts at once, in unit-cube coordinates.

Each start $x_k \in [0, 1]^6$ takes Adam steps (optax) on $J(y(x))$ and is projected back
onto the box after each step (`optax.projections.projection_box`, i.e. clipping), so
every evaluated design lies within the bounds. The starts are a Latin hypercube sample
(one stratum per start and parameter), and all starts are evaluated together: one
compiled call of `Objective`'s value and gradient per iteration.

**Kinks.** $J$ is piecewise smooth: it kinks where the mesh-in regime switches (surface
$\leftrightarrow$ edge contact) and where the binding candidate or the LTCA's active set
changes. The gradient there is the one-sided gradient of the branch that binds; Adam's
normalised steps do not blow up at such a kink, and because each start keeps its best
point, a step that crosses into a worse branch costs an evaluation, not the progress.
A design whose evaluation fails (objective $+\infty$, non-finite gradient) is not
stepped from: the start moves halfway back to its best point (towards the centre of the
box if it has none yet).

**Gaussian smoothing** (`GradientConfig.smoothing` $\sigma_0 > 0$). The step follows the
gradient of the smoothed objective $J_\sigma(x) = \mathrm E_\varepsilon[J(x + \sigma\varepsilon)]$,
$\varepsilon \sim N(0, I)$, estimated from the start's own point and `smoothing_pairs`
antithetic pairs $x \pm \sigma\varepsilon_j$ (clipped to the box) as the mean of the
objective's gradients there, $\nabla J_\sigma(x) = \mathrm E[\nabla J(x + \sigma\varepsilon)]$
(Nesterov & Spokoiny 2017 for the smoothing). Every start of an iteration sees the same
$\varepsilon_j$ (common random numbers), drawn afresh each iteration. $\sigma$ decays
linearly from $\sigma_0$ towards 0 over `iterations` ($\sigma_0/$`iterations` at the last),
so the search first averages over the kinks and wiggles of $J$ within $\sigma$ and ends
nearly on $J$ itself. The best point and the
step-length test use $J$ at the start's own point; the stall test is off (while $\sigma$ is
large, $J$ there need not improve), so a start runs its `iterations` unless its step
vanishes. Each iteration evaluates $1 + 2\,$`smoothing_pairs` designs per start.

**Stopping.** A start stops when its best value has not improved by more than `ftol`
(relative) for `patience` iterations (not with smoothing), or when its projected step is shorter than `xtol`
(unit coordinates); the run stops when every start has stopped (`converged`), or after
`iterations`.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import optax

from .._custom_types import Array, Bool, Float, Int
from .._validate import check_int, check_range


class GradientConfig(eqx.Module):
    r"""Static settings of the multi-start projected Adam.

    Attributes:
        starts: number of starts run together (>= 1; default 10).
        iterations: cap on the iterations (>= 1; default 100: with 10 starts about the
            GA's default budget of 40 x 30 evaluations, a value and gradient costing
            1.2-1.3 forward evaluations).
        learning_rate: Adam's initial step size in unit-cube coordinates (> 0), decaying
            to 1 % of it over `iterations` (cosine schedule).
        ftol: relative improvement of a start's best value below which it counts as stalled.
        patience: stalled iterations after which a start stops (>= 1).
        xtol: projected step length (unit coordinates) below which a start stops.
        smoothing: $\sigma_0$ of the Gaussian smoothing (unit coordinates, 0 to 0.5); 0
            (default) follows the gradient of the objective itself.
        smoothing_pairs: antithetic sample pairs per start and iteration when smoothing
            (>= 1).
    """

    starts: int = eqx.field(static=True, default=10)
    iterations: int = eqx.field(static=True, default=100)
    learning_rate: float = eqx.field(static=True, default=0.05)
    ftol: float = eqx.field(static=True, default=1e-3)
    patience: int = eqx.field(static=True, default=12)
    xtol: float = eqx.field(static=True, default=1e-4)
    smoothing: float = eqx.field(static=True, default=0.0)
    smoothing_pairs: int = eqx.field(static=True, default=2)

    def __check_init__(self):
        check_int("starts", self.starts, 1)
        check_int("iterations", self.iterations, 1)
        check_range("learning_rate", self.learning_rate, 0.0, 1.0, low_inclusive=False)
        check_range("ftol", self.ftol, 0.0, 1.0)
        check_int("patience", self.patience, 1)
        check_range("xtol", self.xtol, 0.0, 1.0)
        check_range("smoothing", self.smoothing, 0.0, 0.5)
        check_int("smoothing_pairs", self.smoothing_pairs, 1)

    @property
    def samples(self) -> int:
        """Designs evaluated per start and iteration: 1, or 1 + 2 `smoothing_pairs`."""
        return 1 + 2 * self.smoothing_pairs if self.smoothing > 0.0 else 1

    def optimizer(self) -> optax.GradientTransformation:
        """Adam with the step size decaying from `learning_rate` to 1 % of it over
        `iterations` (cosine): constant-step Adam only settles to within about one step of
        a minimum."""
        return optax.adam(optax.cosine_decay_schedule(self.learning_rate, self.iterations, alpha=0.01))


class GradientState(eqx.Module):
    """State of a multi-start run (a pytree; saved and restored by the run directory).

    Attributes:
        iteration: iterations done.
        position: current point of each start (unit coordinates), shape (K, d).
        opt_state: Adam's state.
        best: best point of each start, and `best_value` its objective.
        stalled: iterations since each start last improved by more than `ftol`.
        active: the start has not stopped.
        key: the run's random key (the smoothing's samples).
    """

    iteration: Int[Array, ""]
    position: Float[Array, "K d"]
    opt_state: optax.OptState
    best: Float[Array, "K d"]
    best_value: Float[Array, " K"]
    stalled: Int[Array, " K"]
    active: Bool[Array, " K"]
    key: Array


def latin_hypercube(key: Array, count: int, dimension: int) -> Float[Array, "count dimension"]:
    """`count` points in $[0, 1]^d$, one in each of `count` equal strata per coordinate
    (McKay, Beckman & Conover 1979)."""
    k_perm, k_jitter = jax.random.split(key)
    perms = jax.vmap(lambda k: jax.random.permutation(k, count))(jax.random.split(k_perm, dimension)).T
    jitter = jax.random.uniform(k_jitter, (count, dimension))
    return (perms.astype(jitter.dtype) + jitter) / count


def gradient_init(key: Array, config: GradientConfig, dimension: int, initial: Array | None = None) -> GradientState:
    """Starts from a Latin hypercube sample; its first rows replaced by `initial` (unit
    coordinates, shape (m, d)) when given."""
    position = latin_hypercube(key, config.starts, dimension)
    if initial is not None:
        initial = jnp.clip(jnp.atleast_2d(jnp.asarray(initial, position.dtype)), 0.0, 1.0)
        if initial.shape[0] > config.starts or initial.shape[1] != dimension:
            raise ValueError(f"initial designs must have shape (m <= {config.starts}, {dimension}); got {initial.shape}")
        position = position.at[: initial.shape[0]].set(initial)
    k = config.starts
    return GradientState(
        jnp.zeros((), jnp.int32),
        position,
        config.optimizer().init(position),
        position,
        jnp.full((k,), jnp.inf, position.dtype),
        jnp.zeros((k,), jnp.int32),
        jnp.ones((k,), bool),
        key,
    )


def sample_positions(state: GradientState, config: GradientConfig) -> Float[Array, "K M d"]:
    r"""The designs to evaluate this iteration (unit coordinates), `config.samples` per start:
    the start's point, then with smoothing its antithetic pairs $x \pm \sigma\varepsilon_j$
    clipped to the box ($\sigma = \sigma_0(1 - i/$`iterations`$)$ at iteration $i$, so
    $\sigma_0/$`iterations` at the last; the same $\varepsilon_j$ for every start)."""
    position = state.position[:, None, :]
    if config.samples == 1:
        return position
    fraction = 1.0 - state.iteration.astype(position.dtype) / config.iterations
    sigma = config.smoothing * jnp.maximum(fraction, 0.0)
    eps = jax.random.normal(jax.random.fold_in(state.key, state.iteration),
                            (config.smoothing_pairs, position.shape[-1]), position.dtype)
    offsets = jnp.concatenate([jnp.zeros_like(eps[:1]), sigma * eps, -sigma * eps])
    return jnp.clip(position + offsets[None], 0.0, 1.0)


def smoothed(values: Float[Array, "K M"], grads: Float[Array, "K M d"]) -> tuple[Float[Array, " K"], Float[Array, "K d"]]:
    """Each start's objective at its own point (sample 0) and the mean gradient over its
    samples whose value and gradient are finite (NaN where none is): the smoothed
    objective's gradient estimate for `gradient_step`."""
    ok = jnp.isfinite(values) & jnp.all(jnp.isfinite(grads), axis=-1)
    count = jnp.sum(ok, axis=1)
    total = jnp.sum(jnp.where(ok[..., None], grads, 0.0), axis=1)
    grad = jnp.where(count[:, None] > 0, total / jnp.maximum(count, 1)[:, None].astype(total.dtype), jnp.nan)
    return values[:, 0], grad


def gradient_step(state: GradientState, value: Float[Array, " K"], grad: Float[Array, "K d"], config: GradientConfig) -> GradientState:
    """Take the objective and its gradient (unit coordinates) at `state.position` and move
    every active start: bookkeeping of the best point, an Adam step projected onto the box,
    and the stopping tests."""
    ok = jnp.isfinite(value) & jnp.all(jnp.isfinite(grad), axis=-1)
    improved = ok & (value < state.best_value)
    significant = ok & (value < state.best_value - config.ftol * jnp.abs(state.best_value))
    best = jnp.where(improved[:, None], state.position, state.best)
    best_value = jnp.where(improved, value, state.best_value)
    stalled = jnp.where(significant | ~jnp.isfinite(state.best_value), 0, state.stalled + 1)
    # optax's bias correction raises a float to an int32 step count, which JAX's strict
    # dtype promotion (a user setting) would refuse.
    with jax.numpy_dtype_promotion("standard"):
        updates, opt_state = config.optimizer().update(jnp.where(ok[:, None], grad, 0.0), state.opt_state, state.position)
    stepped = optax.projections.projection_box(optax.apply_updates(state.position, updates), 0.0, 1.0)
    # A start that has never had a finite value has no best point: it moves towards the
    # centre of the box instead.
    anchor = jnp.where(jnp.isfinite(best_value)[:, None], best, 0.5)
    retreat = 0.5 * (state.position + anchor)
    moved = jnp.where(ok[:, None], stepped, retreat)
    step = jnp.linalg.norm(moved - state.position, axis=-1)
    # With smoothing, J at the start's point need not improve while sigma is large: no
    # stall test, the run follows its sigma schedule.
    patient = (stalled < config.patience) | (config.smoothing > 0.0)
    active = state.active & patient & ~(ok & (step < config.xtol))
    position = jnp.where(state.active[:, None], moved, state.position)
    return GradientState(state.iteration + 1, position, opt_state, best, best_value, stalled, active, state.key)
