"""Shared timing helpers: compile time and steady-state time are measured separately."""

from __future__ import annotations

import json
import platform
import statistics
import time
from pathlib import Path

import jax

RESULTS = Path(__file__).resolve().parent / "results"


def machine() -> dict:
    dev = jax.devices()[0]
    return {
        "backend": jax.default_backend(),
        "device": getattr(dev, "device_kind", str(dev)),
        "devices": jax.device_count(),
        "cpu": platform.processor() or platform.machine(),
        "jax": jax.__version__,
    }


def time_compiled(fn, *args, repeats: int = 5, warmup: int = 1):
    """(compile seconds, median run seconds, all run times) of `fn(*args)` (a jitted fn)."""
    compile_s, run_s, runs, _ = time_compiled_output(fn, *args, repeats=repeats, warmup=warmup)
    return compile_s, run_s, runs


def time_compiled_output(fn, *args, repeats: int = 5, warmup: int = 1):
    """`time_compiled`, and the output of the compiled program (from the warm-up run, or
    one more run without warm-up), so a check of the results does not compile again."""
    t0 = time.perf_counter()
    compiled = fn.lower(*args).compile()
    compile_s = time.perf_counter() - t0
    output = None
    for _ in range(max(warmup, 1)):
        output = jax.block_until_ready(compiled(*args))
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(compiled(*args))
        runs.append(time.perf_counter() - t0)
    return compile_s, statistics.median(runs), runs, output


def first_and_runs(fn, *args, repeats: int = 5):
    """(seconds of the first call: trace, compile and run; median of `repeats` later calls
    after one warm-up; the later calls; the output) of `fn(*args)`, a jitted function or a
    public gearjax call, each call waited for (`jax.block_until_ready`)."""
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    jax.block_until_ready(fn(*args))
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn(*args))
        runs.append(time.perf_counter() - t0)
    return first, statistics.median(runs), runs, out


def time_host(fn, *args, repeats: int = 5, warmup: int = 1):
    """(median seconds, all run times, last output) of a host (NumPy/SciPy) call `fn(*args)`."""
    output = None
    for _ in range(warmup):
        output = fn(*args)
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        output = fn(*args)
        runs.append(time.perf_counter() - t0)
    return statistics.median(runs), runs, output


def count_equations(jaxpr) -> int:
    """Equations of a jaxpr, those of its sub-jaxprs (loops, conditionals, calls) included:
    a measure of the traced program's size that does not depend on the machine's load."""
    total = 0
    for eqn in jaxpr.eqns:
        total += 1
        for param in eqn.params.values():
            for sub in param if isinstance(param, (tuple, list)) else (param,):
                inner = getattr(sub, "jaxpr", sub)
                if hasattr(inner, "eqns"):
                    total += count_equations(inner)
    return total


def write(name: str, payload: dict) -> Path:
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(payload, indent=2))
    tmp.replace(path)
    return path


def median_time(fn, repeats: int = 3) -> float:
    """Median wall time (s) of `fn()` (blocked until ready) over `repeats` calls, after one
    call that compiles."""
    jax.block_until_ready(fn())
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        runs.append(time.perf_counter() - t0)
    return statistics.median(runs)
