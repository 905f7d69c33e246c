"""Loaded point contact of the double-circular-arc seed pair (m_n 4, z 24/24, b 55 mm,
β 15°) at a pinion torque, at one or more accuracy presets, so that the figures can be
compared between grids (`gearjax.ltca.point_analysis`; not yet a stage of `simulate`).

    python tools/dca_point_contact.py [--torque-Nm 100] [--accuracy fast default default@64x41]

An accuracy is a preset's name, or `PRESET@PxS`: the preset with P positions per pitch and S
face slices (to tell the two grids' effects apart).

Prints, per preset, a JSON line: the loaded and unloaded TE peak-to-peak along the line of
action, the gear's lag and the approach it means, the loads, the pairs' tangent stiffness,
the mesh stiffness as a normal stiffness (dT/dΘ over the arm squared), the contact ellipse
and pressure, and the profile-direction relative curvature B beside the rack arcs'
(1/ρ_a − 1/ρ_f)/2, which the curvatures of the generated flanks should approach.
"""

from __future__ import annotations

import argparse
import json
import time

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax.ltca.point_analysis import point_contact_analysis  # noqa: E402
from gearjax.papers.double_arc import SEED_CASE  # noqa: E402

WINDOW = (-2, -1, 0, 1, 2, 3)


def parse_accuracy(spec: str) -> gj.Accuracy:
    """`PRESET` or `PRESET@PxS` (positions per pitch × face slices)."""
    name, _, grid = spec.partition("@")
    accuracy = gj.Accuracy.preset(name)
    if grid:
        positions, slices = (int(v) for v in grid.lower().split("x"))
        accuracy = accuracy.replace(positions_per_pitch=positions, face_slices=slices)
    return accuracy


def figures(accuracy: str, torque_Nm: float) -> dict:
    pair = gj.DoubleArcGearPair(SEED_CASE["teeth"], SEED_CASE["normal_module"], SEED_CASE["helix_angle_deg"],
                                SEED_CASE["face_width"], 0.0)
    start = time.perf_counter()
    grid = parse_accuracy(accuracy)
    tca = gj.simulate(gj.Scene(pair, pairs=WINDOW, accuracy=grid), throw=False).tca
    r = eqx.filter_jit(point_contact_analysis)(pair.resolve(), tca, jnp.asarray(1e3 * torque_Nm))
    jax.block_until_ready(r.rotation)
    ra2 = float(tca.action_radius[1])
    on = np.asarray(r.loads) > 0
    k_normal = np.asarray(r.mesh_stiffness) / np.asarray(r.arms).max(axis=1) ** 2
    rack = pair.rack
    m = float(pair.normal_module)
    rack_b = 0.5 * (1.0 / (rack.convex_radius * m) - 1.0 / (rack.concave_radius * m))
    curvature_b = np.asarray(r.curvature_b)[on]
    span = lambda x: [round(float(np.min(x)), 4), round(float(np.max(x)), 4)]  # noqa: E731
    return {
        "accuracy": accuracy,
        "positions_per_pitch": grid.positions_per_pitch,
        "face_slices": grid.face_slices,
        "torque_Nm": torque_Nm,
        "seconds_with_compilation": round(time.perf_counter() - start, 1),
        "te_peak_to_peak_um": 1e3 * ra2 * float(tca.te_peak_to_peak),
        "lte_peak_to_peak_um": 1e3 * ra2 * float(jnp.max(r.transmission_error) - jnp.min(r.transmission_error)),
        "lag_urad": span(1e6 * np.asarray(r.rotation)),
        "approach_um": span(1e3 * ra2 * np.asarray(r.rotation)),
        "pairs_loaded": [int(on.sum(1).min()), int(on.sum(1).max())],
        "max_pair_load_N": float(np.asarray(r.loads).max()),
        "pair_stiffness_N_per_mm": span(np.asarray(r.stiffness)[on]),
        "mesh_stiffness_normal_N_per_mm": span(k_normal),
        "linear_compliance_um_per_N": span(1e3 * np.asarray(r.linear_compliance)[on]),
        "semi_axes_mm": [round(float(np.asarray(r.semi_major)[on].max()), 4),
                         round(float(np.asarray(r.semi_minor)[on].max()), 4)],
        "max_pressure_MPa": float(np.asarray(r.max_pressure).max()),
        "relative_curvature_A_per_mm": span(np.asarray(r.curvature_a)[on]),
        "relative_curvature_B_per_mm": span(curvature_b),
        "rack_relative_curvature_B_per_mm": rack_b,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--torque-Nm", type=float, default=100.0)
    parser.add_argument("--accuracy", nargs="+", default=["fast", "default"])
    args = parser.parse_args()
    for accuracy in args.accuracy:
        print(json.dumps(figures(accuracy, args.torque_Nm)), flush=True)


if __name__ == "__main__":
    main()
