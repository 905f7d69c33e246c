"""The contact problem on which the Palmgren Newton iteration cycled: seed 001's
pair, paper optimum, 1000 N·m, 81 face slices, position 8 of 32 per pitch. Run from the
repository root: prints whether the solver converges with and without the damped steps
(`gearjax.ltca.solver._fraction_to_boundary`) on the whole problem and on the tooth pairs
that carry load, and writes the whole problem to `tests/data/palmgren_cycle.npz` (the
fixture of `tests/test_ltca.py::test_palmgren_newton_does_not_cycle`). The loaded pairs
alone do not cycle: the unloaded points change the active-set iteration's scale (the mean
point stiffness) and so its path."""
import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)
import gearjax as gj  # noqa: E402
from gearjax.ltca import analysis as A  # noqa: E402
from gearjax.ltca import solver as S  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402

POSITION = 8


def solve(problem, damped):
    saved = S._fraction_to_boundary
    if not damped:
        S._fraction_to_boundary = lambda loads, new_loads: jnp.asarray(1.0, loads.dtype)
    try:
        return S.solve_contact(problem, rtol=1e-10, atol=1e-10, max_steps=80)
    finally:
        S._fraction_to_boundary = saved


def main():
    acc = gj.Accuracy.preset("default").replace(face_slices=81)
    scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0), effects=("ltca",),
                     accuracy=acc)
    result = gj.simulate(scene, throw=False)
    tca, model, pair = result.tca, scene.contact_model, scene.pair.resolve()
    n = acc.face_slices
    valid, weights = A._loaded_slices(pair, tca, model, None)
    points = model.compliance(pair, model.material, model.hub_radius, tca, n, acc.quadrature_points, weights)
    separation = jnp.where(valid, tca.separation[..., :n], S.NO_CONTACT)
    p, q = A._levers(tca, n, pair.center(1))
    i = POSITION
    full = S.ContactProblem(points.blocks[i], points.nonlinear[i], separation[i], p[i], q[i], jnp.asarray(1.0e6),
                            points.exponent, points.diagonal)
    loaded = np.flatnonzero(np.asarray(jnp.any(solve(full, True).loads > 0, axis=-1)))
    part = jax.tree_util.tree_map(lambda x: x[loaded] if getattr(x, "ndim", 0) >= 2 else x, full)
    for name, problem in (("all pairs", full), (f"pairs {loaded.tolist()}", part)):
        for damped in (False, True):
            s = solve(problem, damped)
            print(f"{name}: damped {damped}: converged {bool(s.converged)} after {int(s.steps)} steps")
    np.savez_compressed("tests/data/palmgren_cycle.npz", **{k: np.asarray(getattr(full, k)) for k in
                        ("compliance", "nonlinear", "separation", "pinion_arm", "gear_arm", "torque")},
                        exponent=points.exponent)


if __name__ == "__main__":
    main()
