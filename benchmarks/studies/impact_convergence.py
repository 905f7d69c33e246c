"""Convergence of the mesh-in impact force in the face slices, on the seed 001 pair.

    python benchmarks/studies/impact_convergence.py [--random 30] [--slices 11 21 41 81 161] [--out FILE] [--markdown]

Designs: the GA and gradient optima of `docs/results/optimize_seed001.json` (1 000 N·m), the
paper optimum (Table 2) and `--random` designs drawn uniformly within seed 001's bounds
(seed 0). Each at 1 000 N·m and 5 000 rpm, the `default` preset with only `face_slices`
changed; one compiled program per slice count for all designs (`vmap(simulate)`, in chunks
of `--chunk`). Per design and slice count: F_s, the regime, the strike point's face
coordinate z and pinion angle, the result code, the LTE peak-to-peak (µm, line of action)
and the maximum Hertz pressure (MPa). Every finished slice count is written
at once to FILE (default `docs/results/impact_convergence.json`) and a rerun with the same
settings resumes from it. Prints the F_s table, each design's error against the finest
slice count, the regime flips, and the observed order of convergence
$p = \\log(|F_a - F_b| / |F_b - F_c|) / \\log(b/a)$ of successive slice counts a < b < c.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
#: seed 001's bounds of the six modification parameters (mm)
LOWER = np.array([0.005, 0.005, 0.5, 0.5, 0.005, 0.0])
UPPER = np.array([0.075, 0.075, 4.0, 4.0, 0.075, 21.0])


def designs(n_random: int) -> dict[str, list[float]]:
    stored = json.loads((ROOT / "docs/results/optimize_seed001.json").read_text())["designs_mm"]
    out = {"GA, 1000 N·m": stored["GA, 1000 N·m"], "gradient, 1000 N·m": stored["gradient, 1000 N·m"],
           "paper optimum": np.asarray(paper_optimum().as_vector()).tolist()}
    rng = np.random.default_rng(0)
    for i in range(n_random):
        out[f"random {i}"] = (LOWER + (UPPER - LOWER) * rng.uniform(size=6)).tolist()
    return out


def scene(y, slices: int) -> gj.Scene:
    return gj.Scene(seed_pair(), gj.FlankModification.from_vector(np.asarray(y)),
                    operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0), effects=("impact",),
                    accuracy=gj.Accuracy.preset("default").replace(face_slices=slices))


def run_slices(named: dict, slices: int, chunk: int) -> dict:
    fn = jax.jit(jax.vmap(lambda s: gj.simulate(s, throw=False)))
    names = list(named)
    rows = {}
    t0 = time.perf_counter()
    for start in range(0, len(names), chunk):
        part = names[start:start + chunk]
        part = part + [part[-1]] * (chunk - len(part))  # one batch shape: one program
        sim = fn(gj.stack_scenes([scene(named[n], slices) for n in part]))
        out = sim.impact
        lte_pp = np.asarray(sim.ltca.lte_peak_to_peak_line) * 1e3
        pressure = np.asarray(sim.ltca.max_pressure)
        for i, name in enumerate(part[: len(names[start:start + chunk])]):
            rows[name] = {
                "force_N": float(out.force[i]),
                "lte_peak_to_peak_um": float(lte_pp[i]),
                "max_pressure_MPa": float(pressure[i]),
                "regime": gj.enum_name(out.regime)[i],
                "slice_z_mm": float(out.slice_z[i]),
                "pinion_angle_rad": float(out.pinion_angle[i]),
                "result": gj.enum_name(out.result)[i],
            }
    return {"rows": rows, "wall_s": time.perf_counter() - t0}


def order(f1, f2, f3, ratio):
    """Observed order of convergence from three successive refinements by `ratio`."""
    a, b = abs(f1 - f2), abs(f2 - f3)
    return math.log(a / b) / math.log(ratio) if a > 0 and b > 0 else None


def report(study: dict) -> None:
    slices = sorted(int(n) for n in study["runs"])
    names = list(study["designs"])
    finest = str(slices[-1])
    print("F_s (N) [regime]; error against", finest, "slices")
    print(f"{'design':22s}" + "".join(f"{n:>22d}" for n in slices))
    flips, worst = [], {n: 0.0 for n in slices}
    for name in names:
        cells = []
        ref = study["runs"][finest]["rows"][name]["force_N"]
        regimes = set()
        for n in slices:
            row = study["runs"][str(n)]["rows"][name]
            err = (row["force_N"] - ref) / ref if ref else float("nan")
            worst[n] = max(worst[n], abs(err))
            regimes.add(row["regime"]) if n >= 21 else None
            ok = "" if row["result"] == "successful" else "!"
            cells.append(f"{row['force_N']:9.0f} {row['regime'][:4]}{ok} {100 * err:+6.1f}%")
        if len(regimes) > 1:
            flips.append(name)
        print(f"{name:22s}" + "".join(f"{c:>22s}" for c in cells))
    print("largest |error| per slice count:", {n: f"{100 * w:.1f} %" for n, w in worst.items()})
    for key in ("lte_peak_to_peak_um", "max_pressure_MPa"):
        if all(key in study["runs"][str(n)]["rows"][names[0]] for n in slices):
            errs = {n: max(abs(study["runs"][str(n)]["rows"][m][key] / study["runs"][finest]["rows"][m][key] - 1)
                           for m in names) for n in slices}
            print(f"largest |error| of {key}:", {n: f"{100 * e:.1f} %" for n, e in errs.items()})
    print("designs whose regime changes from 21 slices on:", flips or "none")
    for a, b, c in zip(slices, slices[1:], slices[2:]):
        ps = [order(*(study["runs"][str(m)]["rows"][name]["force_N"] for m in (a, b, c)), b / a) for name in names]
        ps = [p for p in ps if p is not None]
        if ps:
            print(f"observed order from {a}/{b}/{c} slices: median {np.median(ps):.2f} "
                  f"(quartiles {np.percentile(ps, 25):.2f}, {np.percentile(ps, 75):.2f}; {len(ps)} designs)")


def markdown(study: dict) -> str:
    """The study's tables in Markdown (for `docs/impact_convergence.md`): F_s and regime per
    slice count with the error against the finest, then the largest errors of F_s, the LTE
    peak-to-peak and the maximum pressure per slice count, and the observed orders."""
    slices = sorted(int(n) for n in study["runs"])
    finest = str(slices[-1])
    rows = {n: study["runs"][str(n)]["rows"] for n in slices}
    names = list(study["designs"])
    lines = ["| design | " + " | ".join(f"{n} slices" for n in slices) + " |",
             "|---|" + "---:|" * len(slices)]
    for name in names:
        ref = rows[slices[-1]][name]["force_N"]
        cells = []
        for n in slices:
            row = rows[n][name]
            flag = "" if row["result"] == "successful" else f" ({row['result']})"
            err = "" if str(n) == finest else f", {100 * (row['force_N'] / ref - 1):+.1f} %"
            force = f"{row['force_N']:,.0f}".replace(",", "\u202f")
            cells.append(f"{force} N {row['regime']}{err}{flag}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += ["", "| largest \\|error\\| against " + finest + " slices | " + " | ".join(str(n) for n in slices[:-1]) + " |",
              "|---|" + "---:|" * (len(slices) - 1)]
    for key, label in (("force_N", "F_s"), ("lte_peak_to_peak_um", "LTE peak-to-peak"),
                       ("max_pressure_MPa", "maximum pressure")):
        errs = [max(abs(rows[n][m][key] / rows[slices[-1]][m][key] - 1) for m in names) for n in slices[:-1]]
        lines.append(f"| {label} | " + " | ".join(f"{100 * e:.1f} %" for e in errs) + " |")
    flips = [m for m in names if len({rows[n][m]["regime"] for n in slices if n >= 21}) > 1]
    lines += ["", f"Designs whose regime changes from 21 slices on: {', '.join(flips) if flips else 'none'}."]
    for key, label in (("force_N", "F_s"), ("lte_peak_to_peak_um", "LTE peak-to-peak")):
        for a, b, c in zip(slices, slices[1:], slices[2:]):
            ps = [order(*(rows[k][m][key] for k in (a, b, c)), b / a) for m in names]
            ps = [p for p in ps if p is not None]
            if ps:
                lines.append(f"Observed order of {label} from {a}/{b}/{c} slices: median {np.median(ps):.2f} "
                             f"(quartiles {np.percentile(ps, 25):.2f}, {np.percentile(ps, 75):.2f}; {len(ps)} designs).")
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--random", type=int, default=30)
    parser.add_argument("--slices", type=int, nargs="+", default=[11, 21, 41, 81, 161])
    parser.add_argument("--chunk", type=int, default=11)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/results/impact_convergence.json")
    parser.add_argument("--markdown", action="store_true", help="also print the tables in Markdown")
    args = parser.parse_args(argv)
    named = designs(args.random)
    study = {"designs": named, "runs": {}, "machine": {"jax": jax.__version__}}
    if args.out.exists():
        old = json.loads(args.out.read_text())
        if old.get("designs") == named:
            study["runs"] = old["runs"]
    for n in args.slices:
        if str(n) in study["runs"]:
            continue
        study["runs"][str(n)] = run_slices(named, n, args.chunk)
        print(f"{n} slices done in {study['runs'][str(n)]['wall_s']:.0f} s", flush=True)
        tmp = args.out.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(study, indent=1))
        tmp.replace(args.out)
    study["runs"] = {k: v for k, v in study["runs"].items() if int(k) in args.slices}
    report(study)
    if args.markdown:
        print(markdown(study))


if __name__ == "__main__":
    main()
