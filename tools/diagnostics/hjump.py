"""Diagnose the impact search's H jump on random 29/71 design 18 (tests/test_hard_cases.py)."""
import sys
sys.path.insert(0, "tests")
import jax, jax.numpy as jnp, numpy as np
jax.config.update("jax_enable_x64", True)
import gearjax as gj
from _cases import random_involute, scene, missed_contacts
from gearjax.impact import search
import test_hard_cases as T

rng = np.random.default_rng(20261125)
cases = list(T._cases().values())
designs = [random_involute(rng, (29, 71), T.WINDOW) for _ in range(int(sys.argv[1]) + 1)]
pair, y, kw = designs[-1]
s = scene(pair, y, pairs=T.WINDOW, **kw)
print("pair", pair.teeth, float(pair.normal_module), float(pair.helix_angle_deg) if hasattr(pair,'helix_angle_deg') else '', "face", float(pair.face_width), "y", y, kw)
sim = gj.simulate(s, throw=False)
imp = sim.impact
print("impact", gj.enum_name(imp.result), "steps", int(imp.search_steps), "phi*", float(imp.pinion_angle), "kind", gj.enum_name(imp.kind))
p = s.pair.resolve()
ctx = search.SearchContext(p, s.depth, jnp.asarray(s.operating.torque), s.contact_model, s.pairs)
found, column, lower, upper, gl, gu = search.bracket(sim.tca, sim.ltca)
print("bracket", float(lower), float(upper), float(gl), float(gu), "column", int(column))
ev = jax.jit(lambda phi: search.evaluate(ctx, column, phi))
lo, hi = float(lower), float(upper)
def info(phi):
    (te, lte, tca), (j, ok) = ev(jnp.asarray(phi))
    return float(te - lte), int(j), tca
for _ in range(60):
    mid = 0.5 * (lo + hi)
    h, _, _ = info(mid)
    lo, hi = (mid, hi) if h < 0 else (lo, mid)
lim1 = [float(v) for v in p.profile_limits(0)]; lim2 = [float(v) for v in p.profile_limits(1)]
print("limits pinion", lim1, "gear", lim2, "face slices z", np.asarray(sim.tca.slice_z))
for phi in (lo, hi):
    h, j, tca = info(phi)
    c = int(column)
    print(f"phi {phi:.15f} H {h:.3e} binding slice {j}")
    v = np.asarray(tca.valid[0, c]); te = np.asarray(tca.slice_te[0, c]); kind = np.asarray(tca.kind._value[0, c]) if hasattr(tca.kind,'_value') else None
    u1 = np.asarray(tca.pinion_parameter[0, c]); u2 = np.asarray(tca.gear_parameter[0, c])
    for jj in range(len(v)):
        print(f"   slice {jj:2d} valid {v[jj]!s:5} te {te[jj]: .4e} kind {gj.enum_name(jax.tree_util.tree_map(lambda a: a[0, c, jj], tca.kind))} u1 {u1[jj]:.5f} u2 {u2[jj]:.5f}")
