"""Double-circular-arc hard cases of `tests/test_hard_cases_double_arc.py` (name, e.g.
dca_delta_alpha_max): the TCA candidates that fail on binding slices, and their retry."""
import sys
sys.path.insert(0, "tests")
import jax, jax.numpy as jnp, numpy as np
jax.config.update("jax_enable_x64", True)
import optimistix as optx
import gearjax as gj
from _cases import missed_contacts
from gearjax.tca._slice import make_problem, solve_candidates, solve_again, relevance, edge_is_first, _missed_flank, _starts, _on_active_flanks
from gearjax.tca.grid import face_slices, positions
import test_hard_cases_double_arc as T
cases = T._cases()
p0 = cases[sys.argv[1]]
s = gj.Scene(p0, pairs=T.WINDOW, accuracy="fast")
sim = gj.simulate(s, throw=False)
print("missed", missed_contacts(sim))
zones = s.pair.contact_zones()
p = zones[0].resolve()
acc = s.contact_model.accuracy
z, _ = face_slices(p, acc)
rtol, atol = acc.newton_tolerances(jnp.float64)
#print("limits", [float(v) for v in p.profile_limits(0)], [float(v) for v in p.profile_limits(1)], "dom", [float(v) for v in p.parameter_domain(0)])
un = np.asarray(sim.tca.unconverged)
te, ste, val = (np.asarray(x) for x in (sim.tca.transmission_error, sim.tca.slice_te, sim.tca.valid))
matters = val & (np.abs(ste - te[:, None, None]) <= 1e-9 * (1 + np.abs(te).max()))
un = un * matters
phis = np.asarray(positions(p, acc, 1))
print("unconverged entries", np.argwhere(un > 0).tolist()[:20])
for (a, b, c) in list(zip(*np.nonzero(un)))[:4]:
    zone, kk = divmod(int(b), len(T.WINDOW)); p = zones[zone].resolve()
    print("zone", zone, "limits", [float(v) for v in p.profile_limits(0)], [float(v) for v in p.profile_limits(1)], "dom", [float(v) for v in p.parameter_domain(0)], [float(v) for v in p.parameter_domain(1)])
    prob = make_problem(p, s.depth, T.WINDOW[kk], z[c], jnp.asarray(phis[a]))
    vals, conv, failed = solve_candidates(prob, optx.Newton(rtol=rtol, atol=atol), acc.newton_max_steps)
    print(f"pos {a} pair {b} slice {c} z {float(z[c]):.2f} guess {[float(g) for g in p.contact_guess(prob.pinion_rotation)]}")
    print("   starts", np.asarray(_starts(prob)).round(5).tolist())
    print("   relevant", np.asarray(relevance(prob)), "conv", np.asarray(conv), "onflank", np.asarray(_on_active_flanks(p, vals)), "failed", np.asarray(failed), "edge first", np.asarray(edge_is_first(prob, vals)))
    print("   values", np.asarray(vals).round(6).tolist())
    from gearjax.tca._newton import SafeguardedNewton
    v2 = solve_again(prob, 0, SafeguardedNewton(rtol=rtol, atol=atol), acc.newton_max_steps, True, vals, conv)
    print("   retry", np.asarray(v2[0]).round(6).tolist(), bool(v2[1]), bool(v2[2]))
