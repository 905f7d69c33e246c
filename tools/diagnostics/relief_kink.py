"""Random 17/170 design 143 of `tests/test_hard_cases_ratios.py` (m_n 1 mm, root relief
14.9 µm over 0.145 mm of roll length starting 0.44 mm from the pinion's base circle): the
flank contacts that the TCA's Newton solve and its damped fallback missed at `fast`.

Prints, for the four slices that failed, the offset along the curve of coincident points
(the flank contact is its interior maximum, at the end of the pinion's root relief, where
the flank's curvature jumps) and the steps `SafeguardedNewton` needs from the starts the
TCA uses (the cap was 4 x 8 = 32 at `fast`; `tca.analysis.fallback_steps`). Run from the
repository root."""
import sys

sys.path.insert(0, "tests")
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import optimistix as optx  # noqa: E402

jax.config.update("jax_enable_x64", True)
import test_hard_cases_ratios as R  # noqa: E402
from _cases import random_involute, scene  # noqa: E402

from gearjax.tca._newton import SafeguardedNewton  # noqa: E402
from gearjax.tca._slice import _contact_residual, make_problem  # noqa: E402
from gearjax.tca.analysis import fallback_steps  # noqa: E402
from gearjax.tca.grid import face_slices, positions  # noqa: E402

teeth, seed = R.GROUPS["ratio_1_10"]
rng = np.random.default_rng(seed)
designs = [random_involute(rng, teeth, R.WINDOW) for _ in range(144)]
pair0, y, kw = designs[143]
s = scene(pair0, y, pairs=R.WINDOW, effects=("ltca",), **kw)
p = s.pair.resolve()
acc = s.contact_model.accuracy
z, _ = face_slices(p, acc)
phis = np.asarray(positions(p, acc, 1))
rtol, atol = acc.newton_tolerances(jnp.float64)
start1, _ = p.relief_coordinates(0)
print(f"y (mm) {np.round(y, 4).tolist()}; pinion active flank from u1 = {float(p.profile_limits(0)[0]):.4f}, "
      f"root relief {float(start1):.4f}..{float(start1) + y[2]:.4f} mm; gear tip u2 = {float(p.profile_limits(1)[1]):.4f} mm")
print(f"fallback step cap at `fast`: {fallback_steps(acc.newton_max_steps)} (was {4 * acc.newton_max_steps})")
# (position, pair column, slice, start of the retry: the gear-tip edge contact or the conjugate point)
CASES = [(9, 3, 6, [0.4268, 33.51152, -0.00018]), (8, 3, 7, [0.41558, 33.51152, -0.00024]),
         (8, 3, 7, [0.76830, 33.51152, 5e-05]), (10, 3, 4, [0.45619, 33.51152, -0.00015])]
for a, b, c, start in CASES:
    prob = make_problem(p, s.depth, R.WINDOW[b], z[c], jnp.asarray(phis[a]))

    def solve(y0, prob=prob):
        args = (prob, jnp.eye(3)[0], y0, jnp.array(True))
        return optx.root_find(_contact_residual, SafeguardedNewton(rtol=rtol, atol=atol), y0, args=args,
                              max_steps=400, throw=False)

    sol = jax.jit(solve)(jnp.array(start))
    print(f"position {a}, pair {R.WINDOW[b]}, slice {c}, from {start}: {int(sol.stats['num_steps'])} steps, "
          f"converged {bool(sol.result == optx.RESULTS.successful)}, (u1, u2, offset) = {np.asarray(sol.value).round(7).tolist()}")

# The curve of coincident points of the first case: offset against u2 (its maximum is the flank contact).
a, b, c, start = CASES[0]
prob = make_problem(p, s.depth, R.WINDOW[b], z[c], jnp.asarray(phis[a]))


@jax.jit
def coincident(u2, y0):
    F = lambda y: prob.pinion_point(y[0]) - prob.gear_point(u2, y[1])  # noqa: E731
    for _ in range(30):
        y0 = y0 - jnp.linalg.solve(jax.jacfwd(F)(y0), F(y0))
    return y0


yy = jnp.array([start[0], start[2]])
print("curve of coincident points (u2, u1, offset):")
for u2 in np.linspace(float(p.profile_limits(1)[1]), 33.40, 15):
    yy = coincident(jnp.asarray(u2), yy)
    print(f"  {u2:.5f} {float(yy[0]):.5f} {float(yy[1]):.4e}")
