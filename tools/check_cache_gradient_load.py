"""Reproduces the crash that keeps reverse-mode impact gradients out of JAX's persistent
compilation cache (`gearjax.cache`): two fresh processes compute the optimiser's batched
value and gradient of the seed 001 objective (`fast`, 2 designs) with one new cache
directory; the first compiles and writes the executable, the second loads it and, with
jaxlib 0.10.2, dies of a segmentation fault (a stack overflow in LLVM's JIT linker).

    python tools/check_cache_gradient_load.py     # about 4 min on a 2-core CPU

Prints each process's exit status (0, then -11 where the bug is present).
"""

import subprocess
import sys
import tempfile

CHILD = """
import sys
import jax
jax.config.update("jax_enable_x64", True)
import numpy as np
import gearjax as gj
from gearjax import optimize as go
from gearjax.optimize.run import _batch_value_and_grad
from gearjax.papers.seed001 import paper_optimum, seed_pair

gj.enable_compilation_cache(sys.argv[1], programs=False)
scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                 effects=("impact",), accuracy="fast")
objective = go.Objective.create(scene)
space = go.DesignSpace.for_scene(scene, tip_relief_length=(0.5, 4.5))
units = np.asarray(space.to_unit(np.stack([np.asarray(paper_optimum().as_vector())] * 2)))
value, grad = _batch_value_and_grad(objective, space, units)
print("F_s", np.asarray(value), "dF/dx1", np.asarray(grad)[:, 0])
"""


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="gearjax-gradient-cache-") as directory:
        for run in ("compiles and writes", "loads"):
            proc = subprocess.run([sys.executable, "-c", CHILD, directory], capture_output=True, text=True)
            print(f"process that {run} the gradient program: exit status {proc.returncode}")
            print(proc.stdout.strip())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
