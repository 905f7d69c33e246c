"""Progress display of long runs (optimisation, chunked sweeps) and of compilations: a
live line or tqdm bar on a terminal, plain lines otherwise, or nothing."""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Iterator

#: JAX's monitoring events: one XLA compilation's duration, and a program loaded from the
#: persistent compilation cache (`jax._src.dispatch.BACKEND_COMPILE_EVENT`, `jax._src.compiler`)
BACKEND_COMPILE_EVENT = "/jax/core/compile/backend_compile_duration"
CACHE_HIT_EVENT = "/jax/compilation_cache/cache_hits"
#: time spent reading a program from JAX's persistent cache (inside `BACKEND_COMPILE_EVENT`)
CACHE_RETRIEVAL_EVENT = "/jax/compilation_cache/cache_retrieval_time_sec"
#: a block that is done sooner than this (s) says nothing: nothing worth a line was compiled
NOTICE_DELAY_S = 1.0


def _mode(mode: str | None) -> str | None:
    if mode not in ("auto", "bar", "lines", None):
        raise ValueError(f"progress must be 'auto', 'bar', 'lines' or None; got {mode!r}")
    if mode == "auto":
        return "bar" if sys.stderr.isatty() else "lines"
    return mode


class Progress:
    """A tqdm bar (`mode="bar"`), plain lines on standard error (`"lines"`), nothing
    (None), or `"auto"`: a bar when standard error is a terminal, lines otherwise.

    The bar appears when the first step is done, so that it never sits at 0 % while the
    first step compiles its programs (`compiling` says that).

    Args:
        mode: "auto", "bar", "lines" or None.
        total: number of steps of the run.
        done: steps already finished (a resumed run).
        label: what a step is ("generation", "chunk"); its first word is the bar's unit.
    """

    def __init__(self, mode: str | None, total: int, done: int, label: str):
        self.mode, self.label, self.total, self.done, self.bar = _mode(mode), label, total, done, None

    def update(self, step: int, elapsed: float, **postfix: str) -> None:
        """Step `step` (1-based) is done, `elapsed` seconds into the run; `postfix` is shown
        beside the bar (e.g. best="8375", points_per_s="120")."""
        if self.mode == "bar":
            if self.bar is None:
                from tqdm.auto import tqdm

                self.bar = tqdm(total=self.total, initial=self.done, desc=self.label,
                                unit=self.label.split()[0], file=sys.stderr)
            self.bar.set_postfix(**postfix, elapsed=f"{elapsed:.0f}s")
            self.bar.update(1)
        elif self.mode == "lines":
            extra = "".join(f"  {k.replace('_', ' ')} {v}" for k, v in postfix.items())
            print(f"{self.label} {step}/{self.total}{extra}  elapsed {elapsed:.1f} s", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _cache_note() -> str:
    import jax

    directory = jax.config.jax_compilation_cache_dir
    if directory and jax.config.jax_enable_compilation_cache:
        return f"first time only; cached in {directory}"
    return "the compilation cache is off"


@contextlib.contextmanager
def compiling(what: str, mode: str | None = "auto", delay: float = NOTICE_DELAY_S) -> Iterator[dict]:
    """Say what a block that may trace and compile programs is preparing, if it takes long.

    After `delay` seconds it prints `gearjax: compiling WHAT (first time only; cached in
    DIR)` on standard error: on a terminal (`"bar"`) one line that counts the seconds
    until the block ends, otherwise (`"lines"`) that line and, at the end, one more with the
    time taken. A block done sooner prints nothing. The closing words say whether XLA
    compiled anything (JAX's monitoring events): "compiled" or "loaded from the cache"; or,
    where the block raised, that it stopped (the error itself propagates).

    Yields a dict that holds, once the block is done, `elapsed_s`, `compile_s` (seconds
    XLA spent compiling) and `loaded` (programs loaded from JAX's persistent cache).
    """
    import jax

    mode = _mode(mode)
    stats = {"elapsed_s": 0.0, "compile_s": 0.0, "loaded": 0}

    def on_duration(event: str, duration: float, **_) -> None:
        # JAX times a program read from its cache as part of the backend compile: count
        # only what XLA compiled
        if event == BACKEND_COMPILE_EVENT:
            stats["compile_s"] += duration
        elif event == CACHE_RETRIEVAL_EVENT:
            stats["compile_s"] -= duration

    def on_event(event: str, **_) -> None:
        if event == CACHE_HIT_EVENT:
            stats["loaded"] += 1

    start = time.perf_counter()
    done = threading.Event()
    shown = threading.Event()
    line = f"gearjax: compiling {what} ({_cache_note()})"

    def announce() -> None:
        if mode is None or done.wait(delay):
            return
        shown.set()
        if mode == "lines":
            print(line, file=sys.stderr, flush=True)
            return
        while True:  # a terminal: the line counts the seconds
            print(f"\r{line} {time.perf_counter() - start:.0f} s", end="", file=sys.stderr, flush=True)
            if done.wait(1.0):
                return

    thread = threading.Thread(target=announce, daemon=True)
    jax.monitoring.register_event_duration_secs_listener(on_duration)
    jax.monitoring.register_event_listener(on_event)
    thread.start()
    finished = False
    try:
        yield stats
        finished = True
    finally:
        done.set()
        thread.join()
        jax.monitoring.unregister_event_duration_listener(on_duration)
        jax.monitoring.unregister_event_listener(on_event)
        stats["elapsed_s"] = time.perf_counter() - start
        stats["compile_s"] = max(stats["compile_s"], 0.0)
        if shown.is_set():
            how = ("loaded from the cache" if stats["compile_s"] < 0.1 * stats["elapsed_s"]
                   else f"XLA compiled for {stats['compile_s']:.1f} s")
            end = (f"ready in {stats['elapsed_s']:.1f} s ({how})" if finished
                   else f"stopped by an error after {stats['elapsed_s']:.1f} s")
            if mode == "bar":
                print(f"\r{line}: {end}", file=sys.stderr, flush=True)
            else:
                print(f"gearjax: {what} {end}", file=sys.stderr, flush=True)
