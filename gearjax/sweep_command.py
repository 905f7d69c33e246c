"""`gearjax sweep`: the mesh-in impact over a torque × speed grid (`gearjax.sweep.impact_sweep`),
written as `sweep.json` and `sweep.npz`, optionally plotted.

    gearjax sweep [SCENE.toml] --torque-Nm LIST --speed-rpm LIST [--out DIR] [--json] [--plot]

A LIST is comma-separated numbers (`100,400,1000`) or `start:stop:count` (`count` evenly
spaced values from `start` to `stop`, both included).
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np


class ListError(ValueError):
    """A bad value list on the command line; the message names the option."""


def parse_list(option: str, text: str) -> np.ndarray:
    """`"100,400,1000"` or `"start:stop:count"` as a 1-D float array of finite values >= 0.

    Raises:
        ListError: empty list, a value that is not a number, non-finite or negative, a count
            that is not an integer >= 1, or a range whose stop is below its start.
    """
    text = text.strip()
    if not text:
        raise ListError(f"{option}: empty list; give numbers like 100,400,1000 or start:stop:count")
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise ListError(f"{option}: a range is start:stop:count; got {text!r}")
        start, stop = (_number(option, p) for p in parts[:2])
        try:
            count = int(parts[2])
        except ValueError:
            raise ListError(f"{option}: the count of start:stop:count must be an integer >= 1; got {parts[2]!r}") from None
        if count < 1:
            raise ListError(f"{option}: the count of start:stop:count must be an integer >= 1; got {count}")
        if stop < start:
            raise ListError(f"{option}: the range stop {stop:g} is below its start {start:g}")
        values = np.linspace(start, stop, count)
    else:
        values = np.array([_number(option, p) for p in text.split(",")])
    return values


def _number(option: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ListError(f"{option}: {text.strip()!r} is not a number") from None
    if not math.isfinite(value) or value < 0:
        raise ListError(f"{option}: values must be finite numbers >= 0; got {text.strip()}")
    return value


def run_command(scene_path: str | None, torque: str, speed: str, out: str | None, as_json: bool, plot: bool) -> int:
    from .scene_file import SceneFileError, default_scene, load_scene

    try:
        torques_Nm = parse_list("--torque-Nm", torque)
        speeds_rpm = parse_list("--speed-rpm", speed)
        scene, _ = default_scene() if scene_path is None else load_scene(scene_path)
        if "impact" not in scene.effects:
            raise SceneFileError("analysis.effects: the sweep needs effects = [\"impact\"] in the scene file")
    except (ListError, SceneFileError) as err:
        print(f"gearjax: error: {err}", file=sys.stderr)
        return 2
    from .sweep import impact_sweep

    start = time.perf_counter()
    sweep = impact_sweep(scene, torques_Nm=torques_Nm, speeds_rpm=speeds_rpm, throw=False)
    report = sweep_dict(scene, sweep, time.perf_counter() - start)
    files = []
    if out is not None:
        directory = Path(out)
        directory.mkdir(parents=True, exist_ok=True)
        (directory / "sweep.json").write_text(json.dumps({"sweep": report}, indent=2))
        np.savez(directory / "sweep.npz", **{k: np.asarray(v) for k, v in report.items() if isinstance(v, list)})
        files += [str(directory / "sweep.json"), str(directory / "sweep.npz")]
        if plot:
            files += write_plots(report, directory)
    report["files"] = files
    print(json.dumps({"sweep": report}, indent=2) if as_json else summary(report))
    return 0


def sweep_dict(scene, sweep, wall_time_s: float) -> dict:
    """The sweep in the usual units (keys in the README); nested lists are [torque][speed]."""
    from ._solution import RESULTS, enum_name
    from .optimize.command import _accuracy_name

    imp, ltca = sweep.impact, sweep.ltca
    rb2 = float(np.asarray(ltca.action_radius).reshape(-1, 2)[0, 1])
    lte = np.asarray(ltca.transmission_error)
    return {
        "torque_Nm": np.asarray(sweep.torques_Nm).tolist(),
        "speed_rpm": np.asarray(sweep.speeds_rpm).tolist(),
        "impact_force_N": np.asarray(imp.force).tolist(),
        "impact_velocity_mm_per_s": np.asarray(imp.velocity).tolist(),
        "impact_regime": np.asarray(enum_name(imp.regime)).tolist(),
        "impact_contact_kind": np.asarray(enum_name(imp.kind)).tolist(),
        "impact_pinion_roll_length_mm": np.asarray(imp.pinion_parameter).tolist(),
        "impact_face_position_mm": np.asarray(imp.slice_z).tolist(),
        "impact_pinion_angle_deg": np.degrees(np.asarray(imp.pinion_angle)).tolist(),
        "impact_converged": np.asarray(imp.result == RESULTS.successful).tolist(),
        "impact_result": np.asarray(enum_name(imp.result)).tolist(),
        "stiffness_exponent": np.asarray(imp.stiffness.exponent)[:, 0].tolist(),
        "lte_peak_to_peak_um": (np.asarray(ltca.lte_peak_to_peak_line) * 1e3).tolist(),
        "lte_mean_um": (lte.mean(axis=-1) * rb2 * 1e3).tolist(),
        "ltca_converged": np.asarray(ltca.result == RESULTS.successful).tolist(),
        "accuracy": _accuracy_name(scene.accuracy),
        "wall_time_s": wall_time_s,
    }


def write_plots(report: dict, directory: Path) -> list[str]:
    """`sweep_force_map.png` (F_s over torque × speed, edge strikes marked) and
    `sweep_harris.png` (LTE peak-to-peak against torque)."""
    import matplotlib

    matplotlib.use("Agg")
    from . import plot

    paths = []
    fig = plot.impact_force_map(report["torque_Nm"], report["speed_rpm"], report["impact_force_N"],
                                report["impact_regime"]).figure
    paths.append(directory / "sweep_force_map.png")
    fig.savefig(paths[-1], dpi=120, bbox_inches="tight")
    fig = plot.harris_map(report["torque_Nm"], [report["lte_peak_to_peak_um"]]).figure
    paths.append(directory / "sweep_harris.png")
    fig.savefig(paths[-1], dpi=120, bbox_inches="tight")
    return [str(p) for p in paths]


def summary(r: dict) -> str:
    force = np.asarray(r["impact_force_N"])
    regime = np.asarray(r["impact_regime"])
    lines = [
        f"gearjax sweep: mesh-in impact over {len(r['torque_Nm'])} torques x {len(r['speed_rpm'])} speeds "
        f"(accuracy '{r['accuracy']}', {r['wall_time_s']:.1f} s)",
        "  impact force F_s (N); * = edge contact",
        "  torque (N m) \\ speed (rpm)  " + "".join(f"{n:>11g}" for n in r["speed_rpm"]) + "   LTE p-p (um)",
    ]
    for i, t in enumerate(r["torque_Nm"]):
        cells = "".join(f"{force[i, j]:>10.0f}{'*' if regime[i, j] == 'edge' else ' '}" for j in range(force.shape[1]))
        lines.append(f"  {t:>26g}  {cells}   {r['lte_peak_to_peak_um'][i]:.3f}")
    failed = int(np.size(r["impact_converged"]) - np.sum(r["impact_converged"]))
    if failed:
        lines.append(f"  {failed} grid points did not converge (impact_result in the JSON)")
    if r["files"]:
        lines.append("  wrote " + ", ".join(r["files"]))
    return "\n".join(lines)
