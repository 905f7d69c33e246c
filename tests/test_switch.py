"""The switching-aware SQP alone (`gearjax.optimize.switch`), on problems with known
answers: its quadratic subproblem and whole runs on smooth constrained programs."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gearjax import optimize as go
from gearjax.optimize.switch import _subproblem, switch_init, switch_update

_update = jax.jit(switch_update, static_argnums=2)


def _model(hessian, g, c, a, mu):
    return lambda d: 0.5 * d @ hessian @ d + g @ d + mu * jnp.sum(jnp.maximum(-(c + a @ d), 0.0))


def test_the_subproblem_step_is_the_minimum_of_the_l1_model_in_the_box():
    """The S-l1-QP model is convex: its minimiser over the box is lower than every point of
    the box near it and than the box's other points sampled; random problems with one to
    three constraints of the switching functions' scale (gradients tens of times the box)."""
    rng = np.random.default_rng(2)
    solve = jax.jit(_subproblem)
    for _ in range(12):
        m = int(rng.integers(1, 4))
        root = rng.normal(size=(6, 6))
        hessian = jnp.asarray(root @ root.T + 0.1 * np.eye(6)) * 10.0 ** rng.uniform(-1, 1)
        g, a, c = (jnp.asarray(v) for v in (3 * rng.normal(size=6), 20 * rng.normal(size=(m, 6)), 3 * rng.normal(size=m)))
        x, radius = rng.random(6), 10.0 ** rng.uniform(-2, 0)
        lower, upper = jnp.asarray(np.maximum(-radius, -x)), jnp.asarray(np.minimum(radius, 1.0 - x))
        d, multipliers = solve(hessian, g, c, a, lower, upper, 10.0)
        model = jax.vmap(_model(hessian, g, c, a, 10.0))
        assert bool(jnp.all((d >= lower) & (d <= upper))) and bool(jnp.all((multipliers >= 0) & (multipliers <= 10)))
        scale = float(jnp.max(upper - lower))
        near = jnp.clip(d + scale * jnp.asarray(rng.normal(size=(2000, 6))) * 10.0 ** rng.uniform(-4, -1, (2000, 1)),
                        lower, upper)
        anywhere = lower + (upper - lower) * jnp.asarray(rng.random((2000, 6)))
        value = float(model(d[None])[0])
        assert value <= float(jnp.min(model(jnp.concatenate([near, anywhere])))) + 1e-3 * (1.0 + abs(value))


def _problem(x, extra: int = 0):
    """Objective in N (a quartic bowl around p) and two switching functions (mm), then
    `extra` more that hold with room at the solution (as other loads' switches may)."""
    p = jnp.array([0.2, 0.3, 0.5, 0.5, 0.9, 1.3])
    J = 1000.0 * (1.0 + jnp.sum((x - p) ** 2) + 0.5 * jnp.sum((x - p) ** 4))
    more = [0.1 * (x[4] + 0.5 * k) for k in range(extra)]  # >= 0.09 mm at the solution
    s = jnp.stack([0.1 * (x[0] + x[1] - 1.2), 0.1 * (x[2] ** 2 + x[3] - 0.5)] + more)
    return J, s


def _values(units, extra: int = 0):
    J, s = jax.vmap(lambda x: _problem(x, extra))(units)
    dJ = jax.vmap(jax.grad(lambda x: _problem(x, extra)[0]))(units)
    ds = jax.vmap(jax.jacfwd(lambda x: _problem(x, extra)[1]))(units)
    return J, dJ, s, ds


@pytest.mark.parametrize("extra", [0, 3])
def test_every_slot_reaches_the_kkt_point_of_a_constrained_bowl(extra):
    """min J subject to s >= margin (two constraints active at the solution, the last
    coordinate on its bound; with `extra`, five constraints, more than the subproblem
    holds): every slot's best satisfies the KKT conditions, from starts on either side of
    the constraints; a slot that has converged starts again."""
    config = go.SwitchConfig(starts=4, iterations=40, margin=0.05)
    starts = np.array([[0.1, 0.1, 0.1, 0.1, 0.1, 0.1], [0.9, 0.9, 0.9, 0.9, 0.9, 0.9]])
    state = switch_init(jax.random.PRNGKey(0), config, 2 + extra, starts)
    assert np.array_equal(np.asarray(state.trial[:2]), starts)
    for _ in range(config.iterations):
        state = _update(state, _values(state.trial, extra), config)
    best = np.asarray(state.best)
    assert np.all(np.isfinite(np.asarray(state.best_value))) and int(np.sum(state.restarts)) >= config.starts
    for x in best:
        J, dJ, s, ds = (np.asarray(v)[0] for v in _values(jnp.asarray(x)[None], extra))
        assert np.all(s[2:] > config.margin)
        s, ds = s[:2], ds[:2]
        np.testing.assert_allclose(s, config.margin, atol=1e-6)  # both active
        assert x[5] == pytest.approx(1.0, abs=1e-6)  # p_6 = 1.3 lies beyond the bound
        free = slice(0, 5)
        multipliers, *_ = np.linalg.lstsq(ds[:, free].T, dJ[free], rcond=None)
        assert np.all(multipliers > 0.0)
        np.testing.assert_allclose(ds[:, free].T @ multipliers, dJ[free], atol=1e-3 * np.abs(dJ).max())
        assert dJ[5] < 0.0  # the bound holds the last coordinate against a descent
    np.testing.assert_allclose(np.asarray(state.best_value), float(np.min(state.best_value)), rtol=1e-6)


def test_a_failed_point_is_not_stepped_from_and_a_failed_start_is_replaced():
    """A trial whose value is not finite is rejected (the trust region shrinks, the point
    stays); a start whose first value is not finite is replaced by a random point."""
    config = go.SwitchConfig(starts=2, iterations=3)
    state = switch_init(jax.random.PRNGKey(1), config, 2)
    J, dJ, s, ds = _values(state.trial)
    state = _update(state, (J, dJ, s, ds), config)
    x, radius = np.asarray(state.x), np.asarray(state.radius)
    J, dJ, s, ds = _values(state.trial)
    failed = (J.at[0].set(jnp.inf), dJ, s, ds)
    after = _update(state, failed, config)
    np.testing.assert_array_equal(np.asarray(after.x[0]), x[0])
    assert float(after.radius[0]) < radius[0] and not bool(after.fresh[0])
    fresh = switch_init(jax.random.PRNGKey(2), config, 2)
    J, dJ, s, ds = _values(fresh.trial)
    replaced = _update(fresh, (J.at[1].set(jnp.nan), dJ, s, ds), config)
    assert bool(replaced.fresh[1]) and not np.allclose(np.asarray(replaced.trial[1]), np.asarray(fresh.trial[1]))
    assert int(replaced.restarts[1]) == 1 and not np.isfinite(float(replaced.best_value[1]))


@pytest.mark.parametrize("kwargs, match", [({"margin": -0.1}, "switch margin"), ({"starts": 0}, "starts"),
                                           ({"radius": 0.0}, "trust radius"), ({"patience": 0}, "patience")])
def test_bad_switch_settings_are_rejected(kwargs, match):
    with pytest.raises(ValueError, match=match):
        go.SwitchConfig(**kwargs)
