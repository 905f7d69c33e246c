"""The 17/170 random designs of `tests/test_hard_cases_ratios.py` whose TCA leaves a
failed candidate on a slice that matters, and those candidates (run from the repository root)."""
import sys
sys.path.insert(0, "tests")
import jax, jax.numpy as jnp, numpy as np
jax.config.update("jax_enable_x64", True)
import optimistix as optx
import gearjax as gj
from _cases import random_involute, scene, missed_contacts, forward
from gearjax.tca._slice import make_problem, solve_candidates, solve_again, relevance, edge_is_first
from gearjax.tca.grid import face_slices, positions
from gearjax.tca.analysis import fallback_steps
from gearjax.tca._newton import SafeguardedNewton
import test_hard_cases_ratios as R

teeth, seed = R.GROUPS["ratio_1_10"]
rng = np.random.default_rng(seed)
designs = [random_involute(rng, teeth, R.WINDOW) for _ in range(R.RANDOM)]
scenes = [scene(p, y, pairs=R.WINDOW, effects=("ltca",), **kw) for p, y, kw in designs]
res = forward(scenes)
bad = [i for i in range(len(scenes)) if missed_contacts(res, i)]
print("designs with missed contacts", bad)
for i in bad:
    s = scenes[i]
    p = s.pair.resolve()
    acc = s.contact_model.accuracy
    z, _ = face_slices(p, acc)
    rtol, atol = acc.newton_tolerances(jnp.float64)
    phis = np.asarray(positions(p, acc, 1))
    un = np.asarray(res.tca.unconverged[i])
    print(f"design {i}: y {np.round(designs[i][1], 4).tolist()} unconverged {int(un.sum())} limits",
          [round(float(v), 3) for v in p.profile_limits(0)], [round(float(v), 3) for v in p.profile_limits(1)])
    for (a, b, c) in list(zip(*np.nonzero(un)))[:4]:
        prob = make_problem(p, s.depth, R.WINDOW[b], z[c], jnp.asarray(phis[a]))
        vals, conv, failed = solve_candidates(prob, optx.Newton(rtol=rtol, atol=atol), acc.newton_max_steps)
        print(f"  pos {a} pair {R.WINDOW[b]} slice {c}: relevant {np.asarray(relevance(prob))} conv {np.asarray(conv)} "
              f"failed {np.asarray(failed)} edge first {np.asarray(edge_is_first(prob, vals))}")
        print("    values", np.asarray(vals).round(5).tolist())
        for kind in np.flatnonzero(np.asarray(failed)):
            again = solve_again(prob, int(kind), SafeguardedNewton(rtol=rtol, atol=atol), fallback_steps(acc.newton_max_steps), True, vals, conv)
            print(f"    retry {kind}", np.asarray(again[0]).round(5).tolist(), bool(again[1]), bool(again[2]))
