"""Process-level XLA setting that gearjax needs on CPU.

With the CPU runtime of jaxlib 0.10.x, the *concurrency-optimised scheduler* deadlocks
intermittently when the compiled LTCA program (positions `vmap`-ed over nested Newton
loops) is executed a second time: every runtime thread parks on a futex and the call never
returns (reproduced 3/3 at 32 positions x 21 slices, seed-001 pair, 1000 N m). With
`--xla_cpu_enable_concurrency_optimized_scheduler=false` the same program ran hundreds of
times without a hang and no slower. The flag only changes how independent operations are
ordered, never what is computed.

The flag is read once, when the CPU backend starts, so gearjax appends it to `XLA_FLAGS` on
import unless the user already set that flag either way. If JAX's backends were already
running when gearjax was imported, the flag cannot take effect and a warning says so.
Per-compile `compiler_options` do not reach this setting (tried: it still deadlocks).
"""

from __future__ import annotations

import os
import warnings

FLAG = "xla_cpu_enable_concurrency_optimized_scheduler"


def configure_xla_flags() -> bool:
    """Append `--xla_cpu_enable_concurrency_optimized_scheduler=false` to `XLA_FLAGS`.

    Returns True when gearjax set the flag, False when the user already chose a value.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if FLAG in flags:
        return False
    os.environ["XLA_FLAGS"] = (flags + f" --{FLAG}=false").strip()
    if _backends_started():
        warnings.warn(
            "gearjax was imported after JAX had started its backends, so "
            f"--{FLAG}=false (needed against an XLA CPU deadlock in repeated LTCA calls) "
            "cannot take effect. Import gearjax before running any JAX computation, or "
            f"set XLA_FLAGS=--{FLAG}=false in the environment.",
            RuntimeWarning,
            stacklevel=3,
        )
    return True


def _backends_started() -> bool:
    try:
        from jax._src import xla_bridge
    except ImportError:  # pragma: no cover - private module moved
        return False
    return bool(getattr(xla_bridge, "_backends", None))
