"""TCA benchmark: a transmission-error curve for 1, 100 and 10 000 designs batched.

    python benchmarks/tca.py [--designs 1 100 10000] [--methods plane_of_action surface]

Each design is the seed 001 pair with a random six-parameter modification drawn within the
paper's bounds. One compiled call evaluates the whole batch (`vmap`, chunked with
`lax.map` to bound memory). Compile time and steady-state time (median of repeats, after
a warm-up, `block_until_ready`) are reported separately and written to
`benchmarks/results/tca.json` after every case, so an interrupted run keeps what it
finished.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine, time_compiled, write  # noqa: E402

jax.config.update("jax_enable_x64", True)

import gearjax as gj  # noqa: E402
from gearjax.tca import pair_window, tooth_contact_analysis  # noqa: E402


def random_designs(n: int, module: float, face_width: float, seed: int = 0) -> np.ndarray:
    """y1..y6 (mm) uniform in seed 001's bounds: amounts 0.001-0.015 m_n, lengths
    0.1-0.8 m_n, unmodified length 0-0.5 b."""
    rng = np.random.default_rng(seed)
    lo = np.array([0.001, 0.001, 0.1, 0.1, 0.001, 0.0]) * np.array([module] * 5 + [face_width])
    hi = np.array([0.015, 0.015, 0.8, 0.8, 0.015, 0.5]) * np.array([module] * 5 + [face_width])
    return lo + (hi - lo) * rng.random((n, 6))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--designs", type=int, nargs="+", default=[1, 100, 10000])
    parser.add_argument("--methods", nargs="+", default=["plane_of_action", "surface"])
    parser.add_argument("--positions", type=int, default=64)
    parser.add_argument("--slices", type=int, default=21)
    parser.add_argument("--chunk", type=int, default=256, help="designs per vmapped chunk")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--name", default="tca", help="results file benchmarks/results/NAME.json")
    args = parser.parse_args(argv)

    pair = gj.InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0)
    pairs = pair_window(pair)
    rows = []
    for method in args.methods:
        accuracy = gj.Accuracy(positions_per_pitch=args.positions, face_slices=args.slices, tca_method=method)

        def te_curve(y):
            depth = gj.FlankDepth(pinion=gj.FlankModification.from_vector(y))
            return tooth_contact_analysis(pair, depth, accuracy=accuracy, pairs=pairs).transmission_error

        for n in args.designs:
            chunk = min(n, args.chunk)

            @jax.jit
            def batch(ys):
                return jax.lax.map(te_curve, ys, batch_size=chunk)

            ys = jnp.asarray(random_designs(n, 5.0, 42.0))
            repeats = args.repeats if n * (1 if method == "plane_of_action" else 100) < 200_000 else 1
            compile_s, run_s, runs = time_compiled(batch, ys, repeats=repeats)
            te = np.asarray(batch(ys))
            row = {
                "method": method,
                "designs": n,
                "positions": args.positions,
                "slices": args.slices,
                "chunk": chunk,
                "compile_s": compile_s,
                "run_s": run_s,
                "runs_s": runs,
                "designs_per_s": n / run_s,
                "te_p2p_um_median": float(np.median(np.ptp(te, axis=1)) * float(pair.base_radius[1]) * 1e3),
            }
            rows.append(row)
            print(f"{method:16s} {n:6d} designs: compile {compile_s:6.2f} s, run {run_s:9.4f} s "
                  f"({n / run_s:10.1f} designs/s)", flush=True)
            write(args.name, {"machine": machine(), "rows": rows})

    print("\n| method | designs | compile (s) | run (s) | designs/s |")
    print("|---|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['method']} | {r['designs']} | {r['compile_s']:.2f} | {r['run_s']:.4f} | {r['designs_per_s']:.1f} |")


if __name__ == "__main__":
    main()
