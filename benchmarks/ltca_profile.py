"""Where the LTCA spends its time: TCA, compliance, contact solve.

    python benchmarks/ltca_profile.py [--compliance slice|iso] [--slices 41] [--positions 32]
                                      [--loads 1] [--hertz linear] [--repeats 9] [--name NAME]

The default scene (seed 001 pair, paper optimum, plane-of-action TCA) with
`SliceCompliance(hertz=...)` or `IsoCompliance()`, at `--loads` torques from 100 to
2 000 N·m (1 000 N·m for one): each stage jitted on its own, run on the previous stage's
output, timed after a warm-up (median of `--repeats`), beside the whole `load_sweep`; the
slice model's compliance also in its two parts (the tooth integrals of every point, the
coupled blocks built from them).
It also reports the active-set steps of every position (under `vmap` the loop runs to the
largest; several loads on the CPU are solved in sequence, each warm-started from the load
below, as `load_sweep` solves them) and the points loaded per tooth pair: the solve's cost
is steps × one Cholesky factorisation per tooth-pair block (slices × slices) per position.
Writes `benchmarks/results/NAME.json` (default `ltca_profile`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import gearjax as gj  # before the first computation: its process settings
import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import first_and_runs, machine, write  # noqa: E402

from gearjax.ltca import analysis as ltca_analysis  # noqa: E402
from gearjax.ltca.compliance import pasternak_compliance  # noqa: E402
from gearjax.ltca.solver import NO_CONTACT, ContactProblem, sequential_loads, solve_over_loads, solve_with  # noqa: E402
from gearjax.io.scene_file import default_scene  # noqa: E402


def median_time(fn, *args, repeats):
    """(median run seconds after a warm-up, output) of a jitted stage."""
    _, median, _, out = first_and_runs(fn, *args, repeats=repeats)
    return median, out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slices", type=int, default=41)
    parser.add_argument("--positions", type=int, default=32)
    parser.add_argument("--hertz", default="linear", choices=["linear", "palmgren"])
    parser.add_argument("--compliance", default="slice", choices=["slice", "iso"])
    parser.add_argument("--loads", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--name", default="ltca_profile")
    args = parser.parse_args(argv)
    compliance = gj.SliceCompliance(hertz=args.hertz) if args.compliance == "slice" else gj.IsoCompliance()
    torques = jnp.asarray([1.0e6]) if args.loads == 1 else jnp.linspace(1.0e5, 2.0e6, args.loads)

    scene0, _ = default_scene()
    accuracy = gj.Accuracy(positions_per_pitch=args.positions, face_slices=args.slices, tca_method="plane_of_action")
    scene = gj.Scene(scene0.pair, scene0.modification, accuracy=accuracy,
                     compliance=compliance, operating=gj.OperatingPoint(torque=1.0e6))
    model = scene.contact_model
    n_mid = args.slices

    @jax.jit
    def tca_stage(s):
        return gj.tooth_contact_analysis(s.pair, s.depth, accuracy=s.accuracy, pairs=s.pairs)

    @jax.jit
    def compliance_stage(s, tca):
        pair = s.pair.resolve()
        valid, weights = ltca_analysis._loaded_slices(pair, tca, model, None)
        points = model.compliance(pair, model.material, model.hub_radius, tca, n_mid, model.accuracy.quadrature_points,
                                  weights)
        separation = jnp.where(valid, tca.separation[..., :n_mid], NO_CONTACT)
        p, q = ltca_analysis._levers(tca, n_mid, pair.center(1))
        return points.blocks, points.nonlinear, separation, p, q

    @jax.jit
    def integrals_stage(s, tca):
        """The slice model's tooth compliances of every point (both teeth), summed."""
        pair = s.pair.resolve()
        c = model.compliance
        return tuple(sum(c.tooth_compliances(pair, model.material, model.hub_radius, gear, u[..., :n_mid],
                                             model.accuracy.quadrature_points))
                     for gear, u in ((0, tca.pinion_parameter), (1, tca.gear_parameter)))

    @jax.jit
    def blocks_stage(s, tca, c1, c2):
        """The slice model's coupled blocks from the per-point compliances."""
        pair = s.pair.resolve()
        dz = jnp.mean(tca.slice_width[..., :n_mid])
        lam = model.compliance.coupling_length * pair.normal_module
        frac = tca.transverse_normal_fraction[..., :n_mid]

        def block(c1k, c2k, fk):
            transverse = pasternak_compliance(c1k, dz, lam) + pasternak_compliance(c2k, dz, lam)
            return fk[:, None] * transverse * fk[None, :]

        return jax.vmap(jax.vmap(block))(c1, c2, frac)

    exponent = 1.0 if args.hertz == "linear" or args.compliance == "iso" else 0.9
    diagonal = args.compliance == "iso"

    # several loads as the library solves them: on the CPU in sequence, warm-started
    sequential = args.loads > 1 and sequential_loads(diagonal, exponent)

    @jax.jit
    def solve_stage(blocks, nonlinear, separation, p, q, torques):
        if sequential:
            problems = jax.vmap(lambda t, *d: ContactProblem(*d, t, exponent, diagonal), in_axes=(None, 0, 0, 0, 0, 0))
            return solve_over_loads(lambda t: problems(t, blocks, nonlinear, separation, p, q), torques, accuracy,
                                    False)[0]

        def at(torque):
            def one(b, a, e, pa, qa):
                return solve_with(ContactProblem(b, a, e, pa, qa, torque, exponent, diagonal), accuracy)

            return jax.vmap(one)(blocks, nonlinear, separation, p, q)

        return jax.vmap(at)(torques)

    @jax.jit
    def whole(s, torques):
        ltca = gj.load_sweep(s, torques).ltca
        return ltca.transmission_error, ltca.loads

    t_tca, tca = median_time(tca_stage, scene, repeats=args.repeats)
    t_compliance, data = median_time(compliance_stage, scene, tca, repeats=args.repeats)
    split = {}
    if args.compliance == "slice":
        split["compliance_integrals_s"], per_point = median_time(integrals_stage, scene, tca, repeats=args.repeats)
        split["compliance_blocks_s"], _ = median_time(blocks_stage, scene, tca, *per_point, repeats=args.repeats)
    t_solve, solution = median_time(solve_stage, *data, torques, repeats=args.repeats)
    t_whole, _ = median_time(whole, scene, torques, repeats=args.repeats)
    steps = np.asarray(solution.steps)
    loaded = np.asarray(solution.loads[0] > 0).sum(-1)  # first load: (pos, pair)
    out = {
        "machine": machine(),
        "sizes": {"compliance": args.compliance, "positions": args.positions, "slices": args.slices,
                  "pairs": len(scene.pairs), "loads": args.loads, "hertz": args.hertz},
        "tca_s": t_tca, "compliance_s": t_compliance, **split, "solve_s": t_solve, "load_sweep_s": t_whole,
        "steps": steps.tolist(), "steps_max": int(steps.max()), "steps_mean": float(steps.mean()),
        "loaded_pairs_per_position": [int(v) for v in (loaded > 0).sum(-1)],
        "loaded_points_per_position": [int(v) for v in loaded.sum(-1)],
        "sequential_loads": sequential,
        # a batch runs to its largest step count: all loads together, or each load in sequence
        "factorisations_per_solve": int(steps.max(axis=-1).sum() if sequential else steps.max() * args.loads)
        * args.positions * len(scene.pairs),
    }
    for key in ("tca_s", "compliance_s", *split, "solve_s", "load_sweep_s"):
        print(f"{key}: {out[key] * 1e3:.2f} ms")
    if out["steps_max"] == 0:  # the diagonal model's exact solver: no active-set steps
        print("exact diagonal solver: one sort per position, no factorisation")
        print("wrote", write(args.name, out))
        return
    out["seconds_per_factorisation_upper_bound"] = t_solve / out["factorisations_per_solve"]
    print(f"active-set steps per position: mean {out['steps_mean']:.2f}, max {out['steps_max']} (the batch runs the max); "
          f"{out['factorisations_per_solve']} block factorisations of {args.slices} x {args.slices}, "
          f"{out['seconds_per_factorisation_upper_bound'] * 1e6:.1f} us each at most; loaded pairs per position "
          f"{min(out['loaded_pairs_per_position'])}-{max(out['loaded_pairs_per_position'])} of {len(scene.pairs)}")
    print("wrote", write(args.name, out))


if __name__ == "__main__":
    main()
