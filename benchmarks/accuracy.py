"""What accuracy costs in time: error against `reference` and time, per preset and per knob
varied alone around `default`.

    python benchmarks/accuracy.py [--cases seed001,spur,curvilinear] [--repeats 3]

Cases (each through the public `simulate`, one compiled program per case and setting):

* `seed001`: seed 001's pair with the paper optimum, TCA + LTCA + impact at 400, 1000 and
  1600 N·m and 5000 rpm (surface contact at 400, edge contact above ~590 N·m);
* `spur`: an unmodified 23/41 spur pair (m 4 mm, b 20 mm), TCA + LTCA at 200 N·m;
* `curvilinear`: seed 002's curvilinear pair (R_t 20 mm), TCA + LTCA at 100 N·m.

Settings: the presets `fast`, `default`, `reference`, and `default` with one knob changed
(positions per pitch, face slices, Newton tolerances, quadrature points, impact fit points,
the plane-of-action TCA, float32), and a run finer than `reference` (161 slices, 256
positions per pitch), whose row holds the reference's own error against it. Quantities, in the units of `gearjax run --json`: TE
and LTE peak-to-peak, LTE mean, mean mesh stiffness, maximum load share, maximum pressure,
impact force, strike point (mm) and regime. Errors are relative to `reference`
(to max(|reference|, 0.1 µm) for the TE and LTE quantities, which are zero for perfect
flanks; the strike point's in mm, the regime as equal or not), the largest over a case's
loads; times are the first call minus one run
(trace + compile) and the median of `--repeats` runs. Writes
benchmarks/results/accuracy.json; `--plot` draws docs/figures/accuracy_pareto.png from it.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402
from _common import machine, write  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402
from gearjax.io.report import result_dict  # noqa: E402

#: Quantity name -> path in `result_dict`.
QUANTITIES = {
    "te_pp_um": ("tca", "te_peak_to_peak_um"),
    "lte_pp_um": ("ltca", "lte_peak_to_peak_um"),
    "lte_mean_um": ("ltca", "lte_mean_um"),
    "stiffness": ("ltca", "mean_mesh_stiffness_N_per_mm_um"),
    "load_share": ("ltca", "max_load_share"),
    "pressure_MPa": ("ltca", "max_pressure_MPa"),
    "impact_force_N": ("impact", "force_N"),
}

#: Errors are relative to max(|reference|, floor): the TE of perfect flanks is zero up to
#: rounding, where a relative error means nothing (µm for the TE and LTE quantities).
FLOORS = {"te_pp_um": 0.1, "lte_pp_um": 0.1, "lte_mean_um": 0.1}

DEFAULT = gj.Accuracy.preset("default")
#: the setting whose row is the reference's error against a finer run
FINER = "finer than reference"
SETTINGS = {
    "fast": gj.Accuracy.preset("fast"),
    "default": DEFAULT,
    "reference": gj.Accuracy.preset("reference"),
    "positions 16": DEFAULT.replace(positions_per_pitch=16),
    "positions 64": DEFAULT.replace(positions_per_pitch=64),
    "slices 9": DEFAULT.replace(face_slices=9),
    "slices 31": DEFAULT.replace(face_slices=31),
    "slices 41": DEFAULT.replace(face_slices=41),
    "newton 1e-8": DEFAULT.replace(newton_rtol=1e-8, newton_atol=1e-8),
    "newton 1e-13": DEFAULT.replace(newton_rtol=1e-13, newton_atol=1e-13),
    "quadrature 12": DEFAULT.replace(quadrature_points=12),
    "quadrature 48": DEFAULT.replace(quadrature_points=48),
    "fit points 4": DEFAULT.replace(impact_fit_points=4),
    "fit points 12": DEFAULT.replace(impact_fit_points=12),
    "plane of action": DEFAULT.replace(tca_method="plane_of_action"),
    "float32": DEFAULT.replace(dtype="float32"),
    # twice the reference's slices and positions: its row holds the reference's own error
    FINER: gj.Accuracy.preset("reference").replace(face_slices=161, positions_per_pitch=256),
}


def cases():
    seed = seed_pair()
    spur = gj.InvoluteGearPair((23, 41), 4.0, 20.0, 0.0, 20.0)
    curvilinear = gj.CurvilinearGearPair((20, 30), 2.0, 20.0, 20.0, 20.0)
    return {
        "seed001": [(f"{t:g} N m", seed, paper_optimum(), gj.OperatingPoint(torque_Nm=t, speed_rpm=5000.0), ("impact",))
                    for t in (400.0, 1000.0, 1600.0)],
        "spur": [("200 N m", spur, gj.FlankModification(), gj.OperatingPoint(torque_Nm=200.0), ("ltca",))],
        "curvilinear": [("100 N m", curvilinear, gj.FlankModification(), gj.OperatingPoint(torque_Nm=100.0), ("ltca",))],
    }


def measure(loads, accuracy, repeats):
    """Quantities per load, trace + compile seconds and median run seconds of `simulate`."""
    values, compile_s, run_s = [], None, []
    for _, pair, modification, operating, effects in loads:
        scene = gj.Scene(pair, modification, operating=operating, effects=effects, accuracy=accuracy)
        t0 = time.perf_counter()
        result = jax.block_until_ready(gj.simulate(scene, throw=False))
        first = time.perf_counter() - t0
        runs = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            jax.block_until_ready(gj.simulate(scene, throw=False))
            runs.append(time.perf_counter() - t0)
        if compile_s is None:
            compile_s = first - statistics.median(runs)
        run_s.append(statistics.median(runs))
        d = result_dict(scene, result)
        row = {name: d.get(stage, {}).get(key) for name, (stage, key) in QUANTITIES.items()}
        if "impact" in d:
            row["strike_point_mm"] = d["impact"]["point_mm"]
            row["regime"] = d["impact"]["regime"]
        row["converged"] = all(d.get(stage, {}).get("result", "successful") == "successful" for stage in ("tca", "ltca", "impact"))
        values.append(row)
    return values, compile_s, statistics.median(run_s)


def errors(values, reference):
    """Largest error of each quantity over the loads: relative for the numbers, mm for the
    strike point, and whether every regime agrees."""
    out = {}
    for name in QUANTITIES:
        pairs = [(v[name], r[name]) for v, r in zip(values, reference, strict=True) if r.get(name) is not None]
        if pairs:
            floor = FLOORS.get(name, 1e-12)
            out[name] = max(abs(v - r) / max(abs(r), floor) if v is not None and math.isfinite(v) else math.inf
                            for v, r in pairs)
    if "strike_point_mm" in reference[0]:
        out["strike_point_mm"] = max(float(np.linalg.norm(np.subtract(v["strike_point_mm"], r["strike_point_mm"])))
                                     for v, r in zip(values, reference, strict=True))
        out["regime_equal"] = all(v["regime"] == r["regime"] for v, r in zip(values, reference, strict=True))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cases", default="seed001,spur,curvilinear")
    parser.add_argument("--settings", default=",".join(SETTINGS))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--plot", action="store_true", help="only draw the figure from the results file")
    parser.add_argument("--markdown", action="store_true", help="only print the tables of docs/accuracy.md from the results file")
    parser.add_argument("--resume-from", help="keep the other rows (cases, or settings of a case, not rerun) from "
                        "this results file; a case's reference is always rerun")
    args = parser.parse_args()
    if args.plot:
        return plot()
    if args.markdown:
        return markdown()
    table = cases()
    rows = []
    settings = args.settings.split(",")
    if args.resume_from:
        import json
        from pathlib import Path

        # the rerun rows are measured against a new reference run, which replaces the old one
        settings = ["reference"] + [name for name in settings if name != "reference"]
        rerun = {(case, name) for case in args.cases.split(",") for name in settings}
        rows = [r for r in json.loads(Path(args.resume_from).read_text())["rows"] if (r["case"], r["setting"]) not in rerun]
    for case in args.cases.split(","):
        loads = table[case]
        reference, ref_compile, ref_run = measure(loads, SETTINGS["reference"], args.repeats)
        print(f"{case}: reference compile {ref_compile:.1f} s, run {ref_run * 1e3:.1f} ms", flush=True)
        for name in settings:
            if name == "reference":
                values, compile_s, run_s = reference, ref_compile, ref_run
            else:
                values, compile_s, run_s = measure(loads, SETTINGS[name], args.repeats)
            # the finer run is the truth for the reference's own error
            err = errors(reference, values) if name == FINER else errors(values, reference)
            rows.append({"case": case, "setting": name, "compile_s": compile_s, "run_s": run_s,
                         "run_fraction_of_reference": run_s / ref_run, "errors": err,
                         "values": values, "loads": [load[0] for load in loads]})
            worst = max((v for k, v in err.items() if k not in ("strike_point_mm", "regime_equal")), default=0.0)
            print(f"  {name:16s} compile {compile_s:6.1f} s  run {run_s * 1e3:9.1f} ms ({run_s / ref_run:6.1%})  "
                  f"worst rel. error {worst:.2e}  " + "  ".join(f"{k} {v:.1e}" if isinstance(v, float) else f"{k} {v}"
                                                              for k, v in err.items()), flush=True)
            write("accuracy", {"machine": machine(), "rows": rows})
            # Drop the compiled programs: each holds its machine code in memory maps, and a
            # process that compiled ~30 large programs hit the kernel's map limit
            # (vm.max_map_count; LLVM "Cannot allocate memory", then a segfault).
            jax.clear_caches()


LABELS = {"lte_pp_um": "LTE p-p", "lte_mean_um": "LTE mean", "stiffness": "stiffness", "load_share": "max load share",
          "pressure_MPa": "max pressure", "impact_force_N": "F_s", "te_pp_um": "TE p-p"}


def _percent(x: float) -> str:
    if not math.isfinite(x):
        return "failed"
    if x < 1e-4:
        return "< 0.01 %"
    return f"{x * 100:.2g} %" if x < 0.1 else f"{x * 100:.0f} %"


def markdown() -> None:
    """The tables of docs/accuracy.md, one per case, from benchmarks/results/accuracy.json:
    run time, its fraction of the reference's, compile time and the largest error of each
    quantity over the case's loads. A quantity whose reference is below its floor at every
    load (the unloaded TE of perfect flanks) is left out."""
    import json
    from pathlib import Path

    rows = json.loads((Path(__file__).resolve().parent / "results" / "accuracy.json").read_text())["rows"]
    for case in dict.fromkeys(r["case"] for r in rows):
        order = list(SETTINGS)
        mine = sorted((r for r in rows if r["case"] == case), key=lambda r: order.index(r["setting"]))
        reference = next(r for r in mine if r["setting"] == "reference")["values"]
        names = [n for n in QUANTITIES if any(v.get(n) is not None and abs(v[n]) >= FLOORS.get(n, 0.0) for v in reference)]
        impact = "strike_point_mm" in reference[0]
        head = ["setting", "run (ms)", "of reference", "compile (s)", *(LABELS[n] for n in names)]
        head += ["strike point (mm)", "regime"] if impact else []
        print(f"\n{case} ({', '.join(mine[0]['loads'])}):\n")
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" + "---:|" * (len(head) - 1 - impact) + ("---|" if impact else ""))
        for r in mine:
            label = "`reference` against the finer run (its time: the finer run's)" if r["setting"] == FINER else r["setting"]
            cells = [label, f"{r['run_s'] * 1e3:,.1f}".replace(",", " "), _percent(r["run_fraction_of_reference"]),
                     f"{r['compile_s']:.0f}"]
            if r["setting"] == "reference":
                cells += ["—"] * (len(head) - len(cells))
            else:
                cells += [_percent(r["errors"].get(n, math.nan)) for n in names]
                if impact:
                    cells += [f"{r['errors']['strike_point_mm']:.2g}", "same" if r["errors"]["regime_equal"] else "differs"]
            print("| " + " | ".join(cells) + " |")


def plot() -> None:
    """docs/figures/accuracy_pareto.png: error against run time (log-log), one panel per
    quantity, a colour per case, presets marked by name."""
    import json
    from pathlib import Path

    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    root = Path(__file__).resolve().parent
    rows = json.loads((root / "results" / "accuracy.json").read_text())["rows"]
    names = list(QUANTITIES) + ["strike_point_mm"]
    fig, axes = plt.subplots(2, 4, figsize=(16, 7.5))
    colours = {}
    for ax, name in zip(axes.flat, names, strict=True):
        for row in rows:
            if row["setting"] in ("reference", FINER) or name not in row["errors"]:
                continue
            colour = colours.setdefault(row["case"], f"C{len(colours)}")
            error = max(row["errors"][name], 1e-9)
            preset = row["setting"] in ("fast", "default")
            ax.loglog(row["run_s"], error, "s" if preset else "o", color=colour, ms=8 if preset else 4,
                      label=row["case"] if preset and row["setting"] == "default" else None)
            if preset:
                ax.annotate(row["setting"], (row["run_s"], error), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.axhline(0.05 if name == "strike_point_mm" else 0.01, color="grey", lw=0.8, ls="--")
        ax.set_title(name + (" (mm)" if name == "strike_point_mm" else " (relative)"), fontsize=9)
        ax.set_xlabel("run time of simulate (s)", fontsize=8)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())  # minor labels overlap
    axes.flat[0].legend(fontsize=7)
    fig.suptitle("Error against the 'reference' preset vs run time: presets (squares) and one knob changed "
                 "from 'default' (dots); dashed: the targets (1 %, 0.05 mm)", fontsize=10)
    fig.tight_layout()
    out = root.parent / "docs" / "figures" / "accuracy_pareto.png"
    fig.savefig(out, dpi=110)
    print(f"written {out}")


if __name__ == "__main__":
    main()
