"""Throughput of the batched sweeps: how the cost grows with loads, speeds and
designs.

    python benchmarks/sweep.py [--accuracy fast] [--repeats 3]
    XLA_FLAGS=--xla_force_host_platform_device_count=2 python benchmarks/sweep.py --sharded

Seed 001 pair, paper optimum. Each row is one compiled call (compile time apart, median of
the repeats): `impact_sweep` over 1 … 1 024 loads at one speed, 16 and 1 024 loads at 4 and
16 speeds, `design_sweep` of 1 … 64 designs at 4 loads and one speed, and the batched
`regime_transition` of 1 and 16 designs (one bisection program, 400–1600 N·m, tolerance
1e-3). Then 1 024 loads in 16 chunks of 64 through `sweep_run.run_impact_sweep` (the
public path of `gearjax sweep --chunk 64`, its program compiled by a first call that is
not timed). Writes benchmarks/results/sweep.json. With `--sharded`: 16 loads and 16 designs on one device and
sharded over all devices (`devices="all"`, the public API, compilation included in a first
call that is not timed), written to benchmarks/results/sweep_sharded.json.
"""

from __future__ import annotations

import argparse
import statistics
import time

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from _common import machine, time_compiled_output, write  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402
from gearjax.pipeline import prepare as _prepare  # noqa: E402
from gearjax.sweep.designs import _design_sweep  # noqa: E402
from gearjax.sweep.loads import _impact_sweep  # noqa: E402
from gearjax.sweep.transition import _transition  # noqa: E402
from gearjax.sweep.run import run_impact_sweep  # noqa: E402
from gearjax.units import rpm_to_rad_per_s  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--accuracy", default="fast")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--sharded", action="store_true", help="one device vs all devices")
    args = parser.parse_args()
    if args.sharded:
        return sharded(args)
    scene = _prepare(gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                              effects=("impact",), accuracy=args.accuracy))
    rows = []

    def grid(loads, speeds):
        return jnp.linspace(2.0e5, 1.6e6, loads), rpm_to_rad_per_s(jnp.linspace(1000.0, 6000.0, speeds))

    def row(case, fn, fn_args, designs, loads, speeds):
        compile_s, run_s, runs, out = time_compiled_output(fn, *fn_args, repeats=args.repeats)
        finite = bool(np.all(np.isfinite(np.asarray(out.impact.force))))
        entry = {"case": case, "designs": designs, "loads": loads, "speeds": speeds, "compile_s": compile_s,
                 "run_s": run_s, "runs_s": runs, "load_cases_per_s": designs * loads / run_s,
                 "impact_points_per_s": designs * loads * speeds / run_s, "all_finite": finite}
        rows.append(entry)
        print(f"{case:14s} designs {designs:3d} loads {loads:3d} speeds {speeds:3d}  compile {compile_s:6.1f} s  "
              f"run {run_s * 1e3:9.1f} ms  {entry['load_cases_per_s']:8.1f} load cases/s  "
              f"{entry['impact_points_per_s']:9.1f} impact points/s", flush=True)

    for loads in (1, 4, 16, 64, 256, 1024):
        row("impact_sweep", _impact_sweep, (scene, *grid(loads, 1)), 1, loads, 1)
    for loads, speeds in ((16, 4), (16, 16), (1024, 16)):
        row("impact_sweep", _impact_sweep, (scene, *grid(loads, speeds)), 1, loads, speeds)

    def designs_of(count):
        scales = np.linspace(0.0, 3.0, count)
        return [eqx.tree_at(lambda s: s.modification.root_relief, scene, scene.modification.root_relief * float(k))
                for k in scales]

    for designs in (1, 4, 16, 64):
        row("design_sweep", _design_sweep, (gj.stack_scenes(designs_of(designs)), *grid(4, 1)), designs, 4, 1)
    for designs in (1, 16):
        arrays, static = eqx.partition(gj.stack_scenes(designs_of(designs)), eqx.is_array)
        bounds = (jnp.asarray(4.0e5), jnp.asarray(1.6e6), jnp.asarray(1e-3))
        compile_s, run_s, runs, out = time_compiled_output(_transition, arrays, static, *bounds, repeats=args.repeats)
        found = int(np.sum(~np.asarray(out[2]) & np.asarray(out[3])))
        rows.append({"case": "regime_transition", "designs": designs, "compile_s": compile_s, "run_s": run_s,
                     "runs_s": runs, "designs_per_s": designs / run_s, "switches_found": found})
        print(f"{'regime_trans.':14s} designs {designs:3d}  compile {compile_s:6.1f} s  run {run_s * 1e3:9.1f} ms  "
              f"{designs / run_s:8.2f} designs/s  ({found} with a switch in 400-1600 N m)", flush=True)
    torques_Nm = np.linspace(200.0, 1600.0, 1024)
    run_impact_sweep(scene, torques_Nm[:64], [5000.0], chunk=64)  # compiles the chunk program
    runs = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        report = run_impact_sweep(scene, torques_Nm, [5000.0], chunk=64)
        runs.append(time.perf_counter() - t0)
    run_s = statistics.median(runs)
    rows.append({"case": "run_impact_sweep chunks", "designs": 1, "loads": 1024, "speeds": 1, "chunk_length": 64,
                 "chunks": report["chunks"], "run_s": run_s, "runs_s": runs, "load_cases_per_s": 1024 / run_s,
                 "all_finite": bool(np.all(np.isfinite(report["impact_force_N"])))})
    print(f"{'chunked':14s} 1024 loads in {report['chunks']} chunks of 64  run {run_s * 1e3:9.1f} ms  "
          f"{1024 / run_s:8.1f} load cases/s", flush=True)
    write("sweep", {"machine": machine(), "accuracy": args.accuracy, "rows": rows})


def sharded(args) -> None:
    """Median run time of `impact_sweep` (16 loads) and `design_sweep` (16 designs, 4 loads)
    through the public API on the default device and sharded over `jax.devices()`."""
    scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                     effects=("impact",), accuracy=args.accuracy)
    designs = [eqx.tree_at(lambda s: s.modification.root_relief, scene, scene.modification.root_relief * float(k))
               for k in np.linspace(0.0, 3.0, 16)]
    calls = {
        "impact_sweep 16 loads": lambda devices: gj.impact_sweep(
            scene, torques_Nm=np.linspace(200.0, 1600.0, 16), speeds_rpm=[5000.0], devices=devices).impact.force,
        "design_sweep 16 designs x 4 loads": lambda devices: gj.design_sweep(
            designs, torques_Nm=[400.0, 800.0, 1200.0, 1600.0], speeds_rpm=[5000.0], devices=devices).impact.force,
    }
    rows = []
    for name, call in calls.items():
        for devices in (None, "all"):
            jax.block_until_ready(call(devices))
            runs = []
            for _ in range(args.repeats):
                t0 = time.perf_counter()
                jax.block_until_ready(call(devices))
                runs.append(time.perf_counter() - t0)
            count = 1 if devices is None else jax.device_count()
            rows.append({"case": name, "devices": count, "run_s": statistics.median(runs), "runs_s": runs})
            print(f"{name:36s} devices {count}  run {statistics.median(runs) * 1e3:8.1f} ms", flush=True)
    write("sweep_sharded", {"machine": machine(), "accuracy": args.accuracy, "rows": rows})


if __name__ == "__main__":
    main()
