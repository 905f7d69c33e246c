"""How the impact force of seed 001's pair (paper optimum, 5000 rpm) depends on the face
slices and on the force range of the local stiffness fit (run from the repository root,
about 5 min). The contact solver gets `reference`'s 80 steps: at 81 slices
and 1000 N·m the default 40 do not settle the LTCA's active set.

For each slice count the incoming pair's force-approach curve delta(F) is computed once at
41 forces over (0.002, 2) x the static normal load, and the power law F = K_s delta^n is
then fitted in numpy over sub-ranges of it, as `local_stiffness` does. The last column
integrates the energy under the computed curve itself (no power law): the force at which
the work done equals the kinetic energy.

    python tools/diagnostics/impact_fit.py [--slices 9,21,41,81,161]
"""
import argparse

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)
import gearjax as gj  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402

RANGES = ((0.02, 1.0), (0.05, 1.0), (0.1, 1.0), (0.2, 1.0))


def power_law_force(forces, approaches, energy):
    n, log_k = np.polyfit(np.log(approaches), np.log(forces), 1)
    k = np.exp(log_k)
    return k * ((n + 1) * energy / k) ** (n / (n + 1))


def work_force(forces, approaches, energy):
    f, d = np.r_[0.0, forces], np.r_[0.0, approaches]
    work = np.r_[0.0, np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(d))]
    return np.interp(energy, work, f)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slices", default="9,21,41,81,161")
    args = parser.parse_args()
    print("slices  torque  v_n (mm/s)  " + "  ".join(f"F_s fit {lo:g}-{hi:g}" for lo, hi in RANGES) + "  F_s work")
    for n in map(int, args.slices.split(",")):
        acc = gj.Accuracy.preset("default").replace(face_slices=n, impact_fit_points=41, impact_fit_range=(0.002, 2.0),
                                                   contact_max_steps=80)
        for torque in (400.0, 1000.0, 1600.0):
            scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=torque, speed_rpm=5000.0),
                             effects=("impact",), accuracy=acc)
            impact = gj.simulate(scene).impact
            forces = np.asarray(impact.stiffness.forces)
            approaches = np.asarray(impact.stiffness.approaches)
            reference = forces[-1] / 2.0
            energy = float(impact.kinetic_energy)
            fits = []
            for lo, hi in RANGES:
                keep = (forces >= lo * reference * (1 - 1e-9)) & (forces <= hi * reference * (1 + 1e-9))
                fits.append(power_law_force(forces[keep], approaches[keep], energy))
            print(f"{n:6d}  {torque:6.0f}  {float(impact.velocity):10.2f}  " + "  ".join(f"{f:15.0f}" for f in fits)
                  + f"  {work_force(forces, approaches, energy):8.0f}", flush=True)


if __name__ == "__main__":
    main()
