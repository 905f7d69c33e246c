"""Process-level settings that gearjax needs on CPU, applied on import.

**The deadlock.** jaxlib 0.10.0 to 0.11.0 split a batched LAPACK call (`getrf`, `trsm`,
`gtsv`, ... behind `jnp.linalg.solve` and lineax's LU solves) into chunks on XLA's intra-op
thread pool once the batch is worth more than 2e5 flops, and the pool worker that runs the
call then blocks until its chunks are done (`ParallelBatchMap` in
`jaxlib/cpu/lapack_kernels.cc`). When as many such calls run at once as the pool has workers
(XLA's CPU runtime runs independent operations concurrently), no worker is left to run a
chunk and the program never returns: every thread parked on a futex, CPU time frozen. Seen
in gearjax as hangs of the vmapped LTCA program (32 positions x 21 slices, seed-001 pair)
and of batched derivative programs in the test suite (`gdb -p PID -batch -ex "thread apply
all bt"`: both `tf_XLAEigen` workers in `lapack_dgetrf_ffi`/`lapack_dtrsm_ffi` ->
`jax::ParallelBatchMap` -> `absl::BlockingCounter::Wait`). jax's own source stopped doing
this in open-source builds after 0.11.0 (commit 859992407d, "Don't try to parallelize LAPACK
kernels in opensource builds", 2026-07-21).

**What gearjax sets**, each unless the user already chose a value:

- `PJRT_NPROC=1` (only for the affected jaxlib versions): XLA's CPU client sizes its intra-op
  pool from this variable (`DefaultThreadPoolSize` in XLA's PjRt utilities), and jaxlib's
  kernels never split a batch over a pool of one thread. This removes the deadlock; it also
  runs each program's operations on one thread: +10 % on one default scene's impact chain
  (`benchmarks/stages.py`), but +60 % on the surface TCA of 100 designs batched on 2 cores
  (`benchmarks/tca.py`; more with more cores), and nothing where processes already share
  the cores (pytest-xdist, a GA population farmed out per process). A user who sets
  `PJRT_NPROC` gets XLA's pool back, and the deadlock's risk with it.
- `--xla_cpu_enable_concurrency_optimized_scheduler=false` in `XLA_FLAGS`: the first
  workaround, from before the cause was known. It made the deadlock rarer (fewer
  independent LAPACK calls scheduled side by side) but did not remove it. It only changes
  how independent operations are ordered, never what is computed, and stays as a second
  guard for users who raise `PJRT_NPROC` again.

Both are read once, when JAX's CPU backend starts. If the backends were already running when
gearjax was imported, the settings cannot take effect and a warning says so.
"""

from __future__ import annotations

import os
import re
import warnings

FLAG = "xla_cpu_enable_concurrency_optimized_scheduler"
NPROC = "PJRT_NPROC"
#: the variables XLA reads for its pool size, in this order; a value set by the user stays
NPROC_VARIABLES = (NPROC, "NPROC")
#: jaxlib versions [first, end) whose CPU LAPACK kernels split batches over XLA's pool.
AFFECTED_JAXLIB = ((0, 10, 0), (0, 11, 1))


def configure_xla_flags() -> bool:
    """Append `--xla_cpu_enable_concurrency_optimized_scheduler=false` to `XLA_FLAGS`.

    Returns True when gearjax set the flag, False when the user already chose a value.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if FLAG in flags:
        return False
    os.environ["XLA_FLAGS"] = (flags + f" --{FLAG}=false").strip()
    _warn_if_started(f"--{FLAG}=false")
    return True


def configure_thread_pool(jaxlib_version: str | None = None) -> bool:
    """Set `PJRT_NPROC=1` (one intra-op thread) when jaxlib's batched LAPACK can deadlock.

    Args:
        jaxlib_version: the installed jaxlib's version string (default: read from jaxlib).

    Returns True when gearjax set the variable; False when the user already set
    `PJRT_NPROC` or `NPROC` (which XLA reads in that order), or when this jaxlib is not
    affected.
    """
    if any(name in os.environ for name in NPROC_VARIABLES):
        return False
    if jaxlib_version is None:
        from jaxlib import version as _jaxlib_version

        jaxlib_version = _jaxlib_version.__version__
    if not affected(jaxlib_version):
        return False
    os.environ[NPROC] = "1"
    _warn_if_started(f"{NPROC}=1")
    return True


def affected(jaxlib_version: str) -> bool:
    """Whether a jaxlib version splits batched LAPACK calls over XLA's pool (see module doc)."""
    numbers = re.match(r"(\d+)\.(\d+)\.(\d+)", jaxlib_version)
    if numbers is None:
        return True  # unknown scheme: keep the guard
    version = tuple(int(n) for n in numbers.groups())
    return AFFECTED_JAXLIB[0] <= version < AFFECTED_JAXLIB[1]


def _warn_if_started(setting: str) -> None:
    if _backends_started():
        warnings.warn(
            f"gearjax was imported after JAX had started its backends, so {setting} (needed "
            "against a deadlock of jaxlib's CPU LAPACK kernels, see gearjax._runtime) cannot "
            "take effect. Import gearjax before running any JAX computation, or set it in "
            "the environment.",
            RuntimeWarning,
            stacklevel=4,
        )


def _backends_started() -> bool:
    try:
        from jax._src import xla_bridge
    except ImportError:  # pragma: no cover - private module moved
        return False
    return bool(getattr(xla_bridge, "_backends", None))
