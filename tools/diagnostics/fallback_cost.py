"""What the TCA fallback's step cap costs (`tca.analysis.fallback_steps`): the batched
forward program of `tests/_cases.py` (TCA + LTCA at `fast`, `vmap` over 20 designs) on
two batches of random 17/170 designs, the one with design 143 (whose retried solves need
up to 71 steps) and the first one, with the cap given on the command line (e.g. 32, 4 x
`newton_max_steps`, against 128, the default). Under `vmap` the fallback runs for every batch, and
its loop runs until the slowest retried solve of the batch stops. Prints compile and median run
times and the failed solves where the contact matters. Run from the repository root."""
import sys
import time

sys.path.insert(0, "tests")
import equinox as eqx  # noqa: E402
import jax  # noqa: E402
import numpy as np  # noqa: E402

jax.config.update("jax_enable_x64", True)
import test_hard_cases_ratios as R  # noqa: E402
from _cases import missed_contacts, random_involute, scene  # noqa: E402

import gearjax as gj  # noqa: E402
import gearjax.tca.analysis as analysis  # noqa: E402

teeth, seed = R.GROUPS["ratio_1_10"]
rng = np.random.default_rng(seed)
designs = [random_involute(rng, teeth, R.WINDOW) for _ in range(160)]
batches = {"designs 0-19": range(0, 20), "designs 140-159 (143)": range(140, 160)}
# One cap per process: `simulate`'s programs are cached by their static arguments, so a
# second cap in this process would reuse the first one's trace.
cap = int(sys.argv[1]) if len(sys.argv) > 1 else 128
analysis.FALLBACK_MIN_STEPS = cap
analysis.FALLBACK_STEPS = 0  # the cap alone: 32 is what `fast` had (4 x 8)
run = eqx.filter_jit(jax.vmap(lambda s: gj.simulate(s, throw=False)))
for name, index in batches.items():
    stacked = gj.stack_scenes([scene(*designs[i][:2], pairs=R.WINDOW, effects=("ltca",), **designs[i][2]) for i in index])
    t0 = time.perf_counter()
    result = jax.block_until_ready(run(stacked))
    first = time.perf_counter() - t0
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        jax.block_until_ready(run(stacked))
        times.append(time.perf_counter() - t0)
    missed = [i for k, i in enumerate(index) if missed_contacts(result, k)]
    print(f"cap {cap:3d}, {name}: first call {first:.1f} s, run median {np.median(times):.3f} s "
          f"(min {min(times):.3f}), designs with a missed contact {missed}", flush=True)
