"""Reverse-mode gradient of the optimiser's impact objective against central differences.

    python benchmarks/studies/impact_gradient_check.py [--step 1e-4]

The seed 001 pair at the `fast` preset, 1 000 N·m, 5 000 rpm (the objective of
`tests/test_optimize.py`), at the two starts of its gradient test: seed 001's lower bounds
and the lower bounds plus a quarter of the bounds' width. Prints F_s, the gradient of
`gearjax.optimize.batch.batch_value_and_grad` and central differences of
`_batch_objective` in unit-cube coordinates (N per unit of each bound's width). Central
differences straddle a jump where the step crosses a regime or candidate switch: compare
where the two agree in order of magnitude and sign.
"""

from __future__ import annotations

import argparse

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax import optimize as go  # noqa: E402
from gearjax.optimize.batch import batch_objective as _batch_objective, batch_value_and_grad as _batch_value_and_grad  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402

BATCH = 12  # the batch of `tests/test_optimize.py`: the same program


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--step", type=float, default=1e-4, help="central-difference step (unit-cube coordinates)")
    args = parser.parse_args()
    scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                     effects=("impact",), accuracy="fast")
    objective = go.Objective.create(scene)
    space = go.DesignSpace.for_scene(scene, tip_relief_length=(0.5, 4.5))
    lower = np.asarray(space.lower)
    starts = np.asarray(space.to_unit(np.stack([lower, lower + 0.25 * np.asarray(space.width)])))
    values, grads = _batch_value_and_grad(objective, space, starts)
    h = args.step
    for k, start in enumerate(starts):
        rows = np.repeat(start[None], 2 * 6, axis=0)
        for i in range(6):
            rows[2 * i, i] += h
            rows[2 * i + 1, i] -= h
        shifted = []
        for part in (rows[:BATCH], rows[BATCH:]):
            if len(part):
                padded = np.concatenate([part, np.repeat(part[-1:], BATCH - len(part), axis=0)])
                shifted.append(np.asarray(_batch_objective(objective, space.to_design(jnp.asarray(padded))))[: len(part)])
        f = np.concatenate(shifted)
        central = (f[0::2] - f[1::2]) / (2 * h)
        print(f"start {k}: F_s {float(values[k]):.6g} N")
        print("  reverse mode       ", np.array2string(np.asarray(grads[k]), precision=1, suppress_small=True))
        print("  central differences", np.array2string(central, precision=1, suppress_small=True))


if __name__ == "__main__":
    main()
