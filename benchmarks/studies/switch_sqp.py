"""SLSQP on the flank branch of the regime switch, with exact gradients: a first look.

    python benchmarks/studies/switch_sqp.py [--starts 5] [--seed 0] [--accuracy fast]
        [--margin 0.0] [--certify reference] [--check-slices 161] [--iterations 40]
        [--out benchmarks/results/switch_sqp.json]

Seed 001's pair at 1 000 N·m and 5 000 rpm in seed 001's design space (the unit cube). The
lowest designs sit on the switch between a flank strike and a tip-edge strike
(docs/landscape.md), on the flank side of it; `gj.impact_branches` (decision 0017) gives the
flank branch's force F_flank, smooth across that switch, and the switching function s
(mm of the gear's roll length, >= 0 where the flanks strike). This study solves

    min F_flank(x)  subject to  s(x) >= margin,  x in [0, 1]^6

with SciPy's SLSQP fed by F_flank, s and their Jacobian (`jax.jacfwd`: six tangents of the
branches' implicit derivatives) from `--starts` random starts (seeded), at the search
accuracy; each end point is then evaluated by `simulate` at the certification accuracy
(the ordinary impact, both branches' switch ignored), and the best certified end point of
the file at `default` with `--check-slices` face slices (the convergence study's finest).
A margin (mm of roll length) keeps the end point off the switch, which moves between
accuracies: an end point on s = 0 at `fast` can strike with the edge at `reference`. Every
finished start is written to `--out` at once and a rerun skips it (per seed, start and
margin). Costs are in calls of the branches' program and their Jacobian's, with the
measured time of each.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from scipy.optimize import minimize  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax import pipeline  # noqa: E402
from gearjax.optimize.space import DesignSpace, modification_from_design  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402

FORCE_SCALE = 1e3  # N: SLSQP sees F_flank in kN


def template(accuracy: str | gj.Accuracy) -> gj.Scene:
    scene = gj.Scene(seed_pair(), paper_optimum(), effects=("impact",), accuracy=accuracy,
                     operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0))
    return pipeline.prepare(scene)


def branches_program(scene: gj.Scene, space: DesignSpace):
    """`(f, jac)`: x (6,) -> (F_flank (N), s (mm), F_edge (N), codes (2,)) and its Jacobian."""

    def branches(x):
        s = eqx.tree_at(lambda s: s.modification, scene, modification_from_design(space.to_design(x)))
        pair = s.pair.resolve()
        tca = pipeline.unloaded(s, pair)
        ltca = pipeline.loaded(s, pair, tca, s.operating.torque)
        both = pipeline.branches(s, pair, tca, ltca, s.operating.torque, s.operating.speed)
        codes = jnp.stack([both.flank.result._value, both.edge.result._value, ltca.result._value])
        return jnp.stack([both.flank.force, both.switch, both.edge.force]), codes

    f = jax.jit(branches)
    jac = jax.jit(jax.jacfwd(lambda x: branches(x)[0]))
    return f, jac


def certified(scene: gj.Scene, space: DesignSpace, units: np.ndarray) -> list[dict]:
    out = []
    for x in units:
        s = eqx.tree_at(lambda s: s.modification, scene, modification_from_design(space.to_design(jnp.asarray(x))))
        hit = gj.simulate(s, throw=False).impact
        out.append({"force_N": float(hit.force), "regime": hit.regime_name, "result": int(hit.result._value)})
    return out


def run_start(x0, f, jac, iterations: int, margin: float, log: list) -> dict:
    cache: dict = {}

    def values(x):
        key = tuple(np.round(x, 15))
        if key not in cache:
            t = time.perf_counter()
            v, codes = f(jnp.asarray(x))
            v, codes = np.asarray(v), np.asarray(codes)
            log.append(("f", time.perf_counter() - t))
            cache[key] = (v, codes)
        return cache[key]

    def jacobian(x):
        key = ("j",) + tuple(np.round(x, 15))
        if key not in cache:
            t = time.perf_counter()
            cache[key] = np.asarray(jac(jnp.asarray(x)))
            log.append(("jac", time.perf_counter() - t))
        return cache[key]

    def objective(x):
        v, codes = values(x)
        return v[0] / FORCE_SCALE if np.all(codes[[0, 2]] == 0) and np.isfinite(v[0]) else 1e3

    def gradient(x):
        return jacobian(x)[0] / FORCE_SCALE

    def clearance(x):
        v, codes = values(x)
        return v[1] - margin if codes[0] == 0 and np.isfinite(v[1]) else -1.0

    result = minimize(objective, x0, jac=gradient, method="SLSQP", bounds=[(0.0, 1.0)] * 6,
                      constraints=[{"type": "ineq", "fun": clearance, "jac": lambda x: jacobian(x)[1]}],
                      options={"maxiter": iterations, "ftol": 1e-6})
    v, codes = values(result.x)
    return {"x": result.x.tolist(), "force_N": float(v[0]), "switch_mm": float(v[1]), "edge_force_N": float(v[2]),
            "codes": codes.tolist(), "slsqp": {"status": int(result.status), "message": str(result.message),
                                                "nit": int(result.nit), "nfev": int(result.nfev),
                                                "njev": int(result.njev)}}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--accuracy", default="fast")
    parser.add_argument("--certify", default="reference")
    parser.add_argument("--iterations", type=int, default=40)
    parser.add_argument("--margin", type=float, default=0.0, help="s >= margin (mm)")
    parser.add_argument("--check-slices", type=int, default=161)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("benchmarks/results/switch_sqp.json"))
    args = parser.parse_args(argv)

    done = json.loads(args.out.read_text()) if args.out.exists() else {"starts": []}
    scene = template(args.accuracy)
    space = DesignSpace.for_scene(scene)
    starts = np.random.default_rng(args.seed).random((args.starts, 6))
    f, jac = branches_program(scene, space)
    t = time.perf_counter()
    f(jnp.asarray(starts[0]))[0].block_until_ready()
    compile_f = time.perf_counter() - t
    t = time.perf_counter()
    jac(jnp.asarray(starts[0])).block_until_ready()
    compile_jac = time.perf_counter() - t
    print(f"first calls (compile and run): branches {compile_f:.1f} s, Jacobian {compile_jac:.1f} s", flush=True)
    reference = template(args.certify)
    for i, x0 in enumerate(starts):
        if any(r["start"] == i and r["seed"] == args.seed and r.get("margin_mm", 0.0) == args.margin
               for r in done["starts"]):
            continue
        log: list = []
        t = time.perf_counter()
        record = run_start(x0, f, jac, args.iterations, args.margin, log)
        record.update(start=i, seed=args.seed, margin_mm=args.margin, accuracy=args.accuracy,
                      wall_s=time.perf_counter() - t,
                      calls={k: sum(1 for n, _ in log if n == k) for k in ("f", "jac")},
                      median_s={k: float(np.median([d for n, d in log if n == k] or [np.nan])) for k in ("f", "jac")})
        record["certified"] = certified(reference, space, np.asarray([record["x"]]))[0] | {"accuracy": args.certify}
        done["starts"].append(record)
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(done, indent=1))
        print(json.dumps({k: record[k] for k in ("start", "force_N", "switch_mm", "certified", "calls", "slsqp")}),
              flush=True)
    check_best(done, space, args)


def check_best(done: dict, space: DesignSpace, args) -> None:
    """The best certified end point of the file at `default` with `--check-slices` slices."""
    ok = [r for r in done["starts"] if r["certified"]["result"] == 0]
    if not ok or args.check_slices <= 0:
        return
    best = min(ok, key=lambda r: r["certified"]["force_N"])
    if best.get("checked", {}).get("slices") == args.check_slices:
        return
    scene = template(gj.Accuracy.preset("default").replace(face_slices=args.check_slices))
    best["checked"] = certified(scene, space, np.asarray([best["x"]]))[0] | {"slices": args.check_slices}
    args.out.write_text(json.dumps(done, indent=1))
    print("best", best["certified"], "checked", best["checked"], flush=True)


if __name__ == "__main__":
    main()
