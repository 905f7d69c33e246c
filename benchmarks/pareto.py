"""The Pareto front of impact force, loaded TE and contact pressure over a duty cycle:
gearjax's gradient front search against a sampling-and-filter search and NSGA-II.

    python benchmarks/pareto.py [--seeds 5] [--budget 1200] [--methods pareto_sqp sobol_filter nsga2]
        [--accuracy default] [--certify reference] [--finer reference@128x161] [--plot]

Seed 001's pair and design space at 5 000 rpm over the duty cycle 400/1 000/1 600 N·m with
time shares 1:2:1 (0.25/0.5/0.25). Three quantities: the time-weighted mean impact force
F_s (N), the time-weighted mean loaded TE peak-to-peak (µm) and the worst-case (largest
over the loads) Hertz pressure (MPa). Every method gets the same budget, counted in
forward evaluations of one design over the whole duty cycle; a call that also computes
the Jacobian counts as `jacobian_cost` evaluations per design, the ratio of its measured
time per design to a forward call's, measured in this run.

Methods:
* `pareto_sqp`: `gearjax.optimize.pareto_front` (21 augmented-Chebyshev scalarisations,
  each a slot of the switching-aware SQP on the flank branch with s >= 0.05 mm), as many
  iterations as the budget buys; its archive holds every design evaluated, with the force
  of the regime that strikes first.
* `sobol_filter`: scrambled Sobol points in the unit cube, the non-dominated ones kept
  (the sampling-and-filter search of the commercial tools).
* `nsga2`: pymoo's NSGA-II, population 40 (ask and tell); a failed design gets 1e6.

Hypervolume: of each run's evaluated designs (search accuracy) at a grid of budgets,
with the quantities scaled to [0, 1] between the ideal and the nadir point of the
non-dominated set of all runs of all methods, and the reference point 1.1 in each; so it
is recomputed from the runs file by every call. The front of the `pareto_sqp` run of
median hypervolume is certified at `--certify` (`pareto_front`'s certification: its
spread-out non-dominated designs evaluated again, the true force there), and its five
spread-out certified designs are checked at `--finer` (`Accuracy.from_spec(..., finer=True)`:
with the active-set steps the finer grid needs).

Long runs lose nothing: the `pareto_sqp` runs keep their run directories
(`benchmarks/results/pareto_runs/`, resumed), every finished run goes at once to
`benchmarks/results/pareto_runs.json`, and a rerun skips what is there. The summary in the
issue's form goes to `benchmarks/results/pareto.json`, the tables to stdout (markdown)
and the figures to `docs/figures/pareto_*.png`.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from _common import RESULTS, machine, median_time  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax import optimize as go  # noqa: E402
from gearjax.optimize.batch import batch_evaluation, batch_quantities  # noqa: E402
from gearjax.optimize.front import hypervolume, nondominated, spread  # noqa: E402
from gearjax.optimize.objective import QUANTITIES  # noqa: E402
from gearjax.optimize.pareto import ParetoConfig, pareto_values  # noqa: E402
from gearjax.optimize.pareto_run import pareto_front  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402

LOADS_NM, SHARES = [400.0, 1000.0, 1600.0], [1.0, 2.0, 1.0]
SPECS = ("force", "lte", "pressure:max")
METHODS = ("pareto_sqp", "sobol_filter", "nsga2")
CHUNK = 40
RUNS_FILE = RESULTS / "pareto_runs.json"
RUN_DIRS = RESULTS / "pareto_runs"
FAILED = 1e6


def objective_for(accuracy: str) -> go.Objective:
    scene = gj.Scene(seed_pair(), paper_optimum(), effects=("impact",), accuracy=accuracy,
                     operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0))
    return go.Objective.create(scene, torques_Nm=LOADS_NM, weights=SHARES)


def quantities(objective, space, units, chunk: int = CHUNK) -> np.ndarray:
    """The three quantities (natural sense) of unit-cube points (n, 6), `chunk` per call;
    non-finite where a stage failed."""
    units = np.atleast_2d(np.asarray(units, float))
    return batch_quantities(objective, space.to_design(jnp.asarray(units)), ParetoConfig(quantities=SPECS).parsed(),
                            chunk)


def jacobian_cost(objective, space, repeats: int = 3) -> dict:
    """Time per design of `pareto_values` over a forward call's, on the same CHUNK random
    designs (compiled apart, medians): the forward call evaluates all CHUNK, the Jacobian
    program (K rows) two overlapping calls of K that cover them."""
    config = ParetoConfig(quantities=SPECS)
    units = jax.random.uniform(jax.random.PRNGKey(7), (CHUNK, 6), jnp.float64)
    forward = median_time(lambda: batch_evaluation(objective, space.to_design(units)), repeats) / CHUNK
    k = config.slots
    calls = [median_time(lambda rows=rows: pareto_values(objective, space, rows, config.parsed()), repeats)
             for rows in (units[:k], units[-k:])]
    both = sum(calls) / (2 * k)
    return {"forward_s_per_design": forward, "jacobian_s_per_design": both, "ratio": both / forward,
            "jacobian_calls_s": calls}


def run_pareto_sqp(objective, space, seed, budget, cost, certify=None) -> dict:
    config = ParetoConfig(quantities=SPECS)
    config = ParetoConfig(quantities=SPECS, iterations=max(1, int(budget // (config.slots * cost))))
    result = pareto_front(objective, space, config, seed=seed, run_dir=RUN_DIRS / f"seed{seed}", resume=True,
                          progress="lines", certify=certify)
    points = []
    for line in (RUN_DIRS / f"seed{seed}" / "history.jsonl").read_text().splitlines():
        record = json.loads(line)
        for i, q in enumerate(record["quantities"]):
            if np.all(np.isfinite(q)):
                spent = ((record["step"] - 1) * config.slots + i + 1) * cost
                points.append([spent, *q])
    return {"points": points, "iterations": config.iterations, "result": result}


def run_sobol(objective, space, seed, budget) -> dict:
    from scipy.stats import qmc

    units = qmc.Sobol(d=6, scramble=True, seed=seed).random(int(budget))
    q = quantities(objective, space, units)
    return {"points": [[i + 1.0, *row] for i, row in enumerate(q.tolist())]}


def run_nsga2(objective, space, seed, budget, population: int = 40) -> dict:
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.evaluator import Evaluator
    from pymoo.core.problem import Problem
    from pymoo.problems.static import StaticProblem

    problem = Problem(n_var=6, n_obj=len(SPECS), xl=0.0, xu=1.0)
    algorithm = NSGA2(pop_size=population)
    algorithm.setup(problem, termination=("n_gen", int(budget // population)), seed=seed, verbose=False)
    sense = np.asarray([QUANTITIES[go.pareto.parse_quantity(s)[0]].sense for s in SPECS])
    points, spent = [], 0
    while algorithm.has_next():
        pop = algorithm.ask()
        q = quantities(objective, space, pop.get("X"))
        F = np.where(np.isfinite(q), q * sense, FAILED)
        Evaluator().eval(StaticProblem(problem, F=F), pop)
        algorithm.tell(infills=pop)
        points += [[spent + i + 1.0, *row] for i, row in enumerate(q.tolist())]
        spent += len(q)
    return {"points": points}


def load_runs() -> dict:
    return json.loads(RUNS_FILE.read_text()) if RUNS_FILE.exists() else {"runs": {}}


def save_runs(data: dict) -> None:
    tmp = RUNS_FILE.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(data))
    tmp.replace(RUNS_FILE)


def minimised(points) -> np.ndarray:
    sense = np.asarray([QUANTITIES[go.pareto.parse_quantity(s)[0]].sense for s in SPECS])
    P = np.asarray(points, float).reshape(-1, 1 + len(SPECS))
    return P[:, 1:] * sense


def scaling(data: dict) -> tuple[np.ndarray, np.ndarray]:
    """Ideal and nadir point of the non-dominated set of every run's points."""
    every = np.concatenate([minimised(run["points"]) for runs in data["runs"].values() for run in runs.values()])
    front = every[nondominated(every)]
    return front.min(axis=0), front.max(axis=0)


def hv_curve(points, ideal, nadir, budgets) -> list[float]:
    P = np.asarray(points, float).reshape(-1, 1 + len(SPECS))
    scaled = (minimised(points) - ideal) / (nadir - ideal)
    return [hypervolume(scaled[P[:, 0] <= b + 1e-9], np.full(len(SPECS), 1.1)) for b in budgets]


def certify_front(data: dict, objective, space, budget, seed: int, certify: str, finer: str | None) -> list:
    """The `pareto_sqp` run of `seed` certified (its run directory's `front.json`), five
    spread-out certified designs checked at `finer`; the front's entries."""
    cost = data["jacobian_cost"]["ratio"]
    result = run_pareto_sqp(objective, space, seed, budget, cost, certify=certify)["result"]
    designs, certified = result.front
    entries = [{"design": dict(go.design_dict(d)), "objectives": dict(zip(result.quantities, map(float, c))),
                "certified": True, "accuracy": result.certification_accuracy} for d, c in zip(designs, certified)]
    if finer is not None:
        checks = data.setdefault("finer", {})
        setting = gj.Accuracy.from_spec(finer, finer=True)  # with the steps 161 slices need
        if (checks.get("seed"), checks.get("accuracy"), checks.get("contact_max_steps")) != \
                (seed, finer, setting.contact_max_steps):
            chosen = spread(certified * np.asarray([QUANTITIES[n.split(":")[0]].sense for n in result.quantities]),
                            5)
            target = go.certification.with_accuracy(objective, setting)
            q = quantities(target, space, space.to_unit(jnp.asarray(designs[chosen])), chunk=len(chosen))
            checks.update(seed=seed, accuracy=finer, contact_max_steps=setting.contact_max_steps,
                          indices=chosen.tolist(), values=q.tolist(),
                          relative_difference=((certified[chosen] - q) / q).tolist())
            save_runs(data)
        for i, q in zip(checks["indices"], checks["values"]):
            entries[i]["finer"] = dict(zip(result.quantities, q))
    return entries


def summary(data: dict, budget: float) -> dict:
    ideal, nadir = scaling(data)
    budgets = [budget * k / 10 for k in range(1, 11)]
    methods, curves = {}, {}
    for method, runs in data["runs"].items():
        methods[method], curves[method] = [], []
        for seed, run in sorted(runs.items(), key=lambda kv: int(kv[0])):
            curve = hv_curve(run["points"], ideal, nadir, budgets)
            curves[method].append(curve)
            methods[method].append({"seed": int(seed), "hypervolume": curve[-1], "evaluations": budget,
                                    "front_size": int(np.sum(nondominated(minimised(run["points"])))),
                                    "wall_s": run.get("wall_s")})
    return {"methods": methods, "budgets": budgets, "curves": curves, "ideal": ideal.tolist(),
            "nadir": nadir.tolist(), "reference_point": [1.1] * len(SPECS)}


def markdown(summary_: dict) -> str:
    lines = ["| method | median hypervolume | range | seeds | median front size |", "|---|---|---|---|---|"]
    for method, entries in summary_["methods"].items():
        hv = [e["hypervolume"] for e in entries]
        sizes = [e["front_size"] for e in entries]
        lines.append(f"| {method} | {statistics.median(hv):.4f} | {min(hv):.4f}–{max(hv):.4f} | {len(hv)} | "
                     f"{statistics.median(sizes):g} |")
    return "\n".join(lines)


def plot(summary_: dict, front: list, data: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figures = RESULTS.parent.parent / "docs" / "figures"
    fig, ax = plt.subplots(figsize=(6, 4))
    for method, curves in summary_["curves"].items():
        median = np.median(np.asarray(curves), axis=0)
        ax.plot(summary_["budgets"], median, marker="o", label=f"{method} (median of {len(curves)})")
    ax.set_xlabel("forward-evaluation equivalents (one design over the duty cycle)")
    ax.set_ylabel("hypervolume (scaled quantities, reference 1.1)")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(figures / "pareto_hypervolume.png", dpi=120)
    names = list(front[0]["objectives"])
    values = np.asarray([[entry["objectives"][n] for n in names] for entry in front])
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for run in data["runs"].get("sobol_filter", {}).values():
        P = np.asarray(run["points"])
        ax.scatter(P[:, 1], P[:, 2], s=4, color="0.8")
        break
    sc = ax.scatter(values[:, 0], values[:, 1], c=values[:, 2], cmap="viridis", edgecolor="k", zorder=3)
    fig.colorbar(sc, label=f"{names[2]} (MPa)")
    ax.set_xlabel(f"{names[0]} (N)")
    ax.set_ylabel(f"{names[1]} (µm)")
    ax.set_title("certified front (colour: pressure); grey: one Sobol run")
    fig.tight_layout()
    fig.savefig(figures / "pareto_front.png", dpi=120)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--budget", type=float, default=1200.0)
    parser.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS))
    parser.add_argument("--accuracy", default="default")
    parser.add_argument("--certify", default="reference")
    parser.add_argument("--finer", default=None, help="a finer accuracy (e.g. reference@128x161) for five certified designs")
    parser.add_argument("--plot", action="store_true")
    args = parser.parse_args()
    objective = objective_for(args.accuracy)
    space = go.DesignSpace.for_scene(objective.scene)
    data = load_runs()
    data["settings"] = {"loads_Nm": LOADS_NM, "time_shares": SHARES, "speed_rpm": 5000.0, "quantities": list(SPECS),
                        "budget": args.budget, "accuracy": args.accuracy, "machine": machine()}
    if "jacobian_cost" not in data:
        data["jacobian_cost"] = jacobian_cost(objective, space)
        save_runs(data)
    print("jacobian cost:", data["jacobian_cost"], flush=True)
    for seed in range(args.seeds):
        for method in args.methods:
            runs = data["runs"].setdefault(method, {})
            if str(seed) in runs:
                continue
            start = time.perf_counter()
            if method == "pareto_sqp":
                run = run_pareto_sqp(objective, space, seed, args.budget, data["jacobian_cost"]["ratio"])
                run.pop("result")
            elif method == "sobol_filter":
                run = run_sobol(objective, space, seed, args.budget)
            else:
                run = run_nsga2(objective, space, seed, args.budget)
            run["wall_s"] = time.perf_counter() - start
            runs[str(seed)] = run
            save_runs(data)
            print(f"{method} seed {seed}: {len(run['points'])} points, {run['wall_s']:.0f} s", flush=True)
    result = summary(data, args.budget)
    print(markdown(result))
    front = []
    if args.certify != "none" and "pareto_sqp" in data["runs"]:
        entries = result["methods"]["pareto_sqp"]
        median_seed = sorted(entries, key=lambda e: e["hypervolume"])[len(entries) // 2]["seed"]
        front = certify_front(data, objective, space, args.budget, median_seed, args.certify, args.finer)
        print(f"certified front of pareto_sqp seed {median_seed}: {len(front)} designs", flush=True)
    out = {"methods": result["methods"], "front": front,
           "settings": {**data["settings"], "jacobian_cost": data["jacobian_cost"], "ideal": result["ideal"],
                        "nadir": result["nadir"], "reference_point": result["reference_point"],
                        "budgets": result["budgets"],
                        "median_curves": {m: np.median(np.asarray(c), axis=0).tolist()
                                          for m, c in result["curves"].items()},
                        "finer": data.get("finer")}}
    (RESULTS / "pareto.json").write_text(json.dumps(out, indent=1))
    if args.plot and front:
        plot(result, front, data)


if __name__ == "__main__":
    main()
