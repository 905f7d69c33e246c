import sys
sys.path.insert(0, "tests")
import jax, jax.numpy as jnp, numpy as np
jax.config.update("jax_enable_x64", True)
import gearjax as gj
from _cases import random_involute, scene
from gearjax.tca.analysis import tooth_contact_analysis
import test_hard_cases as T
rng = np.random.default_rng(20261125)
designs = [random_involute(rng, (29, 71), T.WINDOW) for _ in range(400)]
@jax.jit
def run(s):
    t = tooth_contact_analysis(s.pair.resolve(), s.depth, accuracy=s.contact_model.accuracy, pairs=T.WINDOW)
    return jnp.sum(t.unconverged), jnp.sum(t.valid)
for i in [int(a) for a in sys.argv[1:]]:
    pair, y, kw = designs[i]
    print(i, [int(v) for v in run(scene(pair, y, pairs=T.WINDOW, **kw))])
