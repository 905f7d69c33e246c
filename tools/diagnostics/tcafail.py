"""Which TCA candidates still fail on random 29/71 design N (random index)."""
import sys
sys.path.insert(0, "tests")
import jax, jax.numpy as jnp, numpy as np
jax.config.update("jax_enable_x64", True)
import optimistix as optx
import gearjax as gj
from _cases import random_involute, scene, missed_contacts
from gearjax.tca._slice import make_problem, solve_candidates, solve_again, relevance, edge_is_first, _missed_flank
from gearjax.tca._newton import SafeguardedNewton
from gearjax.tca.grid import face_slices
import test_hard_cases as T
N = int(sys.argv[1])
rng = np.random.default_rng(20261125)
designs = [random_involute(rng, (29, 71), T.WINDOW) for _ in range(N + 1)]
pair, y, kw = designs[-1]
s = scene(pair, y, pairs=T.WINDOW, **kw)
print("y", y, kw)
sim = gj.simulate(s, throw=False)
print("impact", gj.enum_name(sim.impact.result), "missed", missed_contacts(sim))
p = s.pair.resolve()
acc = s.contact_model.accuracy
z, _ = face_slices(p, acc)
rtol, atol = acc.newton_tolerances(jnp.float64)
print("limits", [float(v) for v in p.profile_limits(0)], [float(v) for v in p.profile_limits(1)])
un = np.asarray(sim.tca.unconverged)
from gearjax.tca.grid import positions
phis = np.asarray(positions(p, acc, 1))
for (a, b, c) in list(zip(*np.nonzero(un)))[:6]:
    prob = make_problem(p, s.depth, T.WINDOW[b], z[c], jnp.asarray(phis[a]))
    vals, conv, failed = solve_candidates(prob, optx.Newton(rtol=rtol, atol=atol), acc.newton_max_steps)
    print(f"pos {a} pair {b} slice {c} z {float(z[c]):.2f} guess {[float(g) for g in p.contact_guess(prob.pinion_rotation)]}")
    print("   relevant", np.asarray(relevance(prob)), "conv", np.asarray(conv), "failed", np.asarray(failed), "edge first", np.asarray(edge_is_first(prob, vals)))
    print("   values", np.asarray(vals).round(6).tolist())
    v2 = solve_again(prob, 0, optx.Newton(rtol=rtol, atol=atol), acc.newton_max_steps, True, vals, conv)
    print("   retry", np.asarray(v2[0]).round(6).tolist(), bool(v2[1]), bool(v2[2]))
from gearjax.tca import analysis as A
import functools as ft
grid = lambda f: jax.vmap(jax.vmap(jax.vmap(f, (None, None, 0)), (None, 0, None)), (0, None, None))
def one(phi1, k, zz):
    return solve_candidates(make_problem(p, s.depth, k, zz, phi1), optx.Newton(rtol=rtol, atol=atol), acc.newton_max_steps)
cand = jax.jit(grid(one))(jnp.asarray(phis), jnp.asarray(T.WINDOW), z)
print("failed before retry", int(jnp.sum(cand[2])), "of", cand[2].size, "capacity", A.fallback_capacity(cand[2].size))
