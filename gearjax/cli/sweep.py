"""`gearjax sweep`: the mesh-in impact over a torque × speed grid (`gearjax.sweep.impact_sweep`,
in chunks of torques by `gearjax.sweep.run.run_impact_sweep`), written as `sweep.json` and
`sweep.npz`, optionally plotted; a killed run continues with `--resume`.

    gearjax sweep [SCENE.toml] --torque-Nm LIST --speed-rpm LIST [--chunk N] [--out DIR]
                  [--resume] [--json] [--plot] [--quiet]

A LIST is comma-separated numbers (`100,400,1000`) or `start:stop:count` (`count` evenly
spaced values from `start` to `stop`, both included).
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the command imports the engine only when it runs
    from ..scene import Scene


#: the sub-command's help line
HELP = "mesh-in impact over a torque x speed grid, in one compiled call"


def add_arguments(parser) -> None:
    parser.add_argument("scene", nargs="?", help="TOML scene file with effects = [\"impact\"] (default: the built-in scene)")
    parser.add_argument("--torque-Nm", required=True, dest="torque_Nm",
                        help="pinion torques (N m): 100,400,1000 or start:stop:count")
    parser.add_argument("--speed-rpm", required=True, dest="speed_rpm",
                        help="pinion speeds (rpm): 1000,5000 or start:stop:count")
    parser.add_argument("--chunk", type=int, help="torques per chunk (default: all at once); each chunk is written when done")
    parser.add_argument("--out", help="run directory: each finished chunk, then sweep.json and sweep.npz (and the plots)")
    parser.add_argument("--resume", action="store_true", help="continue the killed or finished run in --out")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--plot", action="store_true", help="also write sweep_force_map.png and sweep_harris.png (needs --out)")
    parser.add_argument("--quiet", action="store_true", help="plain progress lines instead of a progress bar")


def run(args) -> int:
    return run_command(args.scene, args.torque_Nm, args.speed_rpm, args.out, args.json, args.plot,
                       chunk=args.chunk, resume=args.resume, quiet=args.quiet)


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


def run_command(scene_path: str | None, torque: str, speed: str, out: str | None, as_json: bool, plot: bool,
                chunk: int | None = None, resume: bool = False, quiet: bool = False) -> int:
    from ..io.scene_file import SceneFileError, default_scene, load_scene

    try:
        torques_Nm = parse_list("--torque-Nm", torque)
        speeds_rpm = parse_list("--speed-rpm", speed)
        if chunk is not None and chunk < 1:
            raise ListError(f"--chunk: the torques per chunk must be an integer >= 1; got {chunk}")
        if resume and out is None:
            raise ListError("--resume: give the run directory with --out")
        scene, _ = default_scene() if scene_path is None else load_scene(scene_path)
        if "impact" not in scene.effects:
            raise SceneFileError("[analysis] effects: the sweep needs effects = [\"impact\"] in the scene file")
    except (ListError, SceneFileError) as err:
        print(f"gearjax: error: {err}", file=sys.stderr)
        return 2
    from ..runtime.resources import MemoryEstimateError
    from ..io.rundir import RunDirectoryError
    from ..sweep.run import run_impact_sweep

    progress = "lines" if quiet or not sys.stderr.isatty() else "bar"
    try:
        report = run_impact_sweep(scene, torques_Nm, speeds_rpm, chunk=chunk, out=out, resume=resume, progress=progress)
    except (RunDirectoryError, MemoryEstimateError) as err:  # another sweep in --out; too big a chunk
        print(f"gearjax: error: {err}", file=sys.stderr)
        return 2
    if out is not None and plot:
        name = "built-in default scene" if scene_path is None else Path(scene_path).name
        report["files"] += write_plots(report, Path(out), name, scene)
    print(json.dumps({"sweep": report}, indent=2) if as_json else summary(report))
    return 0


def write_plots(report: dict, directory: Path, scene_name: str = "scene", scene: Scene | None = None) -> list[str]:
    """`sweep_force_map.png` (F_s over torque × speed, edge strikes marked) and
    `sweep_harris.png` (LTE peak-to-peak against torque), each titled with `scene_name` and,
    given the `scene`, its pair and accuracy (`plot.scene_title`)."""
    import matplotlib

    matplotlib.use("Agg")
    from ..io import plot

    paths = []
    described = "" if scene is None else "\n" + plot.scene_title(scene, operating=False)
    ax = plot.impact_force_map(report["torque_Nm"], report["speed_rpm"], report["impact_force_N"],
                               report["impact_regime"], title=f"{scene_name}: mesh-in impact force{described}")
    paths.append(directory / "sweep_force_map.png")
    ax.figure.savefig(paths[-1], dpi=120, bbox_inches="tight")
    ax = plot.harris_map(report["torque_Nm"], [report["lte_peak_to_peak_um"]],
                         title=f"{scene_name}: loaded TE peak-to-peak{described}")
    paths.append(directory / "sweep_harris.png")
    ax.figure.savefig(paths[-1], dpi=120, bbox_inches="tight")
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
        lines.append(f"  {failed} grid points failed (impact_result in the JSON)")
    if r["files"]:
        lines.append("  wrote " + ", ".join(r["files"]))
    return "\n".join(lines)
