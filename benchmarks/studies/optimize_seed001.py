"""Seed 001's modification optimisation, by the GA and by gradient descent,
and a robust design over a load spectrum and sampled misalignment.

    python benchmarks/studies/optimize_seed001.py [--quick] [--robust] [--accuracy default] [--population 40]
        [--generations 30] [--starts 8] [--iterations 40] [--robust-generations 10] [--out FILE]
        [--certify reference] [--run-dir DIR]

The 29/71 pair at 5000 rpm, objective F_s (energy method) at 1000 N·m (the paper's) and the
mean over 400 / 1000 / 1600 N·m; GA 40 x 30 and projected Adam from 8 Latin-hypercube starts
(40 iterations), both within seed 001's bounds, searched at the `default` accuracy
(`--accuracy`; `fast` misses brief tip-edge strikes between its 16 positions per pitch and
finds optima that do not exist at `default`). Each search ends by certifying its best
candidates at `--certify` (`reference` by default) and returns the best certified one
(`gearjax.optimize.certification`). The optima, the standard (unmodified) pair and the
paper's Table 2 optimum are then evaluated at the search's and at the certification
accuracy over the three loads, beside the paper's Table 4. Writes the JSON results and the
convergence figure (docs/figures/optimize_convergence.png). With `--run-dir DIR` every
search keeps its run directory there, and a rerun resumes where the last one stopped.

    python benchmarks/studies/optimize_seed001.py --reevaluate

evaluates the stored designs again with the current code (after an engine fix) and
rewrites only the JSON's `forces` table.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402


import gearjax as gj  # noqa: E402
from gearjax import optimize as go  # noqa: E402
from gearjax.papers.seed001 import (  # noqa: E402
    SEED_001_NOTE,
    TABLE2_OPTIMUM_UM,
    TABLE4_IMPACT_FORCE,
    paper_optimum,
    seed_pair,
)

ROOT = Path(__file__).resolve().parents[2]
LOADS = (400.0, 1000.0, 1600.0)


def scene(accuracy: str, torque_Nm: float = 1000.0, errors=None) -> gj.Scene:
    return gj.Scene(seed_pair(), paper_optimum(), errors=errors,
                    operating=gj.OperatingPoint(torque_Nm=torque_Nm, speed_rpm=5000.0),
                    effects=("impact",), accuracy=accuracy)


def within(history, evaluations_per_step, target) -> int | None:
    """Evaluations after which the best value first lies within 1 % of `target`."""
    for i, value in enumerate(history):
        if value <= 1.01 * target:
            return (i + 1) * evaluations_per_step
    return None


def run_dir(args, case: str, method: str) -> Path | None:
    """The run directory of one search under `--run-dir` (None without): a rerun resumes it."""
    if args.run_dir is None:
        return None
    slug = "".join(c if c.isalnum() else "_" for c in case).strip("_")
    return Path(args.run_dir) / slug / method


def run_case(name, objective, space, args, runs):
    ga_cfg = go.GAConfig(population=args.population)
    ga = go.genetic(objective, space, config=ga_cfg, generations=args.generations, seed=0, progress="lines",
                    certify=args.certify, run_dir=run_dir(args, name, "ga"), resume=args.run_dir is not None)
    cfg = go.GradientConfig(starts=args.starts, iterations=args.iterations)
    gd = go.gradient_descent(objective, space, config=cfg, seed=0, progress="lines",
                             certify=args.certify, run_dir=run_dir(args, name, "gradient"), resume=args.run_dir is not None)
    best = min(min(ga.history), min(gd.history))
    per = objective.torques.shape[0] * objective.samples
    out = {}
    for label, result, step_evals in (("ga", ga, args.population * per), ("gradient", gd, args.starts * per)):
        out[label] = {
            "best_objective_N": result.best_objective,
            "certified_objective_N": result.certified_objective,
            "certification_accuracy": result.certification.accuracy,
            "certified_candidates": result.certification.to_dict(),
            "best_modification": go.design_dict(result.best_design),
            "history": result.history,
            "evaluations": result.evaluations,
            "best_source": result.best_source,
            "wall_time_s": result.wall_time_s,
            "converged": result.converged,
            "evaluations_to_1pct_of_best": within(result.history, step_evals, best),
        }
    runs[name] = out
    return ga, gd


def stored_case(args, name: str, evaluations_per_step: dict) -> dict:
    """The results of one case's finished searches, read from their run directories
    (`history.jsonl`, `certification.json`) without computing anything."""
    out = {}
    for method in ("ga", "gradient"):
        directory = run_dir(args, name, method)
        lines = [json.loads(line) for line in (directory / "history.jsonl").read_text().splitlines() if line.strip()]
        cert = go.Certification.from_dict(json.loads((directory / "certification.json").read_text()))
        best = cert.best
        out[method] = {
            "best_objective_N": float(cert.objective[best]),
            "certified_objective_N": float(cert.certified[best]),
            "certification_accuracy": cert.accuracy,
            "certified_candidates": cert.to_dict(),
            "best_modification": go.design_dict(cert.designs[best]),
            "history": [line["best_objective"] for line in lines],
            "evaluations": lines[-1]["evaluations"],
            "best_source": "initial" if np.allclose(cert.designs[best], paper_optimum().as_vector(), atol=1e-9)
            else "search",
            "wall_time_s": lines[-1]["elapsed_s"],
            "converged": None,
        }
    best = min(min(r["history"]) for r in out.values())
    for method, r in out.items():
        r["evaluations_to_1pct_of_best"] = within(r["history"], evaluations_per_step[method], best)
    return out


def evaluate_batched(designs: dict, accuracy: str, chunk: int = 6) -> dict:
    """F_s, v_n and regime of each design at each load (mm designs; `simulate` at
    `accuracy`), through one batched program (`vmap(simulate)` over `chunk` scenes)."""
    fn = jax.jit(jax.vmap(lambda s: gj.simulate(s, throw=False)))
    jobs = [(label, load, design) for label, design in designs.items() for load in LOADS]
    out: dict = {label: {} for label in designs}
    for start in range(0, len(jobs), chunk):
        part = jobs[start:start + chunk]
        padded = part + [part[-1]] * (chunk - len(part))
        scenes = [go.Objective.create(scene(accuracy, load)).scene_for(np.asarray(d)) for _, load, d in padded]
        imp = fn(gj.stack_scenes(scenes)).impact
        regime, result = gj.enum_name(imp.regime), gj.enum_name(imp.result)
        for k, (label, load, _) in enumerate(part):
            out[label][f"{load:g}"] = {"force_N": float(imp.force[k]), "regime": str(regime[k]),
                                       "velocity_mm_s": float(imp.velocity[k]), "successful": bool(result[k] == "successful")}
    return out


def assemble(args) -> None:
    """`--assemble`: the JSON and figure from the finished searches in `--run-dir` and a
    forces table at the certification accuracy; no search, no robust design."""
    gj.enable_compilation_cache()  # a rerun loads the forces table's program
    per_step = {"F_s at 1000 N·m": {"ga": args.population, "gradient": args.starts},
                "mean F_s over 400/1000/1600 N·m": {"ga": args.population * len(LOADS),
                                                    "gradient": args.starts * len(LOADS)}}
    runs = {name: stored_case(args, name, steps) for name, steps in per_step.items()}
    def best_design(r):
        cert = go.Certification.from_dict(r["certified_candidates"])
        return cert.designs[cert.best]

    best = {name: {m: best_design(r) for m, r in out.items()} for name, out in runs.items()}
    designs = {
        "standard (unmodified)": np.array([0.0, 0.0, 1.0, 1.0, 0.0, 0.0]),
        "paper optimum (Table 2)": np.asarray(paper_optimum().as_vector()),
        "GA, 1000 N·m": best["F_s at 1000 N·m"]["ga"],
        "gradient, 1000 N·m": best["F_s at 1000 N·m"]["gradient"],
        "GA, spectrum": best["mean F_s over 400/1000/1600 N·m"]["ga"],
        "gradient, spectrum": best["mean F_s over 400/1000/1600 N·m"]["gradient"],
    }
    result = {
        "note": SEED_001_NOTE,
        "settings": {"population": args.population, "generations": args.generations, "starts": args.starts,
                     "iterations": args.iterations, "search_accuracy": args.accuracy,
                     "certification_accuracy": args.certify, "speed_rpm": 5000.0,
                     "lower_mm": [0.005, 0.005, 0.5, 0.5, 0.005, 0.0], "upper_mm": [0.075, 0.075, 4.0, 4.0, 0.075, 21.0]},
        "runs": runs,
        "designs_mm": {k: np.asarray(v).tolist() for k, v in designs.items()},
        "forces": {args.certify: evaluate_batched(designs, args.certify)},
        **({"forces_finer": {"face_slices": args.finer, "forces": evaluate_batched(
            designs, gj.Accuracy.preset(args.certify).replace(face_slices=args.finer))}} if args.finer else {}),
        "paper_table4_N": {f"{k:g}": {"standard": v[0], "optimum": v[1]} for k, v in TABLE4_IMPACT_FORCE.items()},
        "paper_table2_um": TABLE2_OPTIMUM_UM,
    }
    Path(args.out).write_text(json.dumps(result, indent=2))
    figure(runs, ROOT / "docs/figures/optimize_convergence.png")
    print(json.dumps(result["forces"], indent=1))
    for case, out in runs.items():
        for method, r in out.items():
            print(f"{case:36s} {method:9s} search {r['best_objective_N']:9.1f} N  certified "
                  f"{r['certified_objective_N']:9.1f} N  evals {r['evaluations']:5d}  "
                  f"to 1 %: {r['evaluations_to_1pct_of_best']}  {r['wall_time_s']:.0f} s")


def robust_design(args, base, space, single_load_optimum, paper) -> dict:
    """The robust design: a GA on the mean F_s over the three loads x 8 misalignment samples
    (f_ma ~ U(-10, 10) µm), its best candidates certified at `--certify`, compared with the
    single-load optimum and the paper's at both accuracies."""
    import equinox as eqx

    errors = go.sample_errors(8, misalignment=0.010, seed=0)
    robust_obj = go.Objective.create(base, torques_Nm=LOADS, errors=errors)
    cfg = go.GAConfig(population=args.population // 2)
    robust = go.genetic(robust_obj, space, config=cfg, generations=args.robust_generations, seed=0, progress="lines",
                        run_dir=run_dir(args, "robust", "ga"), resume=args.run_dir is not None,
                        certify=args.certify)
    certified_obj = go.Objective.create(scene(args.certify), torques_Nm=LOADS, errors=errors)
    evaluate_one = eqx.filter_jit(lambda o, d: o.batch(d))  # one program for every design
    compare = {"robust": robust.best_design, "single-load optimum (GA, 1000 N·m)": single_load_optimum,
               "paper optimum (Table 2)": paper}
    stats = {}
    for label, design in compare.items():
        stats[label] = {"design": go.design_dict(design)}
        for accuracy, obj in ((args.accuracy, robust_obj), (args.certify, certified_obj)):
            ev = evaluate_one(obj, np.asarray(design, dtype=float)[None])
            force = np.asarray(ev.force[0])
            edge = np.asarray(ev.edge[0])
            stats[label][accuracy] = {"mean_force_N": float(force.mean()), "worst_force_N": float(force.max()),
                                      "edge_probability": float(edge.mean())}
    return {"samples": 8, "misalignment_tolerance_um": 10.0, "loads_Nm": LOADS,
            "population": args.population // 2, "generations": robust.steps, "evaluations": robust.evaluations,
            "search_objective_N": float(robust.best_objective), "certified_objective_N": float(robust.certified_objective),
            "certification_accuracy": args.certify, "wall_time_s": robust.wall_time_s, "comparison": stats}


def check_robust(args, robust: dict) -> None:
    """The robust comparison's designs at `--certify` with `--check-robust` face slices (4x
    the preset's contact steps; `--check-positions` positions per pitch if given): mean and
    worst F_s, edge probability, into `robust["check"]`."""
    import equinox as eqx

    from gearjax.optimize.space import SCENE_KEYS

    errors = go.sample_errors(robust["samples"], misalignment=robust["misalignment_tolerance_um"] * 1e-3, seed=0)
    base = gj.Accuracy.preset(args.certify)
    finer = base.finer(args.check_robust, args.check_positions)
    objective = go.Objective.create(scene(finer), torques_Nm=robust["loads_Nm"], errors=errors)
    evaluate_one = eqx.filter_jit(lambda o, d: o.batch(d))
    check = {"face_slices": finer.face_slices, "positions_per_pitch": finer.positions_per_pitch}
    for label, stats in robust["comparison"].items():
        design = [stats["design"][key] / factor for key, factor in SCENE_KEYS]  # mm, from the scene file's units
        ev = evaluate_one(objective, np.asarray(design, dtype=float)[None])
        force = np.asarray(ev.force[0])
        check[label] = {"mean_force_N": float(force.mean()), "worst_force_N": float(force.max()),
                        "edge_probability": float(np.asarray(ev.edge[0]).mean())}
    robust["check"] = check


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="population 12 x 6 generations, 2 starts x 8 iterations")
    parser.add_argument("--robust", action="store_true", help="also the robust design (spectrum x misalignment)")
    parser.add_argument("--check-robust", type=int, default=0, metavar="SLICES",
                        help="only evaluate the robust comparison's designs stored in --out at --certify with "
                             "SLICES face slices (the check of the certification); adds 'check' to its 'robust' entry")
    parser.add_argument("--check-positions", type=int, default=0,
                        help="with --check-robust: positions per pitch of the check (default: the preset's)")
    parser.add_argument("--robust-only", action="store_true",
                        help="only the robust design, compared with the GA's 1000 N·m optimum stored in --out; "
                             "updates its 'robust' entry")
    parser.add_argument("--accuracy", default="default", help="accuracy preset of the search (default: default)")
    parser.add_argument("--out", default=str(ROOT / "docs/results/optimize_seed001.json"))
    parser.add_argument("--population", type=int, default=40)
    parser.add_argument("--generations", type=int, default=30)
    parser.add_argument("--starts", type=int, default=8)
    parser.add_argument("--iterations", type=int, default=40)
    parser.add_argument("--robust-generations", type=int, default=10)
    parser.add_argument("--run-dir", default=None,
                        help="keep each search's run directory here; a rerun resumes the searches it holds")
    parser.add_argument("--certify", default="reference",
                        help="accuracy preset of the certification and of the forces table (default: reference)")
    parser.add_argument("--reevaluate", action="store_true",
                        help="only evaluate the designs stored in --out again with the current code (no search); "
                             "updates its 'forces' table")
    parser.add_argument("--assemble", action="store_true",
                        help="no search: the results of the finished searches in --run-dir, and the forces "
                             "table at --certify (pass the searches' --population, --starts, ...)")
    parser.add_argument("--finer", type=int, default=0,
                        help="with --assemble: also the forces table at --certify with this many face slices, "
                             "the check of the certification accuracy")
    args = parser.parse_args()
    if args.assemble:
        if args.run_dir is None:
            parser.error("--assemble needs --run-dir")
        assemble(args)
        return
    if args.reevaluate:
        stored = json.loads(Path(args.out).read_text())
        designs = {k: np.asarray(v) for k, v in stored["designs_mm"].items()}
        stored["forces"] = {args.accuracy: evaluate_batched(designs, args.accuracy), args.certify: evaluate_batched(designs, args.certify)}
        Path(args.out).write_text(json.dumps(stored, indent=2))
        print(json.dumps(stored["forces"], indent=1))
        return
    if args.quick:
        args.population, args.generations, args.starts, args.iterations = 12, 6, 2, 8
    if args.check_robust:
        stored = json.loads(Path(args.out).read_text())
        check_robust(args, stored["robust"])
        Path(args.out).write_text(json.dumps(stored, indent=2))
        print(json.dumps(stored["robust"]["check"], indent=1))
        return
    if args.robust_only:
        stored = json.loads(Path(args.out).read_text())
        base = scene(args.accuracy)
        stored["robust"] = robust_design(args, base, go.DesignSpace.for_scene(base),
                                         np.asarray(stored["designs_mm"]["GA, 1000 N·m"]),
                                         np.asarray(stored["designs_mm"]["paper optimum (Table 2)"]))
        Path(args.out).write_text(json.dumps(stored, indent=2))
        print(json.dumps(stored["robust"], indent=1))
        return

    base = scene(args.accuracy)  # the scene the search runs on
    space = go.DesignSpace.for_scene(base)
    runs: dict = {}
    single = go.Objective.create(base)
    ga1, gd1 = run_case("F_s at 1000 N·m", single, space, args, runs)
    spectrum = go.Objective.create(base, torques_Nm=LOADS)
    ga3, gd3 = run_case("mean F_s over 400/1000/1600 N·m", spectrum, space, args, runs)

    designs = {
        "standard (unmodified)": np.array([0.0, 0.0, 1.0, 1.0, 0.0, 0.0]),
        "paper optimum (Table 2)": np.asarray(TABLE2_OPTIMUM_UM) * np.array([1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3]),
        "GA, 1000 N·m": ga1.best_design,
        "gradient, 1000 N·m": gd1.best_design,
        "GA, spectrum": ga3.best_design,
        "gradient, spectrum": gd3.best_design,
    }
    table = {args.accuracy: evaluate_batched(designs, args.accuracy), args.certify: evaluate_batched(designs, args.certify)}
    result = {
        "note": SEED_001_NOTE,
        "settings": {"population": args.population, "generations": args.generations, "starts": args.starts,
                     "iterations": args.iterations, "search_accuracy": args.accuracy,
                     "certification_accuracy": args.certify, "speed_rpm": 5000.0,
                     "lower_mm": np.asarray(space.lower).tolist(), "upper_mm": np.asarray(space.upper).tolist()},
        "runs": runs,
        "designs_mm": {k: np.asarray(v).tolist() for k, v in designs.items()},
        "forces": table,
        "paper_table4_N": {f"{k:g}": {"standard": v[0], "optimum": v[1]} for k, v in TABLE4_IMPACT_FORCE.items()},
        "paper_table2_um": TABLE2_OPTIMUM_UM,
    }

    if args.robust:
        result["robust"] = robust_design(args, base, space, ga1.best_design, designs["paper optimum (Table 2)"])

    result["sensitivities_at_ga_optimum"] = go.sensitivities(single, ga1.best_design, space)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2))
    figure(runs, ROOT / "docs/figures/optimize_convergence.png")
    print(json.dumps({k: v for k, v in result.items() if k in ("forces", "robust")}, indent=1))
    for case, out in runs.items():
        for method, r in out.items():
            print(f"{case:36s} {method:9s} best {r['best_objective_N']:9.1f} N  evals {r['evaluations']:5d}  "
                  f"to 1 %: {r['evaluations_to_1pct_of_best']}  {r['wall_time_s']:.1f} s")


def figure(runs: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(runs), figsize=(5.5 * len(runs), 4), squeeze=False)
    for ax, (case, out) in zip(axes[0], runs.items()):
        for method, r in out.items():
            steps = len(r["history"])
            per = r["evaluations"] / steps
            ax.plot(per * np.arange(1, steps + 1), r["history"], marker=".", label=method)
        ax.set_xscale("log")
        ax.set_xlabel("objective evaluations (design × load)")
        ax.set_ylabel("best impact force F_s (N)")
        ax.set_title(case)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
