"""The XLA CPU deadlock of jaxlib 0.10's batched LAPACK kernels, reproduced in a few seconds.

    python tools/diagnostics/lapack_deadlock.py [--gearjax] [--tries 5] [--timeout 60]

Runs the program of `tests/test_runtime.py` (two independent batched LU solves, 4000 x
10x10 each, above jaxlib's 2e5-flop threshold for splitting a batch over XLA's intra-op
pool, 20 times) in a fresh process, `--tries` times, each under `--timeout` seconds, with the concurrency-optimised
scheduler on and, with `--gearjax`, gearjax imported first (its `PJRT_NPROC=1`). Prints how
many tries hung. On 2 cores with jaxlib 0.10.2: 5/5 hung without gearjax's setting,
0/5 with it; with `--xla_cpu_enable_concurrency_optimized_scheduler=false` alone (the old
workaround) this program returns, the test suite's derivative programs still hung.
"""

import argparse
import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from test_runtime import DEADLOCK  # noqa: E402  (the program the test runs)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--gearjax", action="store_true")
    parser.add_argument("--tries", type=int, default=5)
    parser.add_argument("--timeout", type=float, default=60.0)
    args = parser.parse_args()
    env = {k: v for k, v in os.environ.items() if k not in ("PJRT_NPROC", "NPROC")}
    env["XLA_FLAGS"] = "--xla_cpu_enable_concurrency_optimized_scheduler=true"
    program = DEADLOCK if args.gearjax else DEADLOCK.replace("import gearjax, ", "import ")
    if not args.gearjax and program == DEADLOCK:  # the test's program changed: it would import gearjax
        sys.exit("lapack_deadlock.py: tests/test_runtime.py's DEADLOCK no longer starts with "
                 "'import gearjax, ': update how this script leaves gearjax out")
    hung = 0
    for _ in range(args.tries):
        try:
            subprocess.run([sys.executable, "-c", program], env=env, check=True, timeout=args.timeout,
                           stdout=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            hung += 1
    print(f"{'with' if args.gearjax else 'without'} gearjax's PJRT_NPROC=1: {hung}/{args.tries} hung")


if __name__ == "__main__":
    main()
