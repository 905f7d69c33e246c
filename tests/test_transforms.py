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
