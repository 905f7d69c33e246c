"""Mesh-in impact of the double-circular-arc seed pair (m_n 4, z 24/24, b 55 mm, β 15°) on
its point-contact loaded model, per contact zone, at one or more accuracies, so that the
figures can be compared between grids (`gearjax.impact` on `ToothSectionCompliance`).

    python benchmarks/studies/dca_impact.py [--torque-Nm 50 100 200] [--speed-rpm 200]
                               [--accuracy default default@64x21 default@32x41]
                               [--axial-pitch-error-um 0 20 -20 373.2]

An accuracy is a preset's name, or `PRESET@PxS`: the preset with P positions per pitch and S
face slices. One JSON line per accuracy, torque and error, printed as each finishes: per zone
(0 convex driving, 1 concave driving) the first contact (pinion angle, axial position, the
regime), the normal velocity, the local stiffness fit $F = K_s\\delta^n$, the equivalent
mass, the peak force and approach, and the energy balance $\\tfrac12 m v^2$ against
$K_s\\delta^{n+1}/(n+1)$; with the run time (s), and for an accuracy's first case
the compile time apart. Every axial pitch error
$\\Delta_\\alpha$ (µm, the scene file's `axial_pitch_error_um`) runs in the program of its
accuracy (the error is a leaf of the scene).
Results are printed with their codes (`throw=False`): a zone whose gap jumps across zero
reports `first_contact_jump` and the angle of the jump.
"""

from __future__ import annotations

import argparse
import json
import time
import tomllib

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax._solution import enum_name  # noqa: E402
from gearjax.io.scene_file import scene_from_dict  # noqa: E402
from gearjax.papers.double_arc import seed_scene_file  # noqa: E402


def scene_text(accuracy: str, torque_nm: float, speed_rpm: float) -> str:
    """The seed pair's scene file with the impact, at `accuracy` (`PRESET` or `PRESET@PxS`)."""
    grid = gj.Accuracy.from_spec(accuracy)
    analysis = {"accuracy": accuracy.partition("@")[0], "effects": ["impact"],
                "positions_per_pitch": grid.positions_per_pitch, "face_slices": grid.face_slices}
    return seed_scene_file(torque_nm, speed_rpm, analysis)


def seed_scene(accuracy: str, torque_nm: float, speed_rpm: float, axial_pitch_error_um: float = 0.0):
    """`scene_text`'s scene with the pair's axial pitch error (µm; checked by the pair)."""
    table = tomllib.loads(scene_text(accuracy, torque_nm, speed_rpm))
    table["pair"]["axial_pitch_error_um"] = axial_pitch_error_um
    return scene_from_dict(table)


def zones(result) -> list[dict]:
    """Per zone, the impact's figures (JSON-ready)."""
    imp = result.impact
    out = []
    for z in range(imp.force.shape[0]):
        k, n = float(imp.stiffness.coefficient[z]), float(imp.stiffness.exponent[z])
        delta = float(imp.approach[z])
        out.append({
            "zone": z,
            "result": str(enum_name(imp.result)[z]),
            "regime": str(imp.regime_name[z]),
            "pair_index": int(imp.pair_index[z]),
            "pinion_angle_deg": float(np.degrees(imp.pinion_angle[z])),
            "face_position_mm": float(imp.slice_z[z]),
            "velocity_mm_per_s": float(imp.velocity[z]),
            "gap_closing_velocity_mm_per_s": float(imp.gap_closing_velocity[z]),
            "stiffness_coefficient": k,
            "stiffness_exponent": n,
            "fit_error": float(imp.stiffness.fit_error[z]),
            "equivalent_mass_kg": float(imp.mass[z]) * 1e3,
            "force_N": float(imp.force[z]),
            "approach_um": delta * 1e3,
            "kinetic_energy_mJ": float(imp.kinetic_energy[z]),
            "strain_energy_mJ": k * delta ** (n + 1.0) / (n + 1.0),
            "search_steps": int(imp.search_steps[z]),
        })
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--torque-Nm", type=float, nargs="+", default=[100.0])
    parser.add_argument("--speed-rpm", type=float, default=200.0)
    parser.add_argument("--accuracy", nargs="+", default=["default"])
    parser.add_argument("--axial-pitch-error-um", type=float, nargs="+", default=[0.0])
    args = parser.parse_args(argv)
    for accuracy in args.accuracy:
        first_run = True
        for torque in args.torque_Nm:
            for error_um in args.axial_pitch_error_um:
                scene = seed_scene(accuracy, torque, args.speed_rpm, error_um)
                start = time.perf_counter()
                result = jax.block_until_ready(gj.simulate(scene, throw=False))
                run = time.perf_counter() - start
                line = {"accuracy": accuracy, "torque_Nm": torque, "speed_rpm": args.speed_rpm,
                        "axial_pitch_error_um": error_um, "slices": scene.accuracy.face_slices,
                        "positions_per_pitch": scene.accuracy.positions_per_pitch, "zones": zones(result)}
                if first_run:  # the accuracy's program compiled in this call: time a second one
                    start = time.perf_counter()
                    jax.block_until_ready(gj.simulate(scene, throw=False))
                    second = time.perf_counter() - start
                    line["compile_s"], run = run - second, second
                    first_run = False
                line["run_s"] = run
                print(json.dumps(line), flush=True)


if __name__ == "__main__":
    main()
