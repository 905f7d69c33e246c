"""The impact objective's landscape around seed 001's optima: one-dimensional scans.

    python benchmarks/studies/landscape.py [--accuracy reference] [--points 41] [--chunk 8]
                              [--out docs/results/landscape.json] [--plot docs/figures/landscape.png]
                              [--markdown] [--report]

Designs: the certified gradient and GA optima at 1 000 N·m of `--optima`
(`docs/results/optimize_seed001.json`, written by `benchmarks/studies/optimize_seed001.py`), the paper's
optimum (Table 2) and an earlier GA optimum of the 21-slice discretisation. Through each,
the objective of the optimiser (F_s at 1 000 N·m and 5 000 rpm) is evaluated along each of
the six parameters over seed 001's bounds (the others held), and along the segments
`SEGMENTS`, extended by a quarter of their length beyond each end. Every point is a full
`simulate` at `--accuracy` (a preset name; `reference` by default, the optimiser's
certification), in batches of `--chunk` through one compiled program.

Each scan is classified (`classify`): *switches*, the steps where something discrete
changes (the regime, the striking edge, the incoming tooth pair, the strike point leaving or
reaching the face end); whether the lowest point is a kink (next to a switch); *wiggles*,
local extrema away from the lowest point and every switch; *jumps*, steps larger than
`JUMP` of the scan's median force and three times both neighbouring steps; *spikes*, single
points off both neighbours by more than `JUMP` of the median; and the basin, the stretch
around the lowest point where F_s stays within `BASIN` of it, as a fraction of the range.

Every finished scan is written to `--out` at once; a rerun with the same settings resumes,
and `--report` only redraws the figure and the table from the stored scans.
"""

from __future__ import annotations

import argparse
import json
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
NAMES = ("root relief", "tip relief", "root relief length", "tip relief length", "crowning", "unmodified length")
#: a jump: a step larger than this fraction of the scan's median force (and 3x its neighbours)
JUMP = 0.05
#: the basin: within this fraction of the scan's lowest force
BASIN = 0.05
#: half the seed pair's face width (mm): a strike point here is at the face end
HALF_FACE = 0.5 * float(seed_pair().face_width)


#: the GA's optimum at 1 000 N·m of a search at `default` before the first contact was
#: continuous along the face (1 343 N there, uncertified): an optimum of the discretisation
EARLIER_GA = np.array([0.024398921672800573, 0.04673654456449089, 0.5, 0.5, 0.024453622726389186, 19.02663786347871])


def designs(optima: Path) -> dict[str, np.ndarray]:
    """The scanned designs: the paper's optimum, the earlier GA optimum and the certified
    gradient and GA optima at 1 000 N·m of `optima` (`benchmarks/studies/optimize_seed001.py`'s JSON)."""
    stored = json.loads(optima.read_text())["designs_mm"]
    return {"gradient (certified)": np.asarray(stored["gradient, 1000 N·m"]),
            "paper optimum": np.asarray(paper_optimum().as_vector()),
            "earlier GA": EARLIER_GA,
            "GA (certified)": np.asarray(stored["GA, 1000 N·m"])}


#: the segments scanned between designs
SEGMENTS = (("gradient (certified)", "GA (certified)"), ("paper optimum", "gradient (certified)"),
            ("earlier GA", "gradient (certified)"))


def scans(named: dict, points: int) -> dict[str, dict]:
    """Every scan: its abscissa (label, values) and its designs (points, 6) in mm."""
    out = {}
    for name, y in named.items():
        for i, label in enumerate(NAMES):
            x = np.linspace(LOWER[i], UPPER[i], points)
            ys = np.repeat(y[None], points, axis=0)
            ys[:, i] = x
            out[f"{name} / {label}"] = {"x_label": f"{label} (mm)", "x": x.tolist(), "designs_mm": ys.tolist()}
    for a, b in SEGMENTS:
        ya, yb = named[a], named[b]
        t = np.linspace(-0.25, 1.25, points)
        ys = np.clip(ya[None] + t[:, None] * (yb - ya)[None], LOWER, UPPER)
        out[f"{a} -> {b}"] = {"x_label": f"t (0: {a}, 1: {b})", "x": t.tolist(), "designs_mm": ys.tolist()}
    return out


def scene(y, accuracy: str) -> gj.Scene:
    return gj.Scene(seed_pair(), gj.FlankModification.from_vector(np.asarray(y)),
                    operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0), effects=("impact",),
                    accuracy=accuracy)


def evaluate(fn, ys: np.ndarray, accuracy: str, chunk: int) -> dict[str, list]:
    rows: dict[str, list] = {k: [] for k in ("force_N", "regime", "kind", "pair_index", "slice_z_mm", "result")}
    for start in range(0, len(ys), chunk):
        part = list(ys[start:start + chunk])
        n = len(part)
        part += [part[-1]] * (chunk - n)  # one batch shape: one program
        imp = fn(gj.stack_scenes([scene(y, accuracy) for y in part])).impact
        rows["force_N"] += np.asarray(imp.force)[:n].tolist()
        rows["regime"] += list(gj.enum_name(imp.regime)[:n])
        rows["kind"] += list(gj.enum_name(imp.kind)[:n])
        rows["pair_index"] += np.asarray(imp.pair_index)[:n].tolist()
        rows["slice_z_mm"] += np.asarray(imp.slice_z)[:n].tolist()
        rows["result"] += list(gj.enum_name(imp.result)[:n])
    return rows


def classify(scan: dict, spacing: float) -> dict:
    """Jumps (index of the step, size relative to the median, cause) and the basin."""
    f = np.asarray(scan["force_N"])
    x = np.asarray(scan["x"])
    steps = np.abs(np.diff(f))
    median = float(np.median(f))
    jumps = []
    for i, s in enumerate(steps):
        neighbours = [steps[j] for j in (i - 1, i + 1) if 0 <= j < len(steps)]
        if s > JUMP * median and all(s > 3 * m for m in neighbours):
            causes = [what for what, key in (("regime", "regime"), ("tooth pair", "pair_index"), ("edge", "kind"))
                      if scan[key][i] != scan[key][i + 1]]
            if abs(scan["slice_z_mm"][i + 1] - scan["slice_z_mm"][i]) > spacing:
                causes.append("strike point along the face")
            jumps.append({"between": [float(x[i]), float(x[i + 1])], "relative": float(s / median),
                          "cause": ", ".join(causes) or "unexplained"})
    face_end = np.abs(np.asarray(scan["slice_z_mm"])) >= HALF_FACE - 1e-6
    switches = []
    for i in range(len(f) - 1):
        what = [w for w, key in (("regime", "regime"), ("tooth pair", "pair_index"), ("edge", "kind"))
                if scan[key][i] != scan[key][i + 1]]
        if face_end[i] != face_end[i + 1]:
            what.append("strike leaves the face end" if face_end[i] else "strike reaches the face end")
        if what:
            switches.append({"between": [float(x[i]), float(x[i + 1])], "what": ", ".join(what)})
    # wiggles: local extrema other than the lowest point and away from every switch, each
    # measured as its distance from the mean of its neighbours, relative to F_s there
    near_switch = {i for sw in switches for i in range(len(x)) if x[i] in sw["between"]}
    slope = np.diff(f)
    wiggles = [abs(f[i] - 0.5 * (f[i - 1] + f[i + 1])) / f[i] for i in range(1, len(f) - 1)
               if slope[i - 1] * slope[i] < 0 and i != int(np.argmin(f)) and i not in near_switch]
    # spikes: single points off both neighbours by more than JUMP of the median, the same way
    # (the lowest point is not one: a minimum at a kink lies below both neighbours)
    spikes = []
    for i in range(1, len(f) - 1):
        left, right = f[i] - f[i - 1], f[i] - f[i + 1]
        if i != int(np.argmin(f)) and left * right > 0 and min(abs(left), abs(right)) > JUMP * median:
            what = [w for w, key in (("regime", "regime"), ("tooth pair", "pair_index"), ("edge", "kind"))
                    if scan[key][i] != scan[key][i - 1] or scan[key][i] != scan[key][i + 1]]
            if scan["result"][i] != "successful":
                what.append(f"failed: {scan['result'][i]}")
            spikes.append({"x": float(x[i]), "relative": float(min(abs(left), abs(right)) / median),
                           "cause": ", ".join(what) or "unexplained"})
    low = int(np.argmin(f))
    inside = f <= (1 + BASIN) * f[low]
    lo = hi = low
    while lo > 0 and inside[lo - 1]:
        lo -= 1
    while hi < len(f) - 1 and inside[hi + 1]:
        hi += 1
    at_switch = any(min(abs(x[low] - sw["between"][0]), abs(x[low] - sw["between"][1])) < 1e-12 for sw in switches)
    return {"jumps": jumps, "spikes": spikes, "switches": switches, "lowest": {"x": float(x[low]), "force_N": float(f[low])},
            "lowest_at_a_switch": bool(at_switch and 0 < low < len(f) - 1),
            "basin_fraction": float((x[hi] - x[lo]) / (x[-1] - x[0])),
            "wiggles": len(wiggles), "largest_wiggle": float(max(wiggles, default=0.0))}


def markdown(study: dict) -> str:
    lines = [f"Accuracy `{study['accuracy']}`, {study['points']} points per scan.", "",
             "| scan | F_s range (N) | lowest at | basin (within 5 %) | switches | wiggles (largest) | "
             "jumps and spikes (cause) |", "|---|---:|---:|---:|---|---:|---|"]
    for name, scan in study["scans"].items():
        c = scan["classified"]
        jumps = "; ".join([f"{j['between'][0]:.4g}–{j['between'][1]:.4g}: {100 * j['relative']:.0f} % ({j['cause']})"
                           for j in c["jumps"]] + [f"spike at {sp['x']:.4g}: {100 * sp['relative']:.0f} % ({sp['cause']})"
                                                   for sp in c["spikes"]]) or "none"
        switches = "; ".join(f"{sw['between'][0]:.4g}–{sw['between'][1]:.4g}: {sw['what']}"
                             for sw in c["switches"]) or "none"
        at = f"{c['lowest']['x']:.4g}" + (" (a kink)" if c["lowest_at_a_switch"] else "")
        lines.append(f"| {name} | {min(scan['force_N']):.0f}–{max(scan['force_N']):.0f} | {at} | "
                     f"{100 * c['basin_fraction']:.0f} % | {switches} | {c['wiggles']} "
                     f"({100 * c['largest_wiggle']:.1f} %) | {jumps} |")
    return "\n".join(lines) + "\n"


def plot(study: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(study["scans"])
    cols = 6
    rows = -(-len(names) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.6 * rows), squeeze=False)
    for ax, name in zip(axes.flat, names):
        scan = study["scans"][name]
        x, f = np.asarray(scan["x"]), np.asarray(scan["force_N"])
        edge = np.asarray(scan["regime"]) == "edge"
        ax.plot(x, f, "-", color="0.6", lw=0.8)
        ax.plot(x[edge], f[edge], "o", ms=3, color="tab:red", label="tip edge")
        ax.plot(x[~edge], f[~edge], "o", ms=3, color="tab:blue", label="flank")
        ax.set_title(name, fontsize=7)
        ax.set_xlabel(scan["x_label"], fontsize=7)
        ax.tick_params(labelsize=6)
    for ax in axes.flat[len(names):]:
        ax.axis("off")
    axes.flat[0].set_ylabel("F_s (N)")
    axes.flat[0].legend(fontsize=6)
    fig.suptitle(f"seed 001 pair, 1 000 N·m, 5 000 rpm: F_s at '{study['accuracy']}'", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--accuracy", default="reference", choices=("fast", "default", "reference"))
    parser.add_argument("--points", type=int, default=41)
    parser.add_argument("--chunk", type=int, default=8)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/results/landscape.json")
    parser.add_argument("--plot", type=Path, default=None)
    parser.add_argument("--optima", type=Path, default=ROOT / "docs/results/optimize_seed001.json",
                        help="the optimiser's results whose certified 1 000 N·m optima are scanned")
    parser.add_argument("--markdown", action="store_true")
    parser.add_argument("--report", action="store_true",
                        help="evaluate nothing: the figure and table of the scans already in --out")
    args = parser.parse_args(argv)
    if args.points < 3 or args.chunk < 1:
        parser.error("--points must be at least 3 and --chunk at least 1")
    planned = scans(designs(args.optima), args.points)
    study = {"accuracy": args.accuracy, "points": args.points, "scans": {}, "jax": jax.__version__}
    if args.out.exists():
        old = json.loads(args.out.read_text())
        if old.get("accuracy") == args.accuracy and old.get("points") == args.points:
            study["scans"] = {k: v for k, v in old["scans"].items() if k in planned}
    spacing = 2 * HALF_FACE / gj.Accuracy.preset(args.accuracy).face_slices
    fn = jax.jit(jax.vmap(lambda s: gj.simulate(s, throw=False)))
    # the certified gradient optimum first, then the segments, then the rest
    order = sorted(planned, key=lambda n: (0 if n.startswith("gradient (certified) /") else 1 if "->" in n else 2))
    for name in order:
        scan = planned[name]
        if name in study["scans"] or args.report:
            continue
        t0 = time.perf_counter()
        scan.update(evaluate(fn, np.asarray(scan["designs_mm"]), args.accuracy, args.chunk))
        scan["wall_s"] = time.perf_counter() - t0
        study["scans"][name] = scan
        print(f"{name}: {scan['wall_s']:.0f} s, lowest {min(scan['force_N']):.0f} N", flush=True)
        tmp = args.out.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(study, indent=1))
        tmp.replace(args.out)
    study["scans"] = {name: study["scans"][name] for name in planned if name in study["scans"]}
    for scan in study["scans"].values():
        scan["classified"] = classify(scan, spacing)
    if not args.report:
        tmp = args.out.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(study, indent=1))
        tmp.replace(args.out)
    if args.plot is not None:
        plot(study, args.plot)
    print(markdown(study))


if __name__ == "__main__":
    main()
