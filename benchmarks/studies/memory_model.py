"""The memory model of `gearjax.runtime.resources`: its constants from XLA's memory plan, and its
estimate against the measured peak memory of larger scenes.

    python benchmarks/studies/memory_model.py

Each size runs in a fresh process: the default scene (seed 001 pair, paper optimum,
1000 N·m, LTCA, `default` accuracy) with `face_slices` changed. For 21, 81 and 161 slices
it prints XLA's temporary buffer size of the compiled `simulate` program
(`Compiled.memory_analysis()`) and the constants c (per slice pair) and c1 (per slice)
that these give; for 401 and 801 slices it runs the program and compares the growth of
the process's peak resident memory over the 21-slice process (the runtime and the
compiler take the same there) with `gearjax.runtime.resources.estimate_bytes`.
"""

from __future__ import annotations

import json
import subprocess
import sys

CHILD = """
import json, resource, sys, dataclasses
import jax
jax.config.update("jax_enable_x64", True)
import gearjax as gj
from gearjax.runtime.resources import estimate_bytes
from gearjax.pipeline import prepare as _prepare, simulate_program as _simulate
from gearjax.io.scene_file import default_scene
scene, _ = default_scene()
scene = dataclasses.replace(scene, effects=frozenset({"ltca"}),
                            accuracy=scene.accuracy.replace(face_slices=int(sys.argv[1])))
prepared = _prepare(scene)
compiled = _simulate.lower(prepared).compile()
plan = compiled.compiled.memory_analysis()
jax.block_until_ready(compiled(prepared))
print(json.dumps({"slices": int(sys.argv[1]), "temp_bytes": plan.temp_size_in_bytes,
                  "output_bytes": plan.output_size_in_bytes, "estimate_bytes": estimate_bytes(scene),
                  "positions": scene.accuracy.positions_per_pitch * scene.pitches, "pairs": len(scene.pairs),
                  "peak_rss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}))
"""


def run(slices: int) -> dict:
    out = subprocess.run([sys.executable, "-c", CHILD, str(slices)], capture_output=True, text=True, timeout=1800)
    if out.returncode != 0:
        raise SystemExit(out.stderr[-3000:])
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    small = {s: run(s) for s in (21, 81, 161)}
    pk8 = small[21]["positions"] * small[21]["pairs"] * 8
    s1, s2, s0 = (small[k]["slices"] + 2 for k in (81, 161, 21))
    c = (small[161]["temp_bytes"] - small[81]["temp_bytes"]) / ((s2**2 - s1**2) * pk8)
    c1 = (small[21]["temp_bytes"] - c * s0**2 * pk8) / (s0 * pk8)
    for k, r in small.items():
        print(f"{k:4d} slices: XLA temporary buffers {r['temp_bytes'] / 1e6:8.1f} MB, estimate {r['estimate_bytes'] / 1e6:8.1f} MB")
    print(f"constants from the plan: c = {c:.2f} words per position, pair and slice pair; c1 = {c1:.0f} per slice")
    base = small[21]["peak_rss_bytes"]
    for slices in (401, 801):
        r = run(slices)
        grown = r["peak_rss_bytes"] - base
        print(f"{slices:4d} slices: peak memory {r['peak_rss_bytes'] / 1e9:.2f} GB, {grown / 1e9:.2f} GB over 21 slices; "
              f"estimate {r['estimate_bytes'] / 1e9:.2f} GB (ratio measured/estimate {grown / r['estimate_bytes']:.2f})")


if __name__ == "__main__":
    main()
