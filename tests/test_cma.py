"""gearjax.optimize.cma: CMA-ES on analytic functions (no gear program is compiled here)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gearjax import optimize as go
from gearjax.optimize.cma import MARGIN, from_unit_cube, to_unit_cube

#: a rotation of the 6-D unit cube's coordinates (fixed), for a non-separable ellipsoid
ROTATION = np.linalg.qr(np.random.default_rng(0).normal(size=(6, 6)))[0]
SCALES = 10.0 ** np.arange(6)  # condition number 1e5


def _run(f, config, generations, seed=0):
    ask = jax.jit(lambda s: go.cma_ask(s, config))
    tell = jax.jit(lambda s, c, v: go.cma_tell(s, c, v, config))
    state = go.cma_init(jax.random.PRNGKey(seed), config, 6)
    asked = []
    for _ in range(generations):
        candidates, state = ask(state)
        asked.append(np.asarray(candidates))
        state = tell(state, candidates, f(candidates))
    return state, np.array(asked)


@settings(max_examples=200, deadline=None)
@given(st.floats(-50.0, 50.0, allow_nan=False))
def test_the_boundary_transformation_is_periodic_bounded_and_the_identity_inside(x):
    y = float(to_unit_cube(jnp.asarray(x)))
    assert 0.0 <= y <= 1.0
    assert float(to_unit_cube(jnp.asarray(x + 2.0 * (1.0 + 2.0 * MARGIN)))) == pytest.approx(y, abs=1e-9)
    if MARGIN <= x <= 1.0 - MARGIN:
        assert y == x
    assert float(to_unit_cube(from_unit_cube(jnp.asarray(y)))) == pytest.approx(y, abs=1e-12)


def test_the_boundary_transformation_is_continuously_differentiable_and_reaches_the_bounds():
    """C¹ at the joints of its linear and quadratic pieces and at the mirror points; the
    bounds are its extrema (slope 0 there)."""
    slope = jax.vmap(jax.grad(to_unit_cube))
    joints = jnp.asarray([-MARGIN, MARGIN, 1.0 - MARGIN, 1.0 + MARGIN])
    h = 1e-7
    assert np.allclose(to_unit_cube(joints - h), to_unit_cube(joints + h), atol=1e-6)
    assert np.allclose(slope(joints - h), slope(joints + h), atol=1e-5)
    assert np.allclose(to_unit_cube(jnp.asarray([-MARGIN, 1.0 + MARGIN])), [0.0, 1.0], atol=0)
    assert np.allclose(slope(jnp.asarray([-MARGIN, 1.0 + MARGIN])), 0.0, atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_cma_es_solves_a_rotated_ill_conditioned_ellipsoid(seed):
    """Conditioning 1e5, rotated, the minimum inside the cube: the covariance must learn
    the Hessian's shape to get from O(1) to 1e-10 within 400 generations of 10 (Hansen's
    defaults need about 250 on the axis-parallel one; an isotropic search would need
    thousands)."""
    target = jnp.asarray([0.35, 0.6, 0.4, 0.55, 0.45, 0.5])

    def f(u):
        return jnp.sum(SCALES * jnp.square((u - target) @ ROTATION.T), axis=-1)

    state, asked = _run(f, go.CMAConfig(tolerance=0.0), 400, seed)
    assert float(state.best_fitness) < 1e-10
    assert np.max(np.abs(np.asarray(state.best) - np.asarray(target))) < 1e-3
    assert int(state.restarts) == 0


def test_cma_es_lands_on_the_bounds_and_asks_only_within_them():
    """The bowl of the GA's test, its centre beyond two bounds: every candidate lies in the
    cube, and the best reaches the clipped centre."""
    centre = jnp.asarray([0.3, 0.7, 0.5, 0.1, -0.2, 1.4])

    def f(u):
        return jnp.sum(jnp.square(u - centre), axis=-1)

    state, asked = _run(f, go.CMAConfig(tolerance=0.0), 150)
    assert asked.min() >= 0.0 and asked.max() <= 1.0
    assert np.max(np.abs(np.asarray(state.best) - np.clip(np.asarray(centre), 0.0, 1.0))) < 1e-4


def test_cma_es_starts_at_the_given_design_bounds_included():
    start = jnp.asarray([0.0, 1.0, 0.5, 0.02, 0.99, 0.3])
    state = go.cma_init(jax.random.PRNGKey(0), go.CMAConfig(), 6, start[None])
    assert np.allclose(to_unit_cube(state.mean), start, atol=1e-12, rtol=0)


def test_cma_es_is_reproducible_counts_nan_as_worst_and_restarts_once_collapsed():
    centre = jnp.full(6, 0.4)

    def f(u):  # NaN on a slab of the cube: those candidates rank last
        value = jnp.sum(jnp.square(u - centre), axis=-1)
        return jnp.where(u[:, 0] > 0.8, jnp.nan, value)

    a, _ = _run(f, go.CMAConfig(), 60, seed=3)
    b, _ = _run(f, go.CMAConfig(), 60, seed=3)
    assert all(np.array_equal(x, y) for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)))
    assert np.isfinite(float(a.best_fitness)) and float(a.best[0]) <= 0.8
    # a tolerance the distribution falls below within a few dozen generations: at the
    # generation it does, the distribution starts again from sigma0 and C = I
    config = go.CMAConfig(tolerance=0.05)
    state = go.cma_init(jax.random.PRNGKey(3), config, 6)
    for _ in range(200):
        candidates, state = go.cma_ask(state, config)
        before = state
        state = go.cma_tell(state, candidates, f(candidates), config)
        if int(state.restarts):
            break
    assert int(state.restarts) == 1 and int(state.generation) > 1
    assert float(before.sigma) * float(jnp.sqrt(jnp.max(jnp.linalg.eigvalsh(before.covariance)))) >= 0.05
    assert float(state.sigma) == 0.3 and np.array_equal(np.asarray(state.covariance), np.eye(6))
    assert not np.array_equal(np.asarray(state.mean), np.asarray(before.mean))
    assert float(state.best_fitness) <= float(before.best_fitness)


@pytest.mark.parametrize("kwargs, match", [({"population": 3}, "population"), ({"sigma0": 0.0}, "sigma0"),
                                            ({"sigma0": 1.5}, "sigma0"), ({"tolerance": -1.0}, "tolerance")])
def test_bad_cma_settings_are_rejected(kwargs, match):
    with pytest.raises(ValueError, match=match):
        go.CMAConfig(**kwargs)
