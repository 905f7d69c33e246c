r"""CMA-ES on the unit cube, in the optax style.

Pure functions on a pytree state: `cma_init`, `cma_ask`, `cma_tell`. The algorithm is the
$(\mu/\mu_w, \lambda)$ covariance matrix adaptation evolution strategy with cumulative
step-size adaptation, rank-one and rank-$\mu$ updates and the default parameters of
Hansen, *The CMA Evolution Strategy: A Tutorial* (arXiv:1604.00772, 2016), Table 1 and
Appendix A, positive weights only:

* sampling: $x_k = m + \sigma B D z_k$, $z_k \sim \mathcal N(0, I)$, $C = B D^2 B^T$;
* selection: the $\mu = \lfloor\lambda/2\rfloor$ best, weights
  $w_i \propto \ln\frac{\lambda + 1}{2} - \ln i$, $\sum w_i = 1$, $\mu_\text{eff} = 1/\sum w_i^2$;
* mean: $m \leftarrow m + \sigma \sum w_i y_{i:\lambda}$, $y = (x - m)/\sigma$;
* step size: $p_\sigma \leftarrow (1 - c_\sigma) p_\sigma + \sqrt{c_\sigma(2 - c_\sigma)\mu_\text{eff}}\,
  C^{-1/2} \langle y\rangle_w$, $\sigma \leftarrow \sigma \exp\bigl(\frac{c_\sigma}{d_\sigma}
  (\lVert p_\sigma\rVert / E\lVert\mathcal N(0, I)\rVert - 1)\bigr)$;
* covariance: $p_c \leftarrow (1 - c_c) p_c + h_\sigma\sqrt{c_c(2 - c_c)\mu_\text{eff}}\,\langle y\rangle_w$,
  $C \leftarrow (1 + c_1\delta(h_\sigma) - c_1 - c_\mu) C + c_1 p_c p_c^T + c_\mu \sum w_i y_{i:\lambda} y_{i:\lambda}^T$.

**Bounds.** The search runs on an unbounded genotype; each candidate is evaluated at its
image in $[0, 1]^d$ under pycma's default boundary transformation
(`cma.transformations.BoxConstraintsLinQuadTransformation`): periodic, the identity on
$[a, 1 - a]$, quadratic on the margins ($a$ = 0.05), mirrored beyond, so that every
evaluated design lies within the bounds and a bound itself is reached by a neighbourhood
of genotypes (the optima of seed 001's design space sit on four of its six bounds).

**Restarts.** When $\sigma\sqrt{\lambda_\max(C)}$ falls below `tolerance` (unit-cube
coordinates), the distribution starts again from a new uniform mean with $\sigma_0$ and
$C = I$: the budget left goes to another basin, not to digits the objective's accuracy
does not resolve.

Everything is `jit`-able and a run is reproducible bit for bit from its seed: the random
key is part of the state. Lower is better; NaN counts as $+\infty$.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, Float, Int, Scalar
from .._validate import check_int, check_range

#: width of the quadratic margins of the boundary transformation (unit cube), pycma's
#: `linquad_margin_width` for bounds 0 and 1
MARGIN = 0.05


class CMAConfig(eqx.Module):
    """Static settings of CMA-ES.

    Attributes:
        population: candidates per generation $\\lambda$ (>= 4).
        sigma0: initial step size $\\sigma_0$ (unit-cube coordinates), in (0, 1].
        tolerance: restart once $\\sigma\\sqrt{\\lambda_\\max(C)}$ is below it (unit cube), >= 0.
    """

    population: int = eqx.field(static=True, default=10)
    sigma0: float = eqx.field(static=True, default=0.3)
    tolerance: float = eqx.field(static=True, default=1e-4)

    def __check_init__(self):
        check_int("population", self.population, 4)
        check_range("sigma0", self.sigma0, 0.0, 1.0, low_inclusive=False)
        check_range("tolerance", self.tolerance, 0.0, None)


class CMAState(eqx.Module):
    """State of a CMA-ES run (a pytree; saved and restored by the run directory).

    Attributes:
        key: the random key.
        generation: generations told so far; `restarts` the restarts so far.
        mean, sigma, covariance, path_sigma, path_c: the distribution (genotype).
        genotypes: the last candidates asked, before the boundary transformation, (P, d).
        population, fitness: the last candidates told (unit cube) and their fitness.
        best: the best candidate found so far (unit cube), and `best_fitness` its fitness.
    """

    key: Array
    generation: Int[Array, ""]
    restarts: Int[Array, ""]
    mean: Float[Array, " d"]
    sigma: Scalar
    covariance: Float[Array, "d d"]
    path_sigma: Float[Array, " d"]
    path_c: Float[Array, " d"]
    genotypes: Float[Array, "P d"]
    population: Float[Array, "P d"]
    fitness: Float[Array, " P"]
    best: Float[Array, " d"]
    best_fitness: Scalar


def to_unit_cube(x: Array) -> Array:
    """pycma's lin-quad boundary transformation onto $[0, 1]$, elementwise: shifted by its
    period $2(1 + 2a)$ into $[-\\tfrac12 - 2a, \\tfrac32 + 2a]$, mirrored at $-a$ and
    $1 + a$, then $(x + a)^2/4a$ below $a$, $x$ up to $1 - a$, $1 - (x - 1 - a)^2/4a$ above."""
    a = MARGIN
    period, start = 2.0 * (1.0 + 2.0 * a), -0.5 - 2.0 * a
    x = x - period * jnp.floor((x - start) / period)
    x = jnp.where(x > 1.0 + a, 2.0 * (1.0 + a) - x, x)
    x = jnp.where(x < -a, -2.0 * a - x, x)
    return jnp.where(x < a, (x + a) ** 2 / (4.0 * a), jnp.where(x < 1.0 - a, x, 1.0 - (x - 1.0 - a) ** 2 / (4.0 * a)))


def from_unit_cube(u: Array) -> Array:
    """The genotype in $[-a, 1 + a]$ that `to_unit_cube` maps onto `u` (in $[0, 1]$)."""
    a = MARGIN
    u = jnp.clip(u, 0.0, 1.0)
    return jnp.where(u < a, jnp.sqrt(4.0 * a * u) - a, jnp.where(u < 1.0 - a, u, 1.0 + a - jnp.sqrt(4.0 * a * (1.0 - u))))


def _weights(population: int):
    """Hansen's positive recombination weights (mu,) and $\\mu_\\text{eff}$."""
    mu = population // 2
    raw = [math.log((population + 1) / 2) - math.log(i + 1) for i in range(mu)]
    weights = [w / sum(raw) for w in raw]
    return weights, 1.0 / sum(w * w for w in weights)


def _rates(population: int, dimension: int) -> dict[str, float]:
    """The learning rates and damping of Hansen's Table 1 ($\\alpha_\\mu$ = 2)."""
    n = dimension
    _, mu_eff = _weights(population)
    c_sigma = (mu_eff + 2) / (n + mu_eff + 5)
    c_1 = 2 / ((n + 1.3) ** 2 + mu_eff)
    return {
        "c_sigma": c_sigma,
        "d_sigma": 1 + 2 * max(0.0, math.sqrt((mu_eff - 1) / (n + 1)) - 1) + c_sigma,
        "c_c": (4 + mu_eff / n) / (n + 4 + 2 * mu_eff / n),
        "c_1": c_1,
        "c_mu": min(1 - c_1, 2 * (mu_eff - 2 + 1 / mu_eff) / ((n + 2) ** 2 + mu_eff)),
        "chi_n": math.sqrt(n) * (1 - 1 / (4 * n) + 1 / (21 * n * n)),
        "mu_eff": mu_eff,
    }


def _fresh(key: Array, config: CMAConfig, state: CMAState) -> CMAState:
    """`state` with a new distribution: a uniform mean in $[0.2, 0.8]^d$, $\\sigma_0$, $C = I$."""
    d = state.mean.shape[0]
    mean = jax.random.uniform(key, (d,), state.mean.dtype, 0.2, 0.8)
    eye = jnp.eye(d, dtype=mean.dtype)
    zero = jnp.zeros_like(mean)
    return eqx.tree_at(lambda s: (s.mean, s.sigma, s.covariance, s.path_sigma, s.path_c), state,
                       (mean, jnp.asarray(config.sigma0, mean.dtype), eye, zero, zero))


def cma_init(key: Array, config: CMAConfig, dimension: int, initial: Array | None = None) -> CMAState:
    """The state before the first generation: the mean uniform in $[0.2, 0.8]^d$, or at
    `initial` (unit coordinates, shape (d,) or (m, d): its first row) when given."""
    key, sub = jax.random.split(key)
    zeros = jnp.zeros((config.population, dimension))
    inf = jnp.full((config.population,), jnp.inf)
    state = CMAState(key, jnp.zeros((), jnp.int32), jnp.zeros((), jnp.int32), zeros[0], jnp.asarray(config.sigma0),
                     jnp.eye(dimension), zeros[0], zeros[0], zeros, zeros, inf, zeros[0], jnp.asarray(jnp.inf))
    state = _fresh(sub, config, state)
    if initial is not None:
        initial = jnp.atleast_2d(jnp.asarray(initial, state.mean.dtype))
        if initial.shape[1] != dimension:
            raise ValueError(f"initial designs must have shape (m, {dimension}); got {initial.shape}")
        state = eqx.tree_at(lambda s: s.mean, state, from_unit_cube(initial[0]))
    return state


def cma_ask(state: CMAState, config: CMAConfig) -> tuple[Float[Array, "P d"], CMAState]:
    """The next `population` candidates to evaluate (unit coordinates, within the bounds)
    and the new state (its key, and the candidates' genotypes for `cma_tell`)."""
    key, sub = jax.random.split(state.key)
    eigenvalues, basis = jnp.linalg.eigh(state.covariance)
    scale = jnp.sqrt(jnp.maximum(eigenvalues, 0.0))
    z = jax.random.normal(sub, (config.population, state.mean.shape[0]), state.mean.dtype)
    genotypes = state.mean + state.sigma * (z * scale) @ basis.T
    return to_unit_cube(genotypes), eqx.tree_at(lambda s: (s.key, s.genotypes), state, (key, genotypes))


def cma_tell(state: CMAState, candidates: Float[Array, "P d"], fitness: Float[Array, " P"],
             config: CMAConfig) -> CMAState:
    """Take the fitness of the candidates `cma_ask` returned (lower is better) and update
    the distribution (module docstring); restart it once it has collapsed below
    `config.tolerance`."""
    fitness = jnp.where(jnp.isnan(fitness), jnp.inf, fitness)
    n = state.mean.shape[0]
    r = _rates(config.population, n)
    weights, _ = _weights(config.population)
    w = jnp.asarray(weights, state.mean.dtype)
    order = jnp.argsort(fitness, stable=True)[: w.shape[0]]
    y = (state.genotypes[order] - state.mean) / state.sigma  # (mu, d)
    y_w = w @ y
    mean = state.mean + state.sigma * y_w
    eigenvalues, basis = jnp.linalg.eigh(state.covariance)
    inverse_sqrt = (basis / jnp.sqrt(jnp.maximum(eigenvalues, 1e-300))) @ basis.T
    c_sigma, c_c, c_1, c_mu = r["c_sigma"], r["c_c"], r["c_1"], r["c_mu"]
    path_sigma = (1 - c_sigma) * state.path_sigma + math.sqrt(c_sigma * (2 - c_sigma) * r["mu_eff"]) * inverse_sqrt @ y_w
    norm = jnp.linalg.norm(path_sigma)
    generations = (state.generation + 1).astype(mean.dtype)
    h_sigma = norm / jnp.sqrt(1 - (1 - c_sigma) ** (2 * generations)) < (1.4 + 2 / (n + 1)) * r["chi_n"]
    path_c = (1 - c_c) * state.path_c + jnp.where(h_sigma, math.sqrt(c_c * (2 - c_c) * r["mu_eff"]), 0.0) * y_w
    delta = jnp.where(h_sigma, 0.0, c_c * (2 - c_c))
    covariance = ((1 + c_1 * delta - c_1 - c_mu) * state.covariance + c_1 * jnp.outer(path_c, path_c)
                  + c_mu * (y.T * w) @ y)
    covariance = (covariance + covariance.T) / 2
    sigma = state.sigma * jnp.exp(c_sigma / r["d_sigma"] * (norm / r["chi_n"] - 1))
    i = jnp.argmin(fitness)
    better = fitness[i] < state.best_fitness
    new = eqx.tree_at(
        lambda s: (s.generation, s.mean, s.sigma, s.covariance, s.path_sigma, s.path_c, s.population, s.fitness,
                   s.best, s.best_fitness),
        state,
        (state.generation + 1, mean, sigma, covariance, path_sigma, path_c, candidates, fitness,
         jnp.where(better, candidates[i], state.best), jnp.where(better, fitness[i], state.best_fitness)),
    )
    collapsed = sigma * jnp.sqrt(jnp.max(jnp.linalg.eigvalsh(covariance))) < config.tolerance
    key, sub = jax.random.split(new.key)
    restarted = eqx.tree_at(lambda s: (s.key, s.restarts), _fresh(sub, config, new), (key, new.restarts + 1))
    return jax.tree_util.tree_map(lambda a, b: jnp.where(collapsed, a, b), restarted, new)
