"""LTCA benchmark: cost against the number of contact points, and load-case throughput.

    python benchmarks/ltca.py [--slices 5 11 21 41] [--loads 1 64 1024]

1. Time per load case (one torque, a full mesh cycle of 32 positions) for a growing number
   of contact points per position (tooth pairs x face slices), slice compliance model.
2. Throughput (load cases per second) of one compiled call over 1, 64 and 1024 torques
   (`gearjax.sweep.load_sweep`: TCA once, LTCA `vmap`-ed over the loads).

Compile time and steady-state time (median, after a warm-up, `block_until_ready`) are
reported separately and written to benchmarks/results/ltca.json after every case.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import jax
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine, time_compiled, write  # noqa: E402

jax.config.update("jax_enable_x64", True)

import gearjax as gj  # noqa: E402
from gearjax.papers.seed001 import paper_optimum  # noqa: E402
from gearjax.sweep.loads import _load_sweep  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slices", type=int, nargs="+", default=[5, 11, 21, 41])
    parser.add_argument("--loads", type=int, nargs="+", default=[1, 64, 1024])
    parser.add_argument("--positions", type=int, default=32)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)

    pair = gj.InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0)
    out = {"machine": machine(), "points": [], "throughput": []}

    for n in args.slices:
        acc = gj.Accuracy(positions_per_pitch=args.positions, face_slices=n)
        scene = gj.Scene(pair, paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0), accuracy=acc)
        torques = jax.numpy.asarray([1.0e6])
        compile_s, run_s, runs = time_compiled(_load_sweep, scene, torques, repeats=args.repeats)
        points = len(scene.pairs) * n
        out["points"].append({"slices": n, "points_per_position": points, "compile_s": compile_s, "run_s": run_s,
                              "ms_per_position": 1e3 * run_s / args.positions})
        print(f"{n:3d} slices ({points:4d} points/position): compile {compile_s:6.2f} s, "
              f"load case {run_s * 1e3:8.1f} ms", flush=True)
        write("ltca", out)

    acc = gj.Accuracy(positions_per_pitch=args.positions, face_slices=21)
    scene = gj.Scene(pair, paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0), accuracy=acc)
    for m in args.loads:
        torques = jax.numpy.asarray(np.linspace(1.0e5, 2.0e6, m))
        compile_s, run_s, runs = time_compiled(_load_sweep, scene, torques, repeats=args.repeats if m < 1000 else 1)
        out["throughput"].append({"loads": m, "compile_s": compile_s, "run_s": run_s, "loads_per_s": m / run_s})
        print(f"{m:5d} loads: compile {compile_s:6.2f} s, run {run_s:8.3f} s ({m / run_s:8.1f} load cases/s)", flush=True)
        write("ltca", out)

    print("\n| face slices | points/position | compile (s) | load case (ms) |")
    print("|---:|---:|---:|---:|")
    for r in out["points"]:
        print(f"| {r['slices']} | {r['points_per_position']} | {r['compile_s']:.1f} | {r['run_s'] * 1e3:.0f} |")
    print("\n| loads | compile (s) | run (s) | load cases/s |")
    print("|---:|---:|---:|---:|")
    for r in out["throughput"]:
        print(f"| {r['loads']} | {r['compile_s']:.1f} | {r['run_s']:.3f} | {r['loads_per_s']:.1f} |")


if __name__ == "__main__":
    main()
