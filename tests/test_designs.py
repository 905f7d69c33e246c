"""`simulate_designs`: many designs of one pair in one call equal `simulate` of each design."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gearjax import (
    RESULTS,
    Accuracy,
    FlankModification,
    MeshErrors,
    Scene,
    SimulationError,
    simulate,
    simulate_designs,
)

PLANE = Accuracy(positions_per_pitch=6, face_slices=5, tca_method="plane_of_action")
SURFACE = Accuracy(positions_per_pitch=4, face_slices=3)
Y = np.array([[0.01, 0.02, 3.0, 4.0, 0.01, 5.0],
              [0.03, 0.01, 6.0, 2.0, 0.00, 0.0],
              [0.00, 0.04, 1.0, 8.0, 0.02, 20.0]])


def transmission_error(result):
    return result.tca.transmission_error


def test_plane_of_action_designs_equal_single_runs(seed_pair):
    scene = Scene(seed_pair, accuracy=PLANE)
    te = simulate_designs(scene, FlankModification.from_vector(Y), outputs=transmission_error)
    whole = simulate_designs(scene, FlankModification.from_vector(Y))
    single = [simulate(Scene(seed_pair, FlankModification.from_vector(y), accuracy=PLANE, pairs=scene.pairs)).tca for y in Y]
    assert te.shape == (3, PLANE.positions_per_pitch)
    np.testing.assert_allclose(np.asarray(te), np.stack([np.asarray(s.transmission_error) for s in single]), rtol=1e-12, atol=1e-15)
    valid = np.stack([np.asarray(s.valid) for s in single])
    np.testing.assert_array_equal(np.asarray(whole.tca.valid), valid)
    np.testing.assert_allclose(np.asarray(whole.tca.slice_te)[valid], np.stack([np.asarray(s.slice_te) for s in single])[valid],
                               rtol=1e-12, atol=1e-15)
    # the designs' slices differ (their TE is 0: an unmodified patch is always in contact)
    assert np.ptp(np.where(valid, np.asarray(whole.tca.slice_te), 0.0), axis=0).max() > 1e-6


def test_surface_designs_in_chunks_with_errors_equal_single_runs(seed_pair):
    """Modifications and mesh errors as lists, run in chunks of 2 (`lax.map`, with a
    remainder chunk)."""
    scene = Scene(seed_pair, accuracy=SURFACE)
    mods = [FlankModification.from_vector(y) for y in Y]
    errors = [MeshErrors(pitch_deviation=e) for e in (0.0, 0.004, -0.002)]
    te = simulate_designs(scene, mods, errors=errors, outputs=transmission_error, batch_size=2)
    single = [simulate(Scene(seed_pair, m, errors=e, accuracy=SURFACE, pairs=scene.pairs)).tca.transmission_error
              for m, e in zip(mods, errors)]
    np.testing.assert_allclose(np.asarray(te), np.stack([np.asarray(s) for s in single]), rtol=1e-9, atol=1e-14)
    assert np.ptp(np.asarray(te), axis=0).min() > 1e-6  # the pitch errors move the TE (rad)


def slice_total(result):
    return jnp.sum(jnp.where(result.tca.valid, result.tca.slice_te, 0.0))


def test_designs_are_differentiable_like_single_runs(seed_pair):
    """`jax.grad` through `simulate_designs` (traced designs: no concrete checks) equals the
    gradient of each design's own `simulate`."""
    scene = Scene(seed_pair, accuracy=PLANE)
    grad = jax.grad(lambda y: jnp.sum(simulate_designs(scene, FlankModification.from_vector(y), outputs=slice_total)))(
        jnp.asarray(Y))
    single = [jax.grad(lambda y: slice_total(simulate(Scene(seed_pair, FlankModification.from_vector(y), accuracy=PLANE,
                                                             pairs=scene.pairs))))(jnp.asarray(y)) for y in Y]
    np.testing.assert_allclose(np.asarray(grad), np.stack([np.asarray(g) for g in single]), rtol=1e-10, atol=1e-14)
    assert np.abs(np.asarray(grad)).max() > 1e-3  # the reliefs move the slices' contact


def test_a_design_out_of_range_is_named(seed_pair):
    """A batch built around the constructor's checks (a negative relief amount in design 1)
    is flagged by the program's guard: `SimulationError`, or its code with throw=False."""
    mods = FlankModification.from_vector(Y)
    mods = eqx.tree_at(lambda m: m.root_relief, mods, jnp.asarray([0.01, -0.01, 0.0]))
    scene = Scene(seed_pair, accuracy=PLANE)
    with pytest.raises(SimulationError, match="invalid_modification"):
        simulate_designs(scene, mods, outputs=transmission_error)
    whole = simulate_designs(scene, mods, throw=False)
    codes = np.asarray(whole.tca.result._value)
    assert codes[1] == RESULTS.invalid_modification._value and (codes[[0, 2]] != codes[1]).all()
    assert np.isnan(np.asarray(whole.tca.transmission_error)[1]).all()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({}, "needs a batch"),
        ({"modifications": [0.1, 0.2]}, "modifications must be a FlankModification"),
        ({"modifications": FlankModification.from_vector(Y[0])}, "1-D array over the designs"),
        ({"modifications": FlankModification.from_vector(Y), "errors": [MeshErrors()]}, "same number of designs"),
        ({"modifications": FlankModification.from_vector(Y), "batch_size": 0}, "batch_size must be a positive integer"),
        ({"modifications": FlankModification.from_vector(Y), "outputs": "te"}, "outputs must be a function"),
        ({"modifications": FlankModification.from_vector(Y * np.array([1, 1, 1, 1, 1, 3]))},
         r"modifications.unmodified_length \(y6\) must be in \[0, 42"),
    ],
    ids=["none", "not-modifications", "unbatched", "lengths", "batch-size", "outputs", "too-long"],
)
def test_bad_batches_give_one_readable_error(seed_pair, kwargs, message):
    with pytest.raises(ValueError, match=message):
        simulate_designs(Scene(seed_pair, accuracy=PLANE), **kwargs)
