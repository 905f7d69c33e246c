"""`gearjax optimize --pareto`: the front of the `[optimize]` section's `pareto_quantities`
over its duty cycle; a table of the front's designs, `front.csv` and `front.png` in the run
directory."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np

from ..optimize.pareto_run import pareto_front
from ..optimize.space import design_dict


def run_pareto(objective, space, settings, out: str, resume: bool, as_json: bool, progress: str) -> int:
    """Run the front search and report it; exit status."""
    config = settings.pareto_config()
    try:
        result = pareto_front(objective, space, config, seed=settings.seed, run_dir=out, resume=resume,
                              progress=progress, certify=settings.certify)
    except ValueError as err:  # e.g. a run directory that holds another run
        print(f"gearjax: error: {err}", file=sys.stderr)
        return 2
    report = _report(objective, result)
    _write_csv(Path(out) / "front.csv", report)
    figure = _figure(Path(out) / "front.png", result)
    report["figure"] = figure
    if as_json:
        print(json.dumps({"pareto": report}, indent=2))
    else:
        print(summary(report))
    return 0


def _report(objective, result) -> dict:
    designs, values = result.front
    return {
        "quantities": list(result.quantities),
        "units": list(result.units),
        "loads_Nm": (np.asarray(objective.torques) / 1000.0).tolist(),
        "time_shares": np.asarray(objective.weights).tolist(),
        "accuracy": result.accuracy,
        "certification_accuracy": result.certification_accuracy,
        "front": [{"modification": design_dict(d), "objectives": dict(zip(result.quantities, map(float, v))),
                   "certified": result.certified is not None} for d, v in zip(designs, values)],
        "evaluated": int(len(result.archive_values)),
        "evaluations": result.evaluations,
        "steps": result.steps,
        "wall_time_s": result.wall_time_s,
        "run_dir": result.run_dir,
    }


def _write_csv(path: Path, report: dict) -> None:
    names = [f"{q} ({u})" for q, u in zip(report["quantities"], report["units"])]
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        keys = list(report["front"][0]["modification"]) if report["front"] else []
        writer.writerow(names + keys)
        for entry in report["front"]:
            writer.writerow([entry["objectives"][q] for q in report["quantities"]] +
                            [entry["modification"][k] for k in keys])


def _figure(path: Path, result) -> str | None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    from ..io import plot

    if not result.on_front.any():
        return None
    fig, ax = plt.subplots(figsize=(6.4, 4.5))
    plot.pareto_front(result, 0, 1, 2 if len(result.quantities) > 2 else None, ax=ax)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return str(path)


def summary(o: dict) -> str:
    at = o["certification_accuracy"] or o["accuracy"]
    head = "  ".join(f"{q} ({u})".rjust(22) for q, u in zip(o["quantities"], o["units"]))
    keys = list(o["front"][0]["modification"]) if o["front"] else []
    lines = [
        f"gearjax optimize --pareto: {', '.join(o['quantities'])} over "
        f"{', '.join(f'{t:g}' for t in o['loads_Nm'])} N·m (time shares "
        f"{', '.join(f'{w:.3g}' for w in o['time_shares'])}; search at '{o['accuracy']}')",
        f"  {len(o['front'])} designs on the front, "
        + ("certified" if o["certification_accuracy"] else "not certified") + f" at '{at}' "
        f"({o['steps']} iterations, {o['evaluations']} evaluations, {o['wall_time_s']:.1f} s)",
        "  " + head + "  " + "  ".join(k.rjust(18) for k in keys),
    ]
    for entry in sorted(o["front"], key=lambda e: e["objectives"][o["quantities"][0]]):
        values = "  ".join(f"{entry['objectives'][q]:22.5g}" for q in o["quantities"])
        lines.append("  " + values + "  " + "  ".join(f"{entry['modification'][k]:18.4g}" for k in keys))
    lines.append(f"  run directory {o['run_dir']} (front.csv" + (", front.png)" if o.get("figure") else ")"))
    return "\n".join(lines)
