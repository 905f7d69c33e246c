"""Slice 10 candidates of design 18 at both sides of the H jump."""
import sys
sys.path.insert(0, "tests")
import jax, jax.numpy as jnp, numpy as np
jax.config.update("jax_enable_x64", True)
import optimistix as optx
import gearjax as gj
from _cases import random_involute, scene
from gearjax.tca._slice import make_problem, solve_candidates, relevance, _starts
from gearjax.tca.grid import face_slices
import test_hard_cases as T
rng = np.random.default_rng(20261125)
designs = [random_involute(rng, (29, 71), T.WINDOW) for _ in range(19)]
pair, y, kw = designs[-1]
s = scene(pair, y, pairs=T.WINDOW, **kw)
p = s.pair.resolve()
acc = s.contact_model.accuracy
z, _ = face_slices(p, acc)
rtol, atol = acc.newton_tolerances(jnp.float64)
column = 3
k = T.WINDOW[column]
phi0 = 0.020972331353666
print("g limits", [float(v) for v in p.profile_limits(0)], [float(v) for v in p.profile_limits(1)])
for dphi in (-1e-6, -1e-9, 0.0, 1e-9, 1e-6, 1e-4):
    phi = jnp.asarray(phi0 + dphi)
    prob = make_problem(p, s.depth, k, z[10], phi)
    g = p.contact_guess(prob.pinion_rotation)
    rel = relevance(prob)
    vals, conv, failed = solve_candidates(prob, optx.Newton(rtol=rtol, atol=atol), acc.newton_max_steps)
    print(f"dphi {dphi:+.0e} guess {float(g[0]):.4f} {float(g[1]):.4f} relevant {np.asarray(rel)} conv {np.asarray(conv)} failed {np.asarray(failed)}")
    print("    values", np.asarray(vals).round(6).tolist())

print("delta(u2) scan, phi0")
prob = make_problem(p, s.depth, k, z[10], jnp.asarray(phi0))
def delta(u2, start):
    def res(y, _):
        return prob.pinion_point(y[0]) - prob.gear_point(u2, y[1])
    sol = optx.root_find(res, optx.Newton(rtol=1e-12, atol=1e-12), start, max_steps=100, throw=False)
    return sol.value, sol.result == optx.RESULTS.successful
st = jnp.asarray([37.0, -9e-5])
for u2 in np.linspace(112.5, 114.8, 24):
    v, ok = delta(jnp.asarray(u2), st)
    print(f"u2 {u2:.3f} u1 {float(v[0]):.4f} delta {float(v[1]):.4e} ok {bool(ok)}")
    if ok: st = v
