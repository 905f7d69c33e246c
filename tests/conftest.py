"""Test configuration: float64 and strict dtype promotion, as the engine's reference.

The command-line tests run `gearjax.cli.main` in-process, and the command enables JAX's
persistent compilation cache; it goes to a directory under the system's temporary
directory rather than the user's cache.
"""

import os
import tempfile

os.environ.setdefault("GEARJAX_CACHE_DIR", os.path.join(tempfile.gettempdir(), "gearjax-test-cache"))

import jax  # noqa: E402
import pytest  # noqa: E402

import gearjax  # noqa: F401, E402  (imported first: sets its XLA CPU flag before backends start)

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_dtype_promotion", "strict")


@pytest.fixture(scope="session")
def seed_pair():
    """Seed 001's 29/71 helical pair (x1 = x2 = 0, a = 281.85 mm)."""
    from gearjax import InvoluteGearPair

    return InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0)


@pytest.fixture(scope="session")
def spur_pair():
    """A standard spur pair used where closed forms are simplest."""
    from gearjax import InvoluteGearPair

    return InvoluteGearPair((23, 41), 4.0, 20.0, 0.0, 20.0)


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """Each test file shares its compiled programs through module-scoped fixtures; once the
    file is done they are dropped, so a worker that runs many files does not accumulate them
    (the larger impact and optimisation programs take gigabytes, and two workers share the
    24 GB machine)."""
    yield
    import gc

    jax.clear_caches()
    gc.collect()
