"""Summarise a test run's per-file profile and check the workers' balance.

    GEARJAX_TEST_PROFILE=/tmp/profile.jsonl make test
    python tools/test_profile.py /tmp/profile.jsonl

`tests/conftest.py` writes one JSON line per test file when `GEARJAX_TEST_PROFILE` is set:
the worker, the wall time, and the seconds that the worker's process spent tracing,
lowering and compiling programs (XLA), with its persistent-cache hits and misses. This
prints each worker's files in the order they ran, the workers' busy times (the run's wall
time is the larger), the compilation share, and the `FILE_COSTS` table to paste into
`tests/conftest.py`, with the two workers' totals that its schedule (longest file first,
each to the worker that is free first) would give.
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict

COMPILE = ("jaxpr_trace_duration", "jaxpr_to_mlir_module_duration", "backend_compile_duration")


def schedule(costs: dict[str, float], workers: int = 2) -> list[float]:
    """Busy time of each worker when the files go out longest first, each to the worker
    that is free first (what `pytest_collection_modifyitems` and xdist's `loadfile` do,
    up to xdist's queue of two files per worker)."""
    busy = [0.0] * workers
    for cost in sorted(costs.values(), reverse=True):
        busy[busy.index(min(busy))] += cost
    return busy


def main(path: str) -> None:
    lines = [json.loads(line) for line in open(path)]
    by_worker = defaultdict(list)
    for line in sorted(lines, key=lambda line: line["start"]):
        by_worker[line["worker"]].append(line)
    for worker, files in sorted(by_worker.items()):
        busy = sum(f["wall_s"] for f in files)
        compiled = sum(f.get(k, 0.0) for f in files for k in COMPILE)
        print(f"{worker}: {busy:7.1f} s busy, {compiled:6.1f} s tracing and compiling in-process")
        for f in files:
            spent = sum(f.get(k, 0.0) for k in COMPILE)
            print(f"    {f['file']:36s} {f['wall_s']:7.1f} s  (compile {spent:6.1f} s, cache hits "
                  f"{int(f.get('cache_hits', 0))}, misses {int(f.get('cache_misses', 0))})")
    costs = {line["file"]: line["wall_s"] for line in lines}
    print("\nFILE_COSTS = {")
    for name, cost in sorted(costs.items(), key=lambda item: -item[1]):
        print(f'    "{name}": {round(cost)},')
    print("}")
    print("longest-first schedule of these costs:", ", ".join(f"{b:.0f} s" for b in schedule(costs)))


if __name__ == "__main__":
    main(sys.argv[1])
