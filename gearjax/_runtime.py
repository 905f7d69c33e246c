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

**Compile time.** XLA's CPU compiler emits fused loops with its MLIR "fusion emitters" by
default; `--xla_cpu_use_fusion_emitters=false` makes it use its older elemental LLVM
emitter. gearjax's programs are many small fusions (Newton solves of 3 unknowns, short
loops over slices and positions), and with jaxlib 0.10.2 the older emitter compiles them
in 14-47 % less time; single scenes run as fast or faster, large batches up to ~9 % slower
(figures in `configure_compiler`).

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
- `--xla_cpu_use_fusion_emitters=false` in `XLA_FLAGS` (only for the jaxlib versions it was
  measured on, `COMPILER_JAXLIB`: XLA aborts the process on a flag it does not know).

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
#: XLA flag that selects the CPU compiler's fused-loop emitter (see `configure_compiler`)
COMPILER_FLAG = "xla_cpu_use_fusion_emitters"
#: jaxlib versions [first, end) on which `COMPILER_FLAG=false` was measured to compile faster
COMPILER_JAXLIB = ((0, 10, 0), (0, 11, 0))


def configure_xla_flags() -> bool:
    """Append `--xla_cpu_enable_concurrency_optimized_scheduler=false` to `XLA_FLAGS`.

    Returns True when gearjax set the flag, False when the user already chose a value.
    """
    return _append_flag(FLAG, "against a deadlock of jaxlib's CPU LAPACK kernels")


def configure_compiler(jaxlib_version: str | None = None) -> bool:
    """Append `--xla_cpu_use_fusion_emitters=false` to `XLA_FLAGS` (XLA's CPU compiler then
    emits fused loops with its elemental LLVM emitter instead of its MLIR fusion emitters).

    Measured with jaxlib 0.10.2 on 2 cores (2026-11-26), each program in a fresh process
    without the persistent cache; "before" with `XLA_FLAGS=--xla_cpu_use_fusion_emitters=true`:

    | program | compile before -> after (s) | run before -> after |
    |---|---|---|
    | default scene, surface TCA | 6.83 -> 3.62 | 49.6 -> 46.8 ms |
    | default scene, TCA + slice LTCA | 8.88 -> 4.81 | 60.9 -> 60.0 ms |
    | default scene, impact chain | 25.91 -> 16.36 | 71.7 -> 64.9 ms |
    | GA batch, 12 designs (seed pair, `fast`, impact) | 27.3 -> 20.4 | 211 -> 199 ms |
    | value and gradient, 2 designs (the same objective) | 136.2 -> 117.7 | 0.11 -> 0.11 s |
    | surface TCA of 1 design (seed pair, 64 positions x 21 slices) | 9.81 -> 6.95 | 0.232 -> 0.237 s |
    | the same, 100 designs batched | 8.83 -> 5.79 | 29.7 -> 32.3 s |

    (`python benchmarks/stages.py --repeats 1 --no-cli --stages tca_surface ltca_slice
    impact --name compiler_elemental`, and `--name compiler_fusion_emitters` with the flag
    set to true; `python benchmarks/tca.py --methods surface --designs 1 100 --repeats 1
    --name tca_surface_elemental` and `_fusion_emitters`; the optimiser's programs of
    `tests/test_optimize.py` timed alone.) Values agree to 1e-12 (the same operations, fused
    and ordered differently). Large batches run up to ~9 % slower (one run each), so a long
    batched job of one compiled program may be faster with the flag set back to true.

    Set only for `COMPILER_JAXLIB`: XLA aborts the process on an unknown flag, so a jaxlib
    that dropped this one must not get it.

    Args:
        jaxlib_version: the installed jaxlib's version string (default: read from jaxlib).

    Returns True when gearjax set the flag; False when the user already chose a value or
    this jaxlib is outside `COMPILER_JAXLIB`.
    """
    if jaxlib_version is None:
        from jaxlib import version as _jaxlib_version

        jaxlib_version = _jaxlib_version.__version__
    if not _in_range(jaxlib_version, COMPILER_JAXLIB, unknown=False):
        return False
    return _append_flag(COMPILER_FLAG, "for a faster compilation")


def _append_flag(name: str, purpose: str) -> bool:
    """Append `--name=false` to `XLA_FLAGS` unless the user named the flag already."""
    flags = os.environ.get("XLA_FLAGS", "")
    if name in flags:
        return False
    os.environ["XLA_FLAGS"] = (flags + f" --{name}=false").strip()
    _warn_if_started(f"--{name}=false", purpose, stacklevel=5)
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
    _warn_if_started(f"{NPROC}=1", "against a deadlock of jaxlib's CPU LAPACK kernels")
    return True


def affected(jaxlib_version: str) -> bool:
    """Whether a jaxlib version splits batched LAPACK calls over XLA's pool (see module doc)."""
    return _in_range(jaxlib_version, AFFECTED_JAXLIB, unknown=True)  # unknown scheme: keep the guard


def _in_range(jaxlib_version: str, bounds, unknown: bool) -> bool:
    """Whether `jaxlib_version` lies in `[bounds[0], bounds[1])`; `unknown` where the string
    does not start with three numbers."""
    numbers = re.match(r"(\d+)\.(\d+)\.(\d+)", jaxlib_version)
    if numbers is None:
        return unknown
    version = tuple(int(n) for n in numbers.groups())
    return bounds[0] <= version < bounds[1]


def _warn_if_started(setting: str, purpose: str, stacklevel: int = 4) -> None:
    if _backends_started():
        warnings.warn(
            f"gearjax was imported after JAX had started its backends, so {setting} ({purpose}, "
            "see gearjax._runtime) cannot take effect. Import gearjax before running any JAX "
            "computation, or set it in the environment.",
            RuntimeWarning,
            stacklevel=stacklevel,
        )


def _backends_started() -> bool:
    try:
        from jax._src import xla_bridge
    except ImportError:  # pragma: no cover - private module moved
        return False
    return bool(getattr(xla_bridge, "_backends", None))
