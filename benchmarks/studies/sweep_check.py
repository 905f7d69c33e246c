"""The default scene's impact sweep at two accuracies: is the published force map converged?

    python benchmarks/studies/sweep_check.py [--accuracy reference] [--check-slices 161] [--torque-Nm 100:1600:16] [--speed-rpm 1000:6000:6]

`gj.impact_sweep` of the built-in scene (seed 001 pair, paper optimum) on the torque x speed
grid at `--accuracy`, and again with `--check-slices` face slices (4x the preset's contact
steps). Prints the largest relative difference of F_s, whether every regime agrees, the
regime switch and the Harris curve's minimum, and writes them to
`docs/results/sweep_check.json`.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402


import gearjax as gj  # noqa: E402
from gearjax.cli.sweep import parse_list  # noqa: E402
from gearjax.io.scene_file import default_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def sweep(accuracy: gj.Accuracy, torques, speeds):
    scene0, _ = default_scene()
    scene = gj.Scene(scene0.pair, scene0.modification, operating=scene0.operating, effects=("impact",), accuracy=accuracy)
    out = gj.impact_sweep(scene, torques_Nm=torques, speeds_rpm=speeds, throw=False)
    return {
        "force_N": np.asarray(out.impact.force),
        "regime": np.asarray(gj.enum_name(out.impact.regime)),
        "converged": bool((np.asarray(gj.enum_name(out.impact.result)) == "successful").all()
                          and (np.asarray(gj.enum_name(out.ltca.result)) == "successful").all()),
        "lte_pp_um": np.asarray(out.ltca.lte_peak_to_peak_line) * 1e3,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--accuracy", default="reference")
    parser.add_argument("--check-slices", type=int, default=161)
    parser.add_argument("--torque-Nm", default="100:1600:16")
    parser.add_argument("--speed-rpm", default="1000:6000:6")
    args = parser.parse_args()
    torques, speeds = parse_list("--torque-Nm", args.torque_Nm), parse_list("--speed-rpm", args.speed_rpm)
    base = gj.Accuracy.preset(args.accuracy)
    a = sweep(base, torques, speeds)
    b = sweep(base.finer(args.check_slices), torques, speeds)
    difference = np.abs(a["force_N"] / b["force_N"] - 1.0)
    edge = a["regime"][:, 0] == "edge"
    result = {
        "accuracy": args.accuracy, "check_face_slices": args.check_slices,
        "torques_Nm": list(map(float, torques)), "speeds_rpm": list(map(float, speeds)),
        "largest_force_difference": float(difference.max()), "regimes_equal": bool((a["regime"] == b["regime"]).all()),
        "converged": [a["converged"], b["converged"]],
        "first_edge_torque_Nm": float(np.asarray(torques)[edge][0]) if edge.any() else None,
        "harris_minimum_Nm": float(np.asarray(torques)[np.argmin(a["lte_pp_um"])]),
        "harris_minimum_lte_pp_um": float(a["lte_pp_um"].min()),
        "force_N": a["force_N"].tolist(), "force_N_at_check": b["force_N"].tolist(),
    }
    (ROOT / "docs" / "results" / "sweep_check.json").write_text(json.dumps(result, indent=1))
    print(json.dumps({k: v for k, v in result.items() if not k.startswith("force_N")}, indent=1))


if __name__ == "__main__":
    main()
