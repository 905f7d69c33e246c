"""`gearjax optimize`: read a scene file's `[optimize]` section, run, report, write the
best design as a ready-to-run scene file."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from ..optimize.certification import accuracy_name
from ..optimize.objective import QUANTITIES
from ..optimize.methods import METHODS
from ..optimize.run import minimize
from ..optimize.settings import OptimizeSettings, SettingsError
from ..optimize.space import design_dict


#: the sub-command's help line
HELP = "tune the pinion modification for a small mesh-in impact ([optimize] section)"


def add_arguments(parser) -> None:
    parser.add_argument("scene", nargs="?",
                        help="TOML scene file with an optional [optimize] section (default: the built-in scene)")
    parser.add_argument("--method", choices=sorted(METHODS), help="overrides [optimize] method")
    parser.add_argument("--out", default="gearjax-optimize", help="run directory (default ./gearjax-optimize)")
    parser.add_argument("--resume", action="store_true", help="continue the run in --out")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--quiet", action="store_true", help="plain progress lines instead of a progress bar")
    parser.add_argument("--pareto", action="store_true",
                        help="the Pareto front of [optimize] pareto_quantities instead of one objective's minimum")


def run(args) -> int:
    return run_command(args.scene, args.method, args.out, args.resume, args.json, args.quiet, args.pareto)


def run_command(scene_path: str | None, method: str | None, out: str, resume: bool, as_json: bool, quiet: bool,
                pareto: bool = False) -> int:
    from ..io.scene_file import DEFAULT_SCENE_TOML, SceneFileError, parse_scene, read_scene_text

    try:
        text = DEFAULT_SCENE_TOML if scene_path is None else read_scene_text(scene_path)
        scene, data = parse_scene(text, "default scene" if scene_path is None else scene_path)
        settings = OptimizeSettings.from_dict(data.get("optimize", {}))
        if method is not None:
            settings = OptimizeSettings.from_dict({**data.get("optimize", {}), "method": method})
        objective, space = settings.build(scene)
        if pareto:
            settings.pareto_config()  # its errors before any computation
    except (SceneFileError, SettingsError) as err:
        print(f"gearjax: error: {err}", file=sys.stderr)
        return 2
    progress = "lines" if quiet or not sys.stderr.isatty() else "bar"
    if pareto:
        from .pareto import run_pareto

        return run_pareto(objective, space, settings, out, resume, as_json, progress)
    try:
        result = minimize(objective, space, settings.search_method(), seed=settings.seed, run_dir=out,
                          resume=resume, progress=progress, certify=settings.certify, certify_top=settings.certify_top)
    except ValueError as err:  # e.g. a run directory that holds another run
        print(f"gearjax: error: {err}", file=sys.stderr)
        return 2
    best_scene = Path(out) / "best_scene.toml"
    best_scene.write_text(best_scene_toml(data, result.best_design))
    report = {"optimize": _report(objective, result, best_scene)}
    if as_json:
        print(json.dumps(report, indent=2))
    else:
        print(summary(report["optimize"]))
    return 0


def _report(objective, result, best_scene: Path) -> dict:
    """The run's report: the "optimize" object of `--json` (loads in N·m, designs as
    modification dicts)."""
    unit = QUANTITIES[objective.quantity][0]
    cert = result.certification
    return {
        "method": result.method,
        "objective": objective.quantity,
        "objective_unit": unit,
        "aggregate": objective.aggregate,
        "loads_Nm": (np.asarray(objective.torques) / 1000.0).tolist(),
        "error_samples": objective.samples,
        "accuracy": accuracy_name(objective.scene.accuracy),
        "initial_objective_N": result.initial_objective,
        "best_objective_N": result.best_objective,
        "best_source": result.best_source,
        "certification_accuracy": None if cert is None else cert.accuracy,
        "certified_objective_N": result.certified_objective,
        "certified_candidates": None if cert is None else [
            {"modification": design_dict(d), "objective_N": float(v), "certified_objective_N": float(c)}
            for d, v, c in zip(cert.designs, cert.objective, cert.certified)
        ],
        "initial_modification": design_dict(result.initial_design),
        "best_modification": design_dict(result.best_design),
        "evaluations": result.evaluations,
        "gradient_evaluations": result.gradient_evaluations,
        "steps": result.steps,
        "wall_time_s": result.wall_time_s,
        "history": result.history,
        "converged": result.converged,
        "run_dir": result.run_dir,
        "best_scene": str(best_scene),
    }


def summary(o: dict) -> str:
    unit = o["objective_unit"]
    lines = [
        f"gearjax optimize: {o['method']} on the mesh-in impact {o['objective']} "
        f"({o['aggregate']} over {', '.join(f'{t:g}' for t in o['loads_Nm'])} N·m"
        + (f", {o['error_samples']} error samples" if o["error_samples"] > 1 else "")
        + f"; accuracy '{o['accuracy']}')",
        f"  initial design     {o['initial_objective_N']:.6g} {unit} at '{o['accuracy']}'",
        f"  best design        {o['best_objective_N']:.6g} {unit} at '{o['accuracy']}'  "
        f"({o['steps']} steps, {o['evaluations']} evaluations, {o['wall_time_s']:.1f} s, "
        f"{'converged' if o['converged'] else 'not converged'})",
        _certified_line(o, unit),
        *(["  the best design is the initial one: the search found nothing better"]
          if o["best_source"] == "initial" else []),
        "  best modification  " + ", ".join(f"{k} = {v:.4g}" for k, v in o["best_modification"].items()),
        f"  run directory      {o['run_dir']}  (best design: {o['best_scene']})",
    ]
    return "\n".join(lines)


def _certified_line(o: dict, unit: str) -> str:
    if o["certified_objective_N"] is None:
        return "  certified          not certified (certify = \"none\")"
    certified, best = o["certified_objective_N"], o["best_objective_N"]
    change = f"{100.0 * (certified / best - 1.0):+.1f} %" if best else "n/a"
    n = len(o["certified_candidates"])
    return (f"  certified          {certified:.6g} {unit} at '{o['certification_accuracy']}' "
            f"({change} against the search's value; best of {n} candidates)")


def best_scene_toml(data: dict, design) -> str:
    """The scene file `data` with `[modification]` set to `design` (mm)."""
    data = {k: dict(v) if isinstance(v, dict) else v for k, v in data.items()}
    data["modification"] = {key: round(value, 6) for key, value in design_dict(design).items()}
    header = "# The best design of a `gearjax optimize` run: the input scene with its [modification] replaced.\n"
    return header + "\n".join(_toml_table(name, table) for name, table in data.items() if isinstance(table, dict))


def _toml_table(name: str, table: dict) -> str:
    lines = [f"[{name}]"]
    for key, value in table.items():
        lines.append(f"{key} = {_toml_value(value)}")
    return "\n".join(lines) + "\n"


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} to TOML")


