"""jit, vmap and grad of the contact analysis: consistency and finite differences."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from gearjax import Accuracy, FlankDepth, FlankModification
from gearjax.tca import pair_window, tooth_contact_analysis

TINY = Accuracy(positions_per_pitch=4, face_slices=3)
SMALL = Accuracy(positions_per_pitch=8, face_slices=7)
# Large reliefs and a short crowned-free centre: no contact line finds an unmodified
# zone at every position, so the TE depends on all six parameters.
Y = jnp.array([0.030, 0.025, 10.0, 9.0, 0.020, 2.0])


def te_of(pair, y, accuracy, pairs):
    depth = FlankDepth(pinion=FlankModification.from_vector(y))
    return tooth_contact_analysis(pair, depth, accuracy=accuracy, pairs=pairs).transmission_error


def test_jit_equals_eager(seed_pair):
    pairs = pair_window(seed_pair)
    eager = te_of(seed_pair, Y, TINY, pairs)
    jitted = eqx.filter_jit(te_of)(seed_pair, Y, TINY, pairs)
    np.testing.assert_allclose(np.asarray(jitted), np.asarray(eager), rtol=1e-12, atol=1e-15)
    assert np.max(np.abs(np.asarray(eager))) > 1e-6  # a real, non-zero TE was compared


def test_vmap_over_designs_equals_a_loop(seed_pair):
    pairs = pair_window(seed_pair)
    designs = jnp.stack([Y, Y * jnp.array([0.5, 1.0, 1.0, 0.8, 1.5, 1.0]), Y * jnp.array([1.0, 0.3, 0.7, 1.0, 0.5, 2.0])])
    f = eqx.filter_jit(lambda y: te_of(seed_pair, y, SMALL, pairs))
    batched = jax.vmap(f)(designs)
    looped = jnp.stack([f(y) for y in designs])
    # under vmap all lanes share the Newton iteration count, so some solves take an extra
    # step beyond the tolerance: agreement is to the solver's accuracy, not bit-for-bit
    np.testing.assert_allclose(np.asarray(batched), np.asarray(looped), rtol=1e-9, atol=1e-14)
    assert not np.allclose(np.asarray(looped[0]), np.asarray(looped[1]))


def test_gradients_match_central_differences(seed_pair):
    pairs = pair_window(seed_pair)

    @eqx.filter_jit
    def objective(y):
        return jnp.sum(te_of(seed_pair, y, SMALL, pairs))

    grad = np.asarray(jax.grad(objective)(Y))
    steps = np.array([1e-6, 1e-6, 1e-4, 1e-4, 1e-6, 1e-4])
    fd = np.array([
        (float(objective(Y.at[i].add(h))) - float(objective(Y.at[i].add(-h)))) / (2 * h)
        for i, h in enumerate(steps)
    ])
    assert np.all(np.abs(grad) > 1e-8), grad  # every parameter moves the TE
    np.testing.assert_allclose(grad, fd, rtol=2e-5)


def test_second_call_does_not_retrace(seed_pair):
    pairs = pair_window(seed_pair)
    traces = []

    @eqx.filter_jit
    def run(y):
        traces.append(1)
        return te_of(seed_pair, y, TINY, pairs)

    run(Y).block_until_ready()
    run(Y * 0.5).block_until_ready()
    assert len(traces) == 1


def test_nested_vmap_equals_the_nested_vmaps():
    """`nested_vmap` over a (3, 4, 5) grid equals three nested `vmap`s: arguments mapped at
    some levels (a per-position scalar, a per-pair vector), at all of them (a pytree of
    per-slice fields) and at none (a constant), with pytree outputs."""
    from gearjax.tca.grid import nested_vmap

    rng = np.random.default_rng(0)
    phi, k, z = (jnp.asarray(rng.normal(size=n)) for n in (3, 4, 5))
    vec = jnp.asarray(rng.normal(size=(4, 2)))
    fields = {"a": jnp.asarray(rng.normal(size=(3, 4, 5))), "b": jnp.asarray(rng.normal(size=(3, 4, 5, 2)))}
    constant = jnp.asarray(rng.normal(size=2))

    def f(p, kk, v, zz, fs, c):
        value = jnp.sin(p) * kk + zz**2 + jnp.dot(v, fs["b"]) + fs["a"] * jnp.sum(c)
        return value, {"vector": v * p + c}

    axes = [(0, None, None, None, 0, None), (None, 0, 0, None, 0, None), (None, None, None, 0, 0, None)]
    args = (phi, k, vec, z, fields, constant)
    nested = f
    for level in reversed(axes):
        nested = jax.vmap(nested, level)
    want, got = nested(*args), nested_vmap(f, axes, *args)
    assert jax.tree_util.tree_structure(got) == jax.tree_util.tree_structure(want)
    assert got[0].shape == (3, 4, 5) and got[1]["vector"].shape == (3, 4, 5, 2)
    for g, w in zip(jax.tree_util.tree_leaves(got), jax.tree_util.tree_leaves(want)):
        np.testing.assert_allclose(np.asarray(g), np.asarray(w), rtol=1e-15, atol=1e-15)
