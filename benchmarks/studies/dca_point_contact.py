"""Loaded point contact of the double-circular-arc seed pair (m_n 4, z 24/24, b 55 mm,
β 15°) at a pinion torque, at one or more accuracy presets, so that the figures can be
compared between grids (`gearjax.ltca.point_analysis`, the `ltca` stage of this family).

    python benchmarks/studies/dca_point_contact.py [--torque-Nm 100] [--accuracy fast default default@64x41]

An accuracy is a preset's name, or `PRESET@PxS`: the preset with P positions per pitch and S
face slices (to tell the two grids' effects apart).

    python benchmarks/studies/dca_point_contact.py --peak-error 9 21 41 [--accuracy default@32x81]

instead measures how well a parabola through three slices finds a point contact's peak:
the rigid TCA at the (fine) accuracy gives each contact's slice TE along the face; that
curve, linearly interpolated, is resampled at the slice spacing of 9, 21, 41 slices (ten
offsets each) and the parabola's peak (as `closest_contact` fits it) compared with the
fine curve's largest sample (the rigid TE of this conjugate pair, the largest sample over
the slices, varies by under 0.004 µm at 41 slices already); one JSON line per slice count:
the peak error's range (µm along the line of action) over every contact, position and
offset (`samples`) whose peak lies inside the face.

Prints, per preset, a JSON line: Table 1's meshing stiffness K (`meshing_stiffness`, on
grids of 21 face slices or more), the loaded and unloaded TE peak-to-peak along the line of
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
from gearjax.ltca.point_analysis import parabola_peak, point_contact_analysis  # noqa: E402
from gearjax.papers.double_arc import SEED_CASE  # noqa: E402
from gearjax.papers.meshing_stiffness import meshing_stiffness  # noqa: E402

WINDOW = (-2, -1, 0, 1, 2, 3)


def figures(accuracy: str, torque_Nm: float) -> dict:
    pair = gj.DoubleArcGearPair(SEED_CASE["teeth"], SEED_CASE["normal_module"], SEED_CASE["helix_angle_deg"],
                                SEED_CASE["face_width"], 0.0)
    start = time.perf_counter()
    grid = gj.Accuracy.from_spec(accuracy)
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
        # Table 1's K (`meshing_stiffness`: its own loaded program; grids a loaded scene accepts)
        "meshing_stiffness_N_per_mm": (
            [float(v) for v in meshing_stiffness(pair, 1e3 * torque_Nm, grid).stiffness]
            if grid.face_slices >= gj.ToothSectionCompliance.min_face_slices else None
        ),
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


def peak_errors(accuracy: str, slice_counts: list[int]) -> list[dict]:
    pair = gj.DoubleArcGearPair(SEED_CASE["teeth"], SEED_CASE["normal_module"], SEED_CASE["helix_angle_deg"],
                                SEED_CASE["face_width"], 0.0)
    grid = gj.Accuracy.from_spec(accuracy)
    tca = gj.simulate(gj.Scene(pair, pairs=WINDOW, accuracy=grid), throw=False).tca
    um = 1e3 * float(tca.action_radius[1])
    n_mid = tca.slice_z.shape[-1] - 2  # the last two slices are the face ends
    z = np.asarray(tca.slice_z)[:n_mid]
    order = np.argsort(z)
    z = z[order]
    te = np.where(np.asarray(tca.valid), np.asarray(tca.slice_te), -np.inf)[..., :n_mid][..., order] * um
    curves = [row for row in te.reshape(-1, n_mid) if np.isfinite(row).sum() > 3]
    rows = []
    for count in slice_counts:
        spacing = float(pair.face_width) / count  # slices sit at the middles of equal parts of the face
        errors = []
        for row in curves:
            ok = np.isfinite(row)
            zs, ts = z[ok], row[ok]
            top = int(np.argmax(ts))
            if zs[top] - zs[0] < spacing or zs[-1] - zs[top] < spacing:
                continue  # within a spacing of a face end: `closest_contact` fits through the end there
            for offset in np.linspace(0.0, spacing, 10, endpoint=False):
                v = np.interp(np.arange(zs[0] + offset, zs[-1], spacing), zs, ts)
                j = int(np.argmax(v))
                if j == 0 or j == v.size - 1:
                    continue
                _, peak, _ = parabola_peak((-1.0, 0.0, 1.0), (v[j - 1], v[j], v[j + 1]))
                errors.append(float(peak) - ts[top])
        rows.append({"accuracy": accuracy, "face_slices": count, "spacing_mm": round(float(spacing), 3),
                     "samples": len(errors), "peak_error_um": [round(float(np.min(errors)), 3),
                                                                round(float(np.max(errors)), 3)]})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--torque-Nm", type=float, default=100.0)
    parser.add_argument("--accuracy", nargs="+", default=None)
    parser.add_argument("--peak-error", type=int, nargs="+", metavar="SLICES",
                        help="the parabola's peak error at these slice counts, from the first --accuracy's TCA")
    args = parser.parse_args()
    if args.peak_error:
        for row in peak_errors((args.accuracy or ["default@32x81"])[0], args.peak_error):
            print(json.dumps(row), flush=True)
        return
    for accuracy in args.accuracy or ["fast", "default"]:
        print(json.dumps(figures(accuracy, args.torque_Nm)), flush=True)


if __name__ == "__main__":
    main()
