"""Forward-mode derivatives of the double-circular-arc mesh-in impact force against central
differences, in the pinion torque and the axial pitch error.

    python benchmarks/studies/dca_force_gradient.py [--torque-Nm 100] [--axial-pitch-error-um 50]
                                       [--accuracy default] [--rtol 0.02]

The seed pair (m_n 4, z 24/24, b 55 mm, β 15°) at 200 rpm with `effects = ["impact"]`:
`jax.jacfwd` of each zone's F_s with respect to (T_1, Δ_α) through the first-contact
search's implicit-function JVP (`gearjax.impact.search.first_contact`), against central
differences of the same program's primal (steps 0.1 % of the torque and 0.1 µm). Prints
both, their relative difference per zone and input (to the larger magnitude), and the
derivative program's trace and compile time; exits 1 where a difference of the force
exceeds `--rtol`. The same comparison is printed for what the force is made of (the first
contact's angle and axial position, the normal velocity, the equivalent mass, the local
stiffness law), to show where a difference enters. Not part of the test suite: the
derivative program takes about 11 min and 13 GB of memory to trace and compile on the
project's 2-core CPU, beyond the suite's budget.
"""

from __future__ import annotations

import argparse
import sys
import time

import equinox as eqx
import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import gearjax as gj  # noqa: E402
from dca_impact import seed_scene  # noqa: E402  (benchmarks/studies/, the script's folder)


#: what each zone's row holds: the force (checked) and the quantities it is made of (printed)
QUANTITIES = ("force F_s (N)", "pinion angle (rad)", "velocity (mm/s)", "mass (t)", "stiffness K_s",
              "exponent n", "axial position (mm)")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--torque-Nm", type=float, default=100.0)
    parser.add_argument("--axial-pitch-error-um", type=float, default=50.0)
    parser.add_argument("--accuracy", default="default")
    parser.add_argument("--rtol", type=float, default=0.02)
    args = parser.parse_args(argv)
    base = seed_scene(args.accuracy, args.torque_Nm, 200.0)

    def impact(x):  # x = (T_1 in N·mm, Δ_α in mm): per zone, the force and what it is made of
        scene = eqx.tree_at(lambda s: (s.operating.torque, s.pair.axial_pitch_error), base, (x[0], x[1]))
        imp = gj.simulate(scene, throw=False).impact
        return jnp.stack([imp.force, imp.pinion_angle, imp.velocity, imp.mass, imp.stiffness.coefficient,
                          imp.stiffness.exponent, imp.slice_z], axis=-1)

    x = jnp.array([args.torque_Nm * 1e3, args.axial_pitch_error_um * 1e-3])
    start = time.perf_counter()
    jacobian = eqx.filter_jit(jax.jacfwd(impact))
    jac = np.asarray(jax.block_until_ready(jacobian(x)))  # (zone, quantity, input)
    compile_s = time.perf_counter() - start
    primal = eqx.filter_jit(impact)
    steps = np.array([1e-3 * float(x[0]), 1e-4])
    central = np.stack([(np.asarray(primal(x.at[i].add(h))) - np.asarray(primal(x.at[i].add(-h)))) / (2 * h)
                        for i, h in enumerate(steps)], axis=-1)
    value = np.asarray(primal(x))
    print(f"T_1 {args.torque_Nm} N·m, Δ_α {args.axial_pitch_error_um} µm, {args.accuracy}: F_s {np.round(value[:, 0], 3)} N; "
          f"derivative program {compile_s:.0f} s (trace, compile and one run)")
    worst = 0.0
    for z in range(jac.shape[0]):
        for q, quantity in enumerate(QUANTITIES):
            for i, name in enumerate(("T1 (per N·mm)", "Δα (per mm)")):
                scale = max(abs(jac[z, q, i]), abs(central[z, q, i]))
                diff = abs(jac[z, q, i] - central[z, q, i]) / scale if scale > 0 else 0.0
                worst = max(worst, diff) if q == 0 else worst
                print(f"zone {z} d {quantity:24s} / d{name:14s} jacfwd {jac[z, q, i]:+.6e}  "
                      f"central {central[z, q, i]:+.6e}  difference {diff:.2e}")
    return 0 if worst <= args.rtol else 1


if __name__ == "__main__":
    sys.exit(main())
