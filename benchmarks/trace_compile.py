"""Trace, lower and compile time of `simulate` on the built-in default scene, timed apart.

    python benchmarks/trace_compile.py [--accuracy fast|default|reference] [--out NAME]
    python benchmarks/trace_compile.py --gradient [--accuracy fast|default|reference]

Each phase is timed once in a fresh process (JAX caches traces in-process, so a second
measurement would time the cache). The persistent compilation cache is not used.
`--gradient` times the optimiser's value and gradient instead
(`jax.jit(jax.value_and_grad(objective))` of the seed 001 pair's impact objective at the
paper's optimum, 1 000 N·m, 5 000 rpm): trace and lower together, then compile, and prints
the value and gradient (a check that two versions compute the same).
"""

from __future__ import annotations

import argparse
import time

import gearjax  # noqa: F401  (sets its XLA flag before JAX starts its backends)
import equinox as eqx
import jax

jax.config.update("jax_enable_x64", True)

from _common import count_equations, machine, write  # noqa: E402

from gearjax.pipeline import prepare, run  # noqa: E402
from gearjax.io.scene_file import default_scene  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--accuracy", default="default")
    parser.add_argument("--out", default=None, help="write benchmarks/results/<OUT>.json")
    parser.add_argument("--trace-only", action="store_true", help="stop after lowering")
    parser.add_argument("--gradient", action="store_true", help="the optimiser's value and gradient instead")
    args = parser.parse_args()
    if args.gradient:
        return gradient(args.accuracy)
    scene, _ = default_scene()
    if args.accuracy != "default":
        import dataclasses

        scene = dataclasses.replace(scene, accuracy=gearjax.Accuracy.preset(args.accuracy))
    scene = prepare(scene)
    dynamic, static = eqx.partition(scene, eqx.is_array)
    fn = jax.jit(lambda d: run(eqx.combine(d, static)))
    t0 = time.perf_counter()
    traced = fn.trace(dynamic)
    t1 = time.perf_counter()
    lowered = traced.lower()
    t2 = time.perf_counter()
    if args.trace_only:
        print(f"jaxpr_equations {count_equations(traced.jaxpr.jaxpr)}")
        print(f"stablehlo_lines {lowered.as_text().count(chr(10))}")
        print(f"trace_s {t1 - t0:.2f}  lower_s {t2 - t1:.2f}")
        return
    compiled = lowered.compile()
    t3 = time.perf_counter()
    jax.block_until_ready(compiled(dynamic))
    t4 = time.perf_counter()
    jax.block_until_ready(compiled(dynamic))
    t5 = time.perf_counter()
    out = {
        "machine": machine(),
        "scene": "default (seed 001, paper optimum, 1000 N m, 5000 rpm, impact)",
        "accuracy": args.accuracy,
        "jaxpr_equations": count_equations(traced.jaxpr.jaxpr),
        "stablehlo_lines": lowered.as_text().count("\n"),
        "trace_s": t1 - t0,
        "lower_s": t2 - t1,
        "compile_s": t3 - t2,
        "first_run_s": t4 - t3,
        "run_s": t5 - t4,
    }
    for key, value in out.items():
        print(f"{key:12s} {value if not isinstance(value, float) else f'{value:.2f}'}")
    if args.out:
        write(args.out, out)


def gradient(accuracy: str) -> None:
    import jax.numpy as jnp

    from gearjax import OperatingPoint, Scene
    from gearjax import optimize as go
    from gearjax.papers.seed001 import paper_optimum, seed_pair

    scene = Scene(seed_pair(), paper_optimum(), operating=OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                  effects=("impact",), accuracy=accuracy)
    objective = go.Objective.create(scene)
    design = jnp.asarray(paper_optimum().as_vector(), objective.torques.dtype)
    t0 = time.perf_counter()
    lowered = jax.jit(jax.value_and_grad(objective)).lower(design)
    t1 = time.perf_counter()
    compiled = lowered.compile()
    t2 = time.perf_counter()
    value, grad = compiled(design)
    print(f"accuracy {accuracy}  trace+lower {t1 - t0:.1f} s  compile {t2 - t1:.1f} s")
    print(f"value {float(value)!r}  gradient {[float(g) for g in grad]}")


if __name__ == "__main__":
    main()
