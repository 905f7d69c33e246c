"""Where gearjax's caches live on disk (`gearjax.runtime.cache`, `gearjax.runtime.program_cache`)."""

from __future__ import annotations

import os
from pathlib import Path

#: Environment variable that moves the cache directory.
ENV_VAR = "GEARJAX_CACHE_DIR"


def default_cache_dir() -> Path:
    """`$GEARJAX_CACHE_DIR`, else `$XDG_CACHE_HOME/gearjax/jax` (default `~/.cache`)."""
    path = os.environ.get(ENV_VAR)
    if path:
        return Path(path).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base).expanduser() / "gearjax" / "jax"


def make_cache_dir(directory: Path) -> Path:
    """Create `directory` (and its parents) if missing; a `ValueError` names the directory
    and `$GEARJAX_CACHE_DIR` when it cannot be created."""
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ValueError(f"cache directory {str(directory)!r} cannot be created ({err.strerror}); "
                         f"set {ENV_VAR} to a writable directory") from None
    return directory
