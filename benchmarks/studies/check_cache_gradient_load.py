"""The optimiser's gradient program and JAX's persistent compilation cache (`gearjax.runtime.cache`).

Two fresh processes compute the optimiser's batched value and gradient of the seed 001
objective (`fast`, 2 designs) with one new cache directory.

    python benchmarks/studies/check_cache_gradient_load.py         # gearjax's program: several minutes on 2 cores
    python benchmarks/studies/check_cache_gradient_load.py --raw   # the same gradient, never excluded from the cache

With a current jaxlib (>= 0.12) the first process writes the program and the second loads
it and prints the same value and gradient. With jaxlib 0.10.2, `--raw` shows why gearjax keeps
it out of the cache there: the second process dies of a segmentation fault (exit status
-11, a stack overflow in LLVM's JIT linker), while gearjax's own program
(`exclude_from_persistent_cache`) writes no entry, so both processes compile it and exit 0.
Prints each process's exit status, its result and the cache entries of the gradient
program after it.
"""

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = """
import logging, sys, time
import equinox as eqx
import jax
jax.config.update("jax_enable_x64", True)
import numpy as np
import gearjax as gj
from gearjax import optimize as go
from gearjax.optimize.batch import batch_value_and_grad as _batch_value_and_grad
from gearjax.papers.seed001 import paper_optimum, seed_pair

gj.enable_compilation_cache(sys.argv[1], programs=False)
messages = []
handler = logging.Handler()
handler.emit = lambda record: messages.append(record.getMessage())
logging.getLogger("jax._src.compiler").addHandler(handler)
logging.getLogger("jax._src.compiler").setLevel(logging.DEBUG)
start = time.perf_counter()
scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                 effects=("impact",), accuracy="fast")
objective = go.Objective.create(scene)
space = go.DesignSpace.for_scene(scene, tip_relief_length=(0.5, 4.5))
units = np.asarray(space.to_unit(np.stack([np.asarray(paper_optimum().as_vector())] * 2)))
if sys.argv[2] == "raw":
    @eqx.filter_jit  # a gradient program of the same objective, never excluded
    def raw_gradient(objective, space, units):
        return jax.lax.map(jax.value_and_grad(lambda x: objective(space.to_design(x))), units)
    value, grad = raw_gradient(objective, space, units)
else:
    value, grad = _batch_value_and_grad(objective, space, units)
print("F_s", np.asarray(value), "dF/dx1", np.asarray(grad)[:, 0], f"({time.perf_counter() - start:.0f} s)")
for m in messages:
    if "gradient" in m and ("cache hit" in m or "CACHE MISS" in m):
        print("  ", m[:110])
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--raw", action="store_true", help="the gradient without gearjax's exclusion from the cache")
    mode = "raw" if parser.parse_args().raw else "gearjax"
    with tempfile.TemporaryDirectory(prefix="gearjax-gradient-cache-") as directory:
        for run in ("first", "second"):
            proc = subprocess.run([sys.executable, "-c", CHILD, directory, mode], capture_output=True, text=True)
            entries = sorted(p.name for p in Path(directory).iterdir() if "grad" in p.name)
            print(f"{run} process ({mode}): exit status {proc.returncode}; gradient entries in the cache: {entries}")
            print(proc.stdout.strip())
            for line in proc.stderr.splitlines():
                if "compilation cache" in line or "Segmentation" in line:
                    print("  stderr:", line[:300])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
