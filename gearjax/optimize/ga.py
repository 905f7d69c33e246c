r"""A compact genetic algorithm on the unit cube, in the optax style.

Pure functions on a pytree state: `ga_init`, `ga_ask`, `ga_tell`. The algorithm is seed
001's choice (a real-coded GA) with the textbook operators:

* **selection**: binary tournaments ($k$ = `tournament` members drawn with replacement,
  the fittest wins);
* **crossover**: blend crossover BLX-$\alpha$ (Eshelman & Schaffer 1993): each gene of the
  child is drawn uniformly from $[\min - \alpha d, \max + \alpha d]$ of the parents' genes,
  $d = |x_a - x_b|$, with probability `crossover_rate` (else the first parent's gene);
* **mutation**: Gaussian, $x \leftarrow x + \sigma\,\mathcal N(0, 1)$ per gene with
  probability `mutation_rate` ($\sigma$ in unit-cube coordinates);
* **bounds**: every child is clipped to $[0, 1]^d$ (projection onto the box), so every
  evaluated design lies within the design space's bounds;
* **elitism**: the next population is the `elite` fittest of the current one plus the
  fittest `population - elite` children ($(\mu + \lambda)$-style truncation), so the best
  value never gets worse from one generation to the next.

Each generation asks for `population` candidates (the first one returns the initial
sample, uniform in the cube, optionally with given designs in its first rows) and is told
their fitness (lower is better; NaN counts as $+\infty$). Everything is `jit`-able and a
run is reproducible bit for bit from its seed: the random key is part of the state.

Why not evosax: its `SimpleGA` would serve, but it brings about 20 packages (flax,
orbax-checkpoint, tensorstore, protobuf, ...) for these forty lines, has no bounds (its
mutation scale is in raw units) and re-evaluates nothing we could not do here.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, Float, Int, Scalar
from .._validate import check_int, check_range


class GAConfig(eqx.Module):
    """Static settings of the genetic algorithm.

    Attributes:
        population: members per generation (>= 2; seed 001: 40).
        elite: members carried over unchanged (0 <= elite < population).
        tournament: tournament size $k$ (>= 1).
        crossover_rate: probability of blending a gene, in [0, 1].
        blend: $\\alpha$ of BLX-$\\alpha$, >= 0.
        mutation_rate: probability of mutating a gene, in [0, 1].
        mutation_scale: $\\sigma$ of the Gaussian mutation (unit-cube coordinates), >= 0.
    """

    population: int = eqx.field(static=True, default=40)
    elite: int = eqx.field(static=True, default=2)
    tournament: int = eqx.field(static=True, default=3)
    crossover_rate: float = eqx.field(static=True, default=0.9)
    blend: float = eqx.field(static=True, default=0.5)
    mutation_rate: float = eqx.field(static=True, default=0.2)
    mutation_scale: float = eqx.field(static=True, default=0.1)

    def __check_init__(self):
        check_int("population", self.population, 2)
        check_int("elite", self.elite, 0, self.population - 1)
        check_int("tournament", self.tournament, 1)
        check_range("crossover_rate", self.crossover_rate, 0.0, 1.0)
        check_range("blend", self.blend, 0.0, None)
        check_range("mutation_rate", self.mutation_rate, 0.0, 1.0)
        check_range("mutation_scale", self.mutation_scale, 0.0, None)


class GAState(eqx.Module):
    """State of a GA run (a pytree; saved and restored by the run directory).

    Attributes:
        key: the random key.
        generation: generations told so far.
        population: current members (unit-cube coordinates), shape (P, d).
        fitness: their fitness (lower is better; $+\\infty$ before the first `ga_tell`).
        best: the best member found so far, and `best_fitness` its fitness.
    """

    key: Array
    generation: Int[Array, ""]
    population: Float[Array, "P d"]
    fitness: Float[Array, " P"]
    best: Float[Array, " d"]
    best_fitness: Scalar


def ga_init(key: Array, config: GAConfig, dimension: int, initial: Array | None = None) -> GAState:
    """The state before the first generation: a uniform sample of the unit cube, whose
    first rows are replaced by `initial` (unit coordinates, shape (m, d), m <= population)
    when given (e.g. the scene's current design)."""
    key, sub = jax.random.split(key)
    population = jax.random.uniform(sub, (config.population, dimension))
    if initial is not None:
        initial = jnp.clip(jnp.atleast_2d(jnp.asarray(initial, population.dtype)), 0.0, 1.0)
        if initial.shape[0] > config.population or initial.shape[1] != dimension:
            raise ValueError(f"initial designs must have shape (m <= {config.population}, {dimension}); got {initial.shape}")
        population = population.at[: initial.shape[0]].set(initial)
    inf = jnp.full((config.population,), jnp.inf, population.dtype)
    return GAState(key, jnp.zeros((), jnp.int32), population, inf, population[0], jnp.asarray(jnp.inf, population.dtype))


def _children(key: Array, state: GAState, config: GAConfig) -> Float[Array, "P d"]:
    size, dimension = state.population.shape
    k_sel, k_cross, k_blend, k_mut, k_gauss = jax.random.split(key, 5)
    contenders = jax.random.randint(k_sel, (2, size, config.tournament), 0, size)
    winners = jnp.take_along_axis(
        contenders, jnp.argmin(state.fitness[contenders], axis=-1)[..., None], axis=-1
    )[..., 0]
    first, second = state.population[winners[0]], state.population[winners[1]]
    low, high = jnp.minimum(first, second), jnp.maximum(first, second)
    spread = config.blend * (high - low)
    blended = jax.random.uniform(k_blend, first.shape, minval=low - spread, maxval=high + spread)
    cross = jax.random.bernoulli(k_cross, config.crossover_rate, first.shape)
    child = jnp.where(cross, blended, first)
    mutate = jax.random.bernoulli(k_mut, config.mutation_rate, child.shape)
    child = child + jnp.where(mutate, config.mutation_scale * jax.random.normal(k_gauss, child.shape), 0.0)
    return jnp.clip(child, 0.0, 1.0)


def ga_ask(state: GAState, config: GAConfig) -> tuple[Float[Array, "P d"], GAState]:
    """The next `population` candidates to evaluate (unit coordinates) and the new state:
    the initial sample at generation 0, else children of the current population."""
    key, sub = jax.random.split(state.key)
    candidates = jax.lax.cond(
        state.generation == 0, lambda: state.population, lambda: _children(sub, state, config)
    )
    return candidates, eqx.tree_at(lambda s: s.key, state, key)


def ga_tell(state: GAState, candidates: Float[Array, "P d"], fitness: Float[Array, " P"], config: GAConfig) -> GAState:
    """Take the candidates' fitness (lower is better): the new population is the `elite`
    best of the current one and the best children (all candidates at generation 0)."""
    fitness = jnp.where(jnp.isnan(fitness), jnp.inf, fitness)
    size = config.population
    order = jnp.argsort(state.fitness)[: config.elite]
    pool = jnp.concatenate([state.population[order], candidates])
    pool_fitness = jnp.concatenate([state.fitness[order], fitness])
    # At generation 0 the old population is the candidates themselves (fitness +inf), so
    # the truncation below keeps every candidate once.
    keep = jnp.argsort(pool_fitness, stable=True)[:size]
    first = state.generation == 0
    population = jnp.where(first, candidates, pool[keep])
    new_fitness = jnp.where(first, fitness, pool_fitness[keep])
    i = jnp.argmin(new_fitness)
    better = new_fitness[i] < state.best_fitness
    return GAState(
        state.key,
        state.generation + 1,
        population,
        new_fitness,
        jnp.where(better, population[i], state.best),
        jnp.where(better, new_fitness[i], state.best_fitness),
    )
