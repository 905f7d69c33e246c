"""LTE peak-to-peak, mean LTE and maximum pressure of seed 001's pair (paper optimum) over
positions per pitch x face slices, at 400, 1000 and 1600 N·m, LTCA only, with the
(position, pair, slice) of the pressure maximum (run from the repository root; about
10 min). The reference preset is 128 positions x 81 slices."""
import time

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)
import gearjax as gj  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402
from gearjax.io.report import result_dict  # noqa: E402

for positions in (32, 64, 128, 256):
    for slices in (21, 41, 81, 161):
        if positions * slices > 128 * 161:
            continue
        accuracy = gj.Accuracy.preset("default").replace(face_slices=slices, positions_per_pitch=positions,
                                                         contact_max_steps=80)
        for torque in (400.0, 1000.0, 1600.0):
            scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=torque),
                             effects=("ltca",), accuracy=accuracy)
            t0 = time.perf_counter()
            result = gj.simulate(scene)
            d = result_dict(scene, result)["ltca"]
            pressure = np.asarray(result.ltca.pressure)
            at = np.unravel_index(np.argmax(pressure), pressure.shape)
            print(f"positions {positions:3d} slices {slices:3d} {torque:6.0f} N·m: LTE p-p {d['lte_peak_to_peak_um']:.4f} µm, "
                  f"mean {d['lte_mean_um']:.4f} µm, max pressure {d['max_pressure_MPa']:.2f} MPa at (position, pair, "
                  f"slice) {tuple(int(i) for i in at)}, {time.perf_counter() - t0:.1f} s", flush=True)
