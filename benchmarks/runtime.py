"""What the installed JAX costs and gives: the public calls a user makes, compile and run apart.

    python benchmarks/runtime.py [--repeats 5] [--rows te_batched te_designs ltca_iso ltca_slice cli] [--name NAME]

Run it under each interpreter to compare JAX versions back to back (`make` builds `.venv`
from the newest Python >= 3.12; a Python 3.11 venv gets jax 0.10.2). Rows:

* `te_batched`: unloaded TE of 100 random designs (seed 001's bounds), 64 positions per
  pitch x 64 face slices, plane of action, `jax.jit(jax.vmap(gj.simulate))` over
  `gj.stack_scenes`: the whole result is computed, as a user who reads `.tca` gets it;
* `te_designs`: the same designs through `gj.simulate_designs(scene, modifications,
  outputs=TE)`: the pair resolved once, only the TE returned;
* `ltca_iso`: uniform-stiffness LTCA of the paper optimum, 32 positions x 64 loads
  (100-2 000 N·m), `gj.load_sweep`;
* `ltca_slice`: slice LTCA (Palmgren's Hertz law), 41 slices, 32 positions, 1 000 N·m,
  `gj.load_sweep`;
* `cli_cold` / `cli_warm`: `gearjax run` of the default scene as a whole process, first
  with an empty cache directory, then again with the cache it wrote (medians of 3 warm).

Each jitted row: the first call's time (trace, lower, compile) and the median of
`--repeats` runs after one warm-up. Writes `benchmarks/results/NAME.json` (default
`runtime_jax<version>`).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import gearjax as gj  # before the first computation: its process settings (gearjax.runtime.versions)
import jax
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import first_and_runs, machine, write  # noqa: E402
from tca import random_designs  # noqa: E402

from gearjax.io.scene_file import default_scene  # noqa: E402


def te_batched(repeats):
    scene0, _ = default_scene()
    acc = gj.Accuracy(positions_per_pitch=64, face_slices=64, tca_method="plane_of_action")
    designs = random_designs(100, float(scene0.pair.normal_module), float(scene0.pair.face_width))
    batch = gj.stack_scenes([gj.Scene(scene0.pair, gj.FlankModification.from_vector(y), accuracy=acc,
                                      pairs=scene0.pairs) for y in designs])
    first, run, runs, out = first_and_runs(jax.jit(jax.vmap(gj.simulate)), batch, repeats=repeats)
    te = np.asarray(out.tca.transmission_error_line)
    return {"first_call_s": first, "run_s": run, "runs_s": runs, "te_peak_to_peak_um_mean": float(np.ptp(te, axis=-1).mean() * 1e3)}


def te_designs(repeats):
    scene0, _ = default_scene()
    acc = gj.Accuracy(positions_per_pitch=64, face_slices=64, tca_method="plane_of_action")
    designs = random_designs(100, float(scene0.pair.normal_module), float(scene0.pair.face_width))
    scene = gj.Scene(scene0.pair, accuracy=acc, pairs=scene0.pairs)
    modifications = gj.FlankModification.from_vector(designs)

    def call():
        return gj.simulate_designs(scene, modifications, outputs=_transmission_error)

    first, run, runs, te = first_and_runs(call, repeats=repeats)
    return {"first_call_s": first, "run_s": run, "runs_s": runs, "te_peak_to_peak_um_mean": float(np.ptp(np.asarray(te), axis=-1).mean() * 1e3)}


def _transmission_error(result):
    return result.tca.transmission_error_line


def load_sweep_row(compliance, slices, torques, repeats):
    scene0, _ = default_scene()
    scene = gj.Scene(scene0.pair, scene0.modification, compliance=compliance,
                     accuracy=gj.Accuracy(positions_per_pitch=32, face_slices=slices, tca_method="plane_of_action"),
                     operating=gj.OperatingPoint(torque=float(torques[0])))
    fn = jax.jit(gj.load_sweep)
    first, run, runs, out = first_and_runs(fn, scene, jax.numpy.asarray(torques), repeats=repeats)
    lte = np.asarray(out.ltca.transmission_error_line)
    return {"first_call_s": first, "run_s": run, "runs_s": runs, "lte_mean_um_first_load": float(lte[0].mean() * 1e3)}


def cli_rows(warm_repeats=3):
    """`gearjax run` as whole processes: one cold (empty cache), then `warm_repeats` warm."""
    command = [sys.executable, "-m", "gearjax.cli", "run", "--json"]
    with tempfile.TemporaryDirectory(prefix="gearjax-bench-cache-") as cache:
        env = {**os.environ, "GEARJAX_CACHE_DIR": cache}
        times = []
        for _ in range(1 + warm_repeats):
            t0 = time.perf_counter()
            proc = subprocess.run(command, env=env, capture_output=True, text=True)
            times.append(time.perf_counter() - t0)
            if proc.returncode != 0:
                raise RuntimeError(proc.stderr[-2000:])
    return {"cli_cold_s": times[0], "cli_warm_s": statistics.median(times[1:]), "cli_warm_runs_s": times[1:]}


ROWS = {
    "te_batched": te_batched,
    "te_designs": te_designs,
    "ltca_iso": lambda repeats: load_sweep_row(gj.IsoCompliance(), 64, np.linspace(1e5, 2e6, 64), repeats),
    "ltca_slice": lambda repeats: load_sweep_row(gj.SliceCompliance(), 41, np.asarray([1e6]), repeats),
    "cli": lambda repeats: cli_rows(),
}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--rows", nargs="+", default=list(ROWS), choices=list(ROWS), help="rows to run (default all)")
    parser.add_argument("--name", default=None)
    args = parser.parse_args(argv)
    out = {"machine": {**machine(), "python": sys.version.split()[0]}, "rows": {}}
    for row in args.rows:
        out["rows"][row] = ROWS[row](args.repeats)
    for key, row in out["rows"].items():
        print(key, {k: (round(v, 4) if isinstance(v, float) else v) for k, v in row.items() if not k.endswith("runs_s")})
    path = write(args.name or f"runtime_jax{jax.__version__}", out)
    print("wrote", path)


if __name__ == "__main__":
    main()
