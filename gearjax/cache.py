"""JAX's persistent compilation cache for gearjax's programs.

Compiling the default scene's program takes about a minute on a 2-core CPU; JAX can store
compiled programs on disk and load them in the next process instead
(`jax_compilation_cache_dir`). It never stores a program that contains a host callback,
which is why gearjax's programs report solver failures as result codes
(`gearjax.RESULTS`) instead of runtime checks.

The command line enables the cache by default (`gearjax ... --no-cache` disables it); the
library never changes JAX's configuration on import, so in Python it is opt-in:

    import gearjax as gj
    gj.enable_compilation_cache()          # before the first computation

The cache directory is `$GEARJAX_CACHE_DIR` if set, else `$XDG_CACHE_HOME/gearjax/jax`
(`~/.cache/gearjax/jax`). Entries are keyed by the program, the JAX version and the
backend, so a new JAX never loads a stale program; delete the directory to reclaim space.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import jax

#: Environment variable that moves the cache directory.
ENV_VAR = "GEARJAX_CACHE_DIR"
#: Programs that compile faster than this (s) are not written: small eager operations
#: would otherwise fill the directory with entries that save nothing.
MIN_COMPILE_TIME_S = 0.2


def default_cache_dir() -> Path:
    """`$GEARJAX_CACHE_DIR`, else `$XDG_CACHE_HOME/gearjax/jax` (default `~/.cache`)."""
    path = os.environ.get(ENV_VAR)
    if path:
        return Path(path).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base).expanduser() / "gearjax" / "jax"


def enable_compilation_cache(path: str | os.PathLike | None = None) -> Path:
    """Store compiled programs in `path` (default `default_cache_dir()`) and load them from
    there in later processes. Call it before the first computation of the process.

    Returns:
        the cache directory (created if missing).
    """
    directory = Path(path).expanduser() if path is not None else default_cache_dir()
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ValueError(f"cache directory {str(directory)!r} cannot be created ({err.strerror}); "
                         f"set {ENV_VAR} to a writable directory") from None
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
    return directory


def _cache_started() -> bool:
    """Whether JAX has already set up its persistent cache in this process (at the first
    compilation that consulted it); a directory set later is not used."""
    try:
        from jax._src import compilation_cache
    except ImportError:  # pragma: no cover - private module moved
        return False
    return bool(getattr(compilation_cache, "_cache_initialized", False))
