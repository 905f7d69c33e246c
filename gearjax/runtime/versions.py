"""What gearjax needs from the installed jaxlib: the one module that knows its versions.

With a current jaxlib (>= 0.12.0) gearjax changes nothing in the process. Older ones get
workarounds, applied on import and each only unless the user already chose a value:

- jaxlib 0.10.0 to 0.11.0 split a batched LAPACK call (`getrf`, `trsm`, ... behind
  `jnp.linalg.solve` and lineax's LU) into chunks on XLA's intra-op pool and block the
  calling pool thread until they are done; as many such calls side by side as the pool has
  threads never return. gearjax sets `PJRT_NPROC=1` (a pool of one thread, which jaxlib never
  splits over) and `--xla_cpu_enable_concurrency_optimized_scheduler=false` in `XLA_FLAGS`
  (fewer such calls side by side). jax stopped splitting after 0.11.0.
- jaxlib 0.10.x compiles gearjax's many small fusions faster with XLA's elemental LLVM
  emitter: `--xla_cpu_use_fusion_emitters=false`. Later XLA has no such flag and aborts the
  process on a flag it does not know, so it is set for the measured versions only.
- jaxlib < 0.12.0: an executable of a reverse-mode impact gradient loaded from JAX's
  persistent cache crashed the loading process (a stack overflow in LLVM's JIT linker, seen
  with 0.10.2; 0.11.x untested), so gearjax keeps its gradient programs out of that cache
  (`gradient_cache_safe`, `gearjax.runtime.cache`).

The settings are read once, when JAX's CPU backend starts: if it was already running when
gearjax was imported, they cannot take effect and a warning says so. Why and how each was
measured: `docs/decisions/0001-jaxlib-workarounds.md`.
"""

from __future__ import annotations

import os
import re
import warnings

#: XLA flag of the concurrency-optimised scheduler (off against the LAPACK deadlock)
FLAG = "xla_cpu_enable_concurrency_optimized_scheduler"
NPROC = "PJRT_NPROC"
#: the variables XLA reads for its pool size, in this order; a value set by the user stays
NPROC_VARIABLES = (NPROC, "NPROC")
#: jaxlib versions [first, end) whose CPU LAPACK kernels split batches over XLA's pool.
AFFECTED_JAXLIB = ((0, 10, 0), (0, 11, 1))
#: XLA flag that selects the CPU compiler's fused-loop emitter
COMPILER_FLAG = "xla_cpu_use_fusion_emitters"
#: jaxlib versions [first, end) on which `COMPILER_FLAG=false` was measured to compile faster
COMPILER_JAXLIB = ((0, 10, 0), (0, 11, 0))
#: the first jaxlib whose cached reverse-mode impact gradient loads in a later process
GRADIENT_CACHE_SAFE_FROM = (0, 12, 0)


def jaxlib_version() -> str:
    """The installed jaxlib's version string."""
    from jaxlib import version as _jaxlib_version

    return _jaxlib_version.__version__


def configure(jaxlib: str | None = None) -> list[str]:
    """Apply the settings this jaxlib needs (none for jaxlib >= 0.11.1); returns those set."""
    jaxlib = jaxlib_version() if jaxlib is None else jaxlib
    done = []
    if configure_thread_pool(jaxlib):
        done.append(f"{NPROC}=1")
    if configure_xla_flags(jaxlib):
        done.append(f"--{FLAG}=false")
    if configure_compiler(jaxlib):
        done.append(f"--{COMPILER_FLAG}=false")
    return done


def configure_xla_flags(jaxlib: str | None = None) -> bool:
    """Append `--xla_cpu_enable_concurrency_optimized_scheduler=false` to `XLA_FLAGS` for a
    jaxlib with the LAPACK deadlock (`affected`).

    Returns True when gearjax set the flag; False when the user already chose a value or
    this jaxlib is not affected.
    """
    if not affected(jaxlib_version() if jaxlib is None else jaxlib):
        return False
    return _append_flag(FLAG, "against a deadlock of jaxlib's CPU LAPACK kernels")


def configure_compiler(jaxlib: str | None = None) -> bool:
    """Append `--xla_cpu_use_fusion_emitters=false` to `XLA_FLAGS` for the jaxlib versions
    it was measured on (`COMPILER_JAXLIB`): XLA's CPU compiler then emits fused loops with
    its elemental LLVM emitter instead of its MLIR fusion emitters.

    Returns True when gearjax set the flag; False when the user already chose a value or
    this jaxlib is outside `COMPILER_JAXLIB`.
    """
    if not _in_range(jaxlib_version() if jaxlib is None else jaxlib, COMPILER_JAXLIB, unknown=False):
        return False
    return _append_flag(COMPILER_FLAG, "for a faster compilation")


def configure_thread_pool(jaxlib: str | None = None) -> bool:
    """Set `PJRT_NPROC=1` (one intra-op thread) when jaxlib's batched LAPACK can deadlock.

    Returns True when gearjax set the variable; False when the user already set
    `PJRT_NPROC` or `NPROC` (which XLA reads in that order), or when this jaxlib is not
    affected.
    """
    if any(name in os.environ for name in NPROC_VARIABLES):
        return False
    if not affected(jaxlib_version() if jaxlib is None else jaxlib):
        return False
    os.environ[NPROC] = "1"
    _warn_if_started(f"{NPROC}=1", "against a deadlock of jaxlib's CPU LAPACK kernels")
    return True


def affected(jaxlib: str) -> bool:
    """Whether a jaxlib version splits batched LAPACK calls over XLA's pool (see module doc)."""
    return _in_range(jaxlib, AFFECTED_JAXLIB, unknown=True)  # unknown scheme: keep the guard


def gradient_cache_safe(jaxlib: str | None = None) -> bool:
    """Whether this jaxlib loads a cached reverse-mode impact gradient safely (>= 0.12.0);
    unknown version strings are taken as unsafe."""
    jaxlib = jaxlib_version() if jaxlib is None else jaxlib
    return not _in_range(jaxlib, ((0, 0, 0), GRADIENT_CACHE_SAFE_FROM), unknown=True)


def _append_flag(name: str, purpose: str) -> bool:
    """Append `--name=false` to `XLA_FLAGS` unless the user named the flag already."""
    flags = os.environ.get("XLA_FLAGS", "")
    if name in flags:
        return False
    os.environ["XLA_FLAGS"] = (flags + f" --{name}=false").strip()
    _warn_if_started(f"--{name}=false", purpose, stacklevel=5)
    return True


def _in_range(jaxlib: str, bounds, unknown: bool) -> bool:
    """Whether `jaxlib` lies in `[bounds[0], bounds[1])`; `unknown` where the string does not
    start with three numbers."""
    numbers = re.match(r"(\d+)\.(\d+)\.(\d+)", jaxlib)
    if numbers is None:
        return unknown
    version = tuple(int(n) for n in numbers.groups())
    return bounds[0] <= version < bounds[1]


def _warn_if_started(setting: str, purpose: str, stacklevel: int = 4) -> None:
    if _backends_started():
        warnings.warn(
            f"gearjax was imported after JAX had started its backends, so {setting} ({purpose}, "
            "see gearjax.runtime.versions) cannot take effect. Import gearjax before running any JAX "
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
