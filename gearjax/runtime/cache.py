"""JAX's persistent compilation cache for gearjax's programs.

Running a scene costs, before any number is computed, tracing `simulate`'s program (Python
builds the jaxpr: about 12 s for the default scene), lowering it to StableHLO (about 2 s)
and compiling it with XLA (about a minute on a 2-core CPU). Two caches on disk remove that:

* **JAX's persistent compilation cache** (`jax_compilation_cache_dir`, this module) stores
  compiled XLA executables, keyed by the lowered program, the JAX version and the backend.
  It never stores a program that contains a host callback, which is why gearjax's programs
  report solver failures as result codes (`gearjax.RESULTS`) instead of runtime checks.
* **gearjax's program cache** (`gearjax.runtime.program_cache`) stores the traced and lowered
  program of `simulate` (`jax.export`), so a later process neither traces nor lowers it;
  its compilation is then found in JAX's cache.

The command line enables both by default, and while it runs it stores even its quickest
compilations (building and reporting a scene runs dozens of small eager programs;
`gearjax ... --no-cache` disables all of it). The library never changes JAX's
configuration on import, so in Python the caches are opt-in:

    import gearjax as gj
    gj.enable_compilation_cache()          # before the first computation; both caches
    gj.enable_compilation_cache(programs=False)   # JAX's cache only

The cache directory is `$GEARJAX_CACHE_DIR` if set, else `$XDG_CACHE_HOME/gearjax/jax`
(`~/.cache/gearjax/jax`); the program cache uses its subdirectory `programs/`. JAX's
entries are keyed by the program, the JAX version and the backend, so a new JAX never loads
a stale program; delete the directory to reclaim space. Both caches load what they find
there, so the directory must be writable only by its user.

**Reverse-mode gradients of the impact force and old jaxlib versions**: with jaxlib 0.10.2
such an executable (e.g. the optimiser's value and gradient of the seed 001 objective) is
written to the cache, but loading it in a later process crashes that process (a stack
overflow in LLVM's JIT linker). Where the installed jaxlib is not known to load them safely
(`gearjax.runtime.versions.gradient_cache_safe`: jaxlib < 0.12), gearjax's own gradient program
(`gearjax.optimize`: gradient descent and `sensitivities` share it) keeps itself out of the
cache with `exclude_from_persistent_cache`; with a current jaxlib it is cached like every
other program, and a later process loads it instead of compiling it.
`python benchmarks/studies/check_cache_gradient_load.py [--raw]` runs it in two fresh processes with
one cache.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import jax

from .directories import default_cache_dir, make_cache_dir
from .program_cache import PROGRAMS_SUBDIR, enable_program_cache

#: Programs that compile faster than this (s) are not written: small eager operations
#: would otherwise fill the directory with entries that save nothing.
MIN_COMPILE_TIME_S = 0.2


def enable_compilation_cache(path: str | os.PathLike | None = None, *, programs: bool = True) -> Path:
    """Store compiled programs in `path` (default `default_cache_dir()`) and load them from
    there in later processes. Call it before the first computation of the process.

    Args:
        path: the cache directory.
        programs: also enable the program cache (traced programs of `simulate`, in
            `path/programs`, see `gearjax.runtime.program_cache`), so that a later process skips
            tracing as well.

    Returns:
        the cache directory (created if missing).
    """
    directory = make_cache_dir(Path(path).expanduser() if path is not None else default_cache_dir())
    if _cache_started() and jax.config.jax_compilation_cache_dir != str(directory):
        warnings.warn(
            "JAX has already compiled programs in this process with another compilation cache "
            "setting, so the cache may not take effect: call enable_compilation_cache() before "
            "the first computation",
            RuntimeWarning,
            stacklevel=2,
        )
    jax.config.update("jax_compilation_cache_dir", str(directory))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_TIME_S)
    if programs:
        enable_program_cache(directory / PROGRAMS_SUBDIR)
    return directory


def _do_nothing() -> None:
    return None


def exclude_from_persistent_cache() -> None:
    """Inside a function being traced for `jit`: keep its compiled program out of JAX's
    persistent compilation cache where the installed jaxlib may crash on loading it back
    (`gearjax.runtime.versions.gradient_cache_safe`; call it in a gradient program of your own
    through the impact force). With a jaxlib that loads such programs it does nothing.

    It adds a host callback that does nothing (`jax.debug.callback`, an effect, so it is
    never removed): jax < 0.12 does not write an executable that has host callbacks. The
    callback costs one call into Python per execution of the program (microseconds).
    """
    from .versions import gradient_cache_safe

    if not gradient_cache_safe():
        jax.debug.callback(_do_nothing)


def _cache_started() -> bool:
    """Whether JAX has already set up its persistent cache in this process (at the first
    compilation that consulted it); a directory set later is not used."""
    try:
        from jax._src import compilation_cache
    except ImportError:  # pragma: no cover - private module moved
        return False
    return bool(getattr(compilation_cache, "_cache_initialized", False))
