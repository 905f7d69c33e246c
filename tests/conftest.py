"""Test configuration: float64 and strict dtype promotion, as the engine's reference.

One JAX persistent compilation cache for the whole test run: the pytest process (xdist's
controller) creates a new temporary directory and removes it when it ends; its xdist
workers and every subprocess the tests start (command-line runs, the killed GA and sweep
runs) inherit it through the environment, so a program that one of them compiled is
loaded, not compiled again, by the others (the killed GA run loads the batch program of
`tests/test_optimize.py`), and so do the notebook kernels (`test_notebooks.py`). Never
the user's cache. Concurrent writers are safe because a size limit is set: JAX then reads
and writes its entries under a file lock (`filelock`, a test dependency for that reason).
"""

import atexit
import os
import shutil
import tempfile

if "GEARJAX_TEST_CACHE_DIR" not in os.environ:  # the first process of the run owns it
    os.environ["GEARJAX_TEST_CACHE_DIR"] = tempfile.mkdtemp(prefix="gearjax-test-cache-")
    atexit.register(shutil.rmtree, os.environ["GEARJAX_TEST_CACHE_DIR"], ignore_errors=True)
# read by gearjax's commands (`gearjax.runtime.cache`) and, in every process, by JAX itself
os.environ["GEARJAX_CACHE_DIR"] = os.environ["GEARJAX_TEST_CACHE_DIR"]
os.environ["JAX_COMPILATION_CACHE_DIR"] = os.environ["GEARJAX_TEST_CACHE_DIR"]
os.environ["JAX_COMPILATION_CACHE_MAX_SIZE"] = str(64 * 2**30)  # a limit, so that JAX locks
os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = "0.2"  # gearjax.runtime.cache.MIN_COMPILE_TIME_S
# The suite compiles far more than it runs: without LLVM's optimisation passes XLA's CPU
# backend compiles the default scene's program in about 60 % of the time and runs it about
# 2.5x slower (`benchmarks/trace_compile.py` under these flags; docs/test_suite.md). No
# fast-math either way, so the arithmetic is the same. Inherited by the workers, the
# subprocesses and the notebook kernels.
TEST_XLA_FLAGS = ("--xla_backend_optimization_level=0", "--xla_llvm_disable_expensive_passes=true")
_flags = os.environ.get("XLA_FLAGS", "")
os.environ["XLA_FLAGS"] = " ".join([_flags, *(f for f in TEST_XLA_FLAGS if f not in _flags)]).strip()

import jax  # noqa: E402
import pytest  # noqa: E402

import gearjax  # noqa: E402  (imported first: sets its XLA CPU flag before backends start)

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_dtype_promotion", "strict")
# enabled before the first compilation (later it would not take effect): the compiled
# programs of a test file are dropped when the file ends (`_release_compiled_programs`),
# and a later file, or another process, that compiles the same program loads it from there.
gearjax.enable_compilation_cache(os.environ["GEARJAX_CACHE_DIR"], programs=False)


#: Approximate cost (s) of each test file in one whole run on 2 cores, from a profile
#: (`GEARJAX_TEST_PROFILE` and `tools/test_profile.py`). Only the schedule uses them: the
#: order matters, not the values; most of each is tracing and compiling.
FILE_COSTS = {
    "test_optimize.py": 324, "test_impact.py": 268, "test_sweep.py": 235, "test_notebooks.py": 168,
    "test_ltca.py": 164, "test_point_impact.py": 158, "test_pareto.py": 143, "test_results.py": 128,
    "test_hard_cases.py": 124, "test_impact_convergence.py": 115, "test_tca.py": 112,
    "test_point_ltca.py": 90, "test_hard_cases_curvilinear.py": 86, "test_transforms.py": 67,
    "test_cli.py": 57, "test_double_arc.py": 57, "test_hard_cases_ratios.py": 51,
    "test_curvilinear.py": 49, "test_scene.py": 47, "test_designs.py": 36, "test_cache.py": 33,
    "test_point_analysis.py": 27, "test_switch.py": 22, "test_hard_cases_double_arc.py": 21,
    "test_hertz_point.py": 19, "test_scene_fuzz.py": 18, "test_point_contact.py": 17,
    "test_resources.py": 16,
}


def pytest_collection_modifyitems(config, items):
    """Schedule for `pytest -n 2 --dist loadfile --no-loadscope-reorder` (`make test`): each
    test file goes whole to one worker (its module fixtures share the compiled programs)
    and the files go out longest first (`FILE_COSTS`), so that the two workers end
    together. xdist's own order (most tests first) sent the notebooks (831 s, one file)
    last, to one worker. Deterministic (every worker must collect the same list); a cost
    that is off only slows the run down. (`--dist loadgroup` would split the notebooks, but
    with pytest 9.2 it is a no-op: xdist 3.8 renames `item._nodeid`, which pytest no longer
    reads, so every test became its own unit and the module fixtures ran on both workers.)"""
    files = list(dict.fromkeys(item.path.name for item in items))
    rank = {name: k for k, name in enumerate(sorted(files, key=lambda f: -FILE_COSTS.get(f, 0)))}
    items.sort(key=lambda item: rank[item.path.name])


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


#: `GEARJAX_TEST_PROFILE=FILE`: each worker appends one JSON line per test file to FILE
#: (worker, start and wall time, and the seconds its process spent tracing, lowering and
#: compiling, with the persistent-cache hits and misses), from which `FILE_COSTS` and the
#: worker balance are read (`tools/test_profile.py`).
PROFILE = os.environ.get("GEARJAX_TEST_PROFILE")
_COUNTS: dict = {}
if PROFILE:
    import jax.monitoring

    def _count(event, value=1.0, **kwargs):
        _COUNTS[event] = _COUNTS.get(event, 0.0) + value

    jax.monitoring.register_event_duration_secs_listener(lambda e, s, **kw: _count(e, s))
    jax.monitoring.register_event_listener(lambda e, **kw: _count(e))


@pytest.fixture(autouse=True, scope="module")
def _profile_file(request):
    """One line of `GEARJAX_TEST_PROFILE` per test file (nothing when it is not set)."""
    if not PROFILE:
        yield
        return
    import json
    import time

    before, start = dict(_COUNTS), time.time()
    yield
    spent = {k.rsplit("/", 1)[-1]: round(v - before.get(k, 0.0), 2) for k, v in _COUNTS.items()
             if k.startswith(("/jax/core/compile/", "/jax/compilation_cache/cache_")) and v != before.get(k, 0.0)}
    line = dict(file=request.path.name, worker=os.environ.get("PYTEST_XDIST_WORKER", "main"),
                start=round(start, 1), wall_s=round(time.time() - start, 1), **spent)
    with open(PROFILE, "a") as f:
        f.write(json.dumps(line) + "\n")


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
