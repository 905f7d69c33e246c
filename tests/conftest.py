"""Test configuration: float64 and strict dtype promotion, as the engine's reference.

JAX's persistent compilation cache (which the command-line tests' in-process
`gearjax.cli.main` would also use) goes to a new temporary directory of this process (each
xdist worker has its own), never the user's cache and never one that another run, or the
other worker, writes at the same time: JAX writes its cache entries in place, without a
lock unless a size limit is set.
"""

import atexit
import os
import shutil
import tempfile

# Set in every process (an xdist worker inherits the controller's environment, and must not
# share its directory), removed when the process ends.
os.environ["GEARJAX_CACHE_DIR"] = tempfile.mkdtemp(prefix="gearjax-test-cache-")
atexit.register(shutil.rmtree, os.environ["GEARJAX_CACHE_DIR"], ignore_errors=True)

import jax  # noqa: E402
import pytest  # noqa: E402

import gearjax  # noqa: F401, E402  (imported first: sets its XLA CPU flag before backends start)

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_dtype_promotion", "strict")
# JAX's persistent compilation cache in this process's own directory, enabled before the
# first compilation (later it would not take effect): the compiled programs of a test file
# are dropped when the file ends (`_release_compiled_programs`), and a later file of the
# same worker that compiles the same program again loads it from there.
gearjax.enable_compilation_cache(os.environ["GEARJAX_CACHE_DIR"], programs=False)


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


@pytest.fixture
def forbid(monkeypatch):
    """`forbid(module, *names)`: calling any of those functions fails the test, which so
    shows that a check came before any computation."""

    def refuse(*args, **kwargs):
        raise AssertionError("computed before the arguments were checked")

    def patch(module, *names):
        for name in names:
            monkeypatch.setattr(module, name, refuse)

    return patch


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """Each test file shares its compiled programs through module-scoped fixtures; once the
    file is done they are dropped, so a worker that runs many files does not accumulate them
    (the larger impact and optimisation programs take gigabytes, and two workers share the
    24 GB machine). Dropping them is not enough: glibc keeps the freed heap, so a worker
    stayed at ~4 GB after compiling one impact gradient; `malloc_trim` hands it back
    (0.7 GB after)."""
    yield
    import ctypes
    import ctypes.util
    import gc

    jax.clear_caches()
    gc.collect()
    libc = ctypes.util.find_library("c")
    if libc is not None and hasattr(ctypes.CDLL(libc), "malloc_trim"):
        ctypes.CDLL(libc).malloc_trim(0)
