"""The XLA CPU deadlock of jaxlib 0.10's batched LAPACK kernels, reproduced in a few seconds.

    python tools/diagnostics/issue12/lapack_deadlock.py [--gearjax] [--tries 5] [--timeout 60]

Runs a program of two independent batched LU solves (4000 x 10x10 each, above jaxlib's
2e5-flop threshold for splitting a batch over XLA's intra-op pool) 20 times in a fresh
process, `--tries` times, each under `--timeout` seconds, with the concurrency-optimised
scheduler on and, with `--gearjax`, gearjax imported first (its `PJRT_NPROC=1`). Prints how
many tries hung. 2026-11-26, 2 cores, jaxlib 0.10.2: 5/5 hung without gearjax's setting,
0/5 with it; with `--xla_cpu_enable_concurrency_optimized_scheduler=false` alone (the old
workaround) this program returns, the test suite's derivative programs still hung.
"""

import argparse
import os
import subprocess
import sys

PROGRAM = """
import sys
if sys.argv[1] == "1":
    import gearjax
import jax, jax.numpy as jnp
jax.config.update("jax_enable_x64", True)
k = jax.random.split(jax.random.PRNGKey(0), 4)
A1, A2 = (jax.random.normal(key, (4000, 10, 10)) + 5 * jnp.eye(10) for key in k[:2])
b1, b2 = (jax.random.normal(key, (4000, 10, 1)) for key in k[2:])
f = jax.jit(lambda A1, A2, b1, b2: (jnp.linalg.solve(A1, b1), jnp.linalg.solve(A2, b2)))
for i in range(20):
    jax.block_until_ready(f(A1 + i * 1e-9, A2, b1, b2))
"""


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--gearjax", action="store_true")
    parser.add_argument("--tries", type=int, default=5)
    parser.add_argument("--timeout", type=float, default=60.0)
    args = parser.parse_args()
    env = {k: v for k, v in os.environ.items() if k not in ("PJRT_NPROC", "NPROC")}
    env["XLA_FLAGS"] = "--xla_cpu_enable_concurrency_optimized_scheduler=true"
    hung = 0
    for _ in range(args.tries):
        try:
            subprocess.run([sys.executable, "-c", PROGRAM, "1" if args.gearjax else "0"], env=env,
                           check=True, timeout=args.timeout)
        except subprocess.TimeoutExpired:
            hung += 1
    print(f"{'with' if args.gearjax else 'without'} gearjax's PJRT_NPROC=1: {hung}/{args.tries} hung")


if __name__ == "__main__":
    main()
