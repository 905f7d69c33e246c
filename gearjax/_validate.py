"""Constructor-time input checks.

Every check raises `ValueError` naming the parameter, its allowed range with units and the
offending value, before any computation. Checks run on concrete values only: inside `jit`
or `vmap` the inputs are tracers and are not inspected (validate the batch before mapping;
constructors accept batched arrays and check every element).
"""

from __future__ import annotations

import math
from typing import Any

import jax
import numpy as np


def is_concrete(*values: Any) -> bool:
    """True when no leaf of `values` is a JAX tracer (so it can be inspected)."""
    leaves = jax.tree_util.tree_leaves(values)
    return not any(isinstance(leaf, jax.core.Tracer) for leaf in leaves)


def as_numpy(value: Any) -> np.ndarray:
    return np.asarray(value, dtype=float)


def _fmt(value: np.ndarray) -> str:
    flat = value.ravel()
    if flat.size == 1:
        return f"{flat[0]:.6g}"
    bad = flat[:6]
    return "[" + ", ".join(f"{v:.6g}" for v in bad) + (", ...]" if flat.size > 6 else "]")


def check_finite(name: str, value: Any) -> None:
    """Reject NaN and infinities."""
    if not is_concrete(value):
        return
    v = as_numpy(value)
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be a finite number; got {_fmt(v)}")


def check_range(
    name: str,
    value: Any,
    low: float | None = None,
    high: float | None = None,
    *,
    low_inclusive: bool = True,
    high_inclusive: bool = True,
    unit: str = "",
) -> None:
    """Reject values outside [low, high] (or the open variants), and NaN."""
    if not is_concrete(value):
        return
    check_finite(name, value)
    v = as_numpy(value)
    ok = np.ones(v.shape, dtype=bool)
    if low is not None:
        ok &= (v >= low) if low_inclusive else (v > low)
    if high is not None:
        ok &= (v <= high) if high_inclusive else (v < high)
    if not np.all(ok):
        lo = "-inf" if low is None else f"{low:g}"
        hi = "inf" if high is None else f"{high:g}"
        lb = "[" if (low is not None and low_inclusive) else "("
        hb = "]" if (high is not None and high_inclusive) else ")"
        u = f" {unit}" if unit else ""
        raise ValueError(f"{name} must be in {lb}{lo}, {hi}{hb}{u}; got {_fmt(v[~ok])}{u}")


def check_int(name: str, value: Any, low: int, high: int | None = None) -> int:
    """Integer parameter (tooth counts, discretisation sizes) in [low, high]."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        if isinstance(value, float) and math.isfinite(value) and value == int(value):
            value = int(value)
        else:
            raise ValueError(f"{name} must be an integer >= {low}; got {value!r}")
    if value < low or (high is not None and value > high):
        rng = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ValueError(f"{name} must be an integer {rng}; got {value}")
    return int(value)


def check_choice(name: str, value: Any, choices: tuple) -> None:
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}; got {value!r}")
