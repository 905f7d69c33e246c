"""Cost of the optimisation objective.

    python benchmarks/optimize.py [--accuracy fast] [--repeats 5]

Seed 001 pair, paper optimum, 1000 N·m, 5000 rpm. Times (compile apart from run, medians
of repeats): the objective of one design; its value and gradient; a population of 40
evaluated in one program one design after another (`lax.map`, the default) and all at
once (`vmap`, batch_size 40); the population at 3 loads; and the error of the search
accuracy against `default` at the paper optimum. Writes benchmarks/results/optimize.json.
"""

from __future__ import annotations

import argparse
import json

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
from _common import RESULTS, machine, time_compiled_output  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax import optimize as go  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--accuracy", default="fast")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--population", type=int, default=40)
    args = parser.parse_args()
    scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                     effects=("impact",), accuracy=args.accuracy)
    space = go.DesignSpace.for_scene(scene)
    y0 = jnp.asarray(paper_optimum().as_vector())
    designs = space.to_design(jax.random.uniform(jax.random.PRNGKey(0), (args.population, 6)))
    rows = []

    def row(name, fn, *fn_args, designs_per_call=1, loads=1):
        compile_s, run_s, runs, out = time_compiled_output(fn, *fn_args, repeats=args.repeats)
        per_eval = run_s / (designs_per_call * loads)
        rows.append({"case": name, "compile_s": compile_s, "run_s": run_s, "runs_s": runs,
                     "designs": designs_per_call, "loads": loads, "per_evaluation_ms": 1e3 * per_eval,
                     "evaluations_per_s": 1.0 / per_eval})
        print(f"{name:48s} compile {compile_s:7.1f} s  run {run_s * 1e3:9.2f} ms  per evaluation {per_eval * 1e3:7.2f} ms", flush=True)
        return out

    one = go.Objective.create(scene)
    value = row("objective, 1 design", eqx.filter_jit(lambda o, y: o(y)), one, y0)
    row("value_and_grad, 1 design", eqx.filter_jit(lambda o, y: jax.value_and_grad(o)(y)), one, y0)
    batch = eqx.filter_jit(lambda o, d: o.batch(d).objective)
    row(f"population {args.population}, lax.map (batch_size 1)", batch, one, designs, designs_per_call=args.population)
    vmapped = go.Objective.create(scene, batch_size=args.population)
    row(f"population {args.population}, vmap (batch_size {args.population})", batch, vmapped, designs, designs_per_call=args.population)
    three = go.Objective.create(scene, torques_Nm=[400.0, 1000.0, 1600.0])
    row(f"population {args.population} x 3 loads, lax.map", batch, three, designs, designs_per_call=args.population, loads=3)

    default_scene = gj.Scene(seed_pair(), paper_optimum(), operating=scene.operating, effects=("impact",), accuracy="default")
    reference = float(gj.simulate(default_scene).impact.force)
    accuracy = {"search_accuracy": args.accuracy, "force_search_N": float(value), "force_default_N": reference,
                "relative_error": float(value) / reference - 1.0}
    print(json.dumps(accuracy))
    out = {"machine": machine(), "rows": rows, "accuracy_at_paper_optimum": accuracy}
    (RESULTS / "optimize.json").write_text(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
