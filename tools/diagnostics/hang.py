import sys, time, faulthandler
faulthandler.dump_traceback_later(600, exit=True)
sys.path.insert(0, "tests")
import numpy as np
import gearjax as gj
import jax
jax.config.update("jax_enable_x64", True)
from _cases import random_involute, scene, derivatives, helical, PAPER_UM
import test_hard_cases_ratios as R
rng = np.random.default_rng(1)
teeth = (40, 40)
designs = [(helical(teeth=teeth), PAPER_UM / 1000.0, {})] + [random_involute(rng, teeth, R.WINDOW) for _ in range(int(sys.argv[1]))]
t = time.time()
for rep in range(int(sys.argv[2])):
    out = derivatives([scene(p, y, pairs=R.WINDOW, effects=("ltca",), **kw) for p, y, kw in designs])
    jax.block_until_ready(out)
    print("rep", rep, round(time.time() - t, 1), flush=True); t = time.time()
