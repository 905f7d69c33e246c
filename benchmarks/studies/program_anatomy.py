"""What a compiled program is made of: its equations counted by the gearjax function that
emitted them.

    python benchmarks/studies/program_anatomy.py [--grad] [--accuracy fast] [--top 40] [--hlo]

Traces the optimiser's objective for one design (seed 001 pair, the paper's optimum, impact
at 1 000 N·m and 5 000 rpm) with `jax.make_jaxpr`, or its value and gradient with `--grad`,
expands every sub-jaxpr (loops, conditionals, `jit`, custom derivatives) and counts the
leaf equations:

* inclusive, by function: an equation counts once for every gearjax function on the Python
  stack that traced it, so a stage's count includes everything it calls;
* by innermost line: the gearjax line that emitted it.

`--hlo` also lowers the program and counts its StableHLO lines and `optx.root_find`
functions. The counts say where tracing and compilation time goes (`docs/test_suite.md`).
"""

from __future__ import annotations

import argparse
import collections
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
from jax.extend import core as jcore  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax import optimize as go  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402


def leaves(jaxpr):
    """The equations of `jaxpr` without sub-jaxprs, those of its sub-jaxprs expanded."""
    for eqn in jaxpr.eqns:
        subs = [j for v in eqn.params.values() for j in (v if isinstance(v, (list, tuple)) else [v])
                if isinstance(j, (jcore.ClosedJaxpr, jcore.Jaxpr))]
        if subs:
            for sub in subs:
                yield from leaves(sub.jaxpr if isinstance(sub, jcore.ClosedJaxpr) else sub)
        else:
            yield eqn


def gearjax_frames(eqn) -> list[tuple[str, str, int]]:
    """(file under gearjax/, function, line) of the gearjax frames that traced `eqn`, innermost first."""
    tb = eqn.source_info.traceback
    if tb is None:
        return []
    return [(f.file_name.split("/gearjax/")[-1], f.function_name, f.line_num)
            for f in tb.frames if "/gearjax/" in f.file_name]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grad", action="store_true", help="the value and gradient, not the value")
    parser.add_argument("--accuracy", default="fast", choices=("fast", "default", "reference"))
    parser.add_argument("--top", type=int, default=40)
    parser.add_argument("--hlo", action="store_true", help="also lower it and count StableHLO lines")
    args = parser.parse_args(argv)
    scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                     effects=("impact",), accuracy=args.accuracy)
    objective = go.Objective.create(scene)
    design = jnp.asarray(paper_optimum().as_vector(), objective.torques.dtype)
    fn = jax.value_and_grad(objective) if args.grad else objective

    t = time.perf_counter()
    closed = jax.make_jaxpr(fn)(design)
    print(f"traced in {time.perf_counter() - t:.1f} s")
    inclusive: collections.Counter = collections.Counter()
    innermost: collections.Counter = collections.Counter()
    total = 0
    for eqn in leaves(closed.jaxpr):
        total += 1
        frames = gearjax_frames(eqn)
        for name in dict.fromkeys(f"{f}:{fn_name}" for f, fn_name, _ in frames):
            inclusive[name] += 1
        if frames:
            f, fn_name, line = frames[0]
            innermost[f"{f}:{line} ({fn_name})"] += 1
    print(f"{total} equations")
    print("\ninclusive, by function")
    for name, n in inclusive.most_common(args.top):
        print(f"{n:8d} {100 * n / total:5.1f} %  {name}")
    print("\nby innermost line")
    for name, n in innermost.most_common(args.top):
        print(f"{n:8d} {100 * n / total:5.1f} %  {name}")
    if args.hlo:
        t = time.perf_counter()
        text = jax.jit(fn).lower(design).as_text()
        print(f"\nlowered in {time.perf_counter() - t:.1f} s: {text.count(chr(10))} StableHLO lines, "
              f"{text.count('func.func private @root_find')} root_find functions")


if __name__ == "__main__":
    main()
