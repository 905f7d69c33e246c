"""Seed 001 reproduction: mesh-in impact force against load (Table 4), the strike-point
trajectory on the flank (Table 3) and the speed exponent.

    python tools/reproduce_seed001.py [--accuracy reference] [--check-slices 161]

Writes docs/results/seed001_impact.json and docs/figures/impact_trajectory.png and prints
the table of `docs/impact.md`. Accuracy: a preset (default `reference`: 128 positions per
pitch, 81 face slices), float64. The Table 4 rows are evaluated again with
`--check-slices` face slices (0: no check; 4x the preset's contact steps) and the largest
difference of F_s and whether every regime agrees are recorded beside them. Every result
records whether its stages converged (`converged`); the script does not stop at one that
did not. The seed's case and numbers come from
`gearjax.papers.seed001`.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402

import _check_accuracy as check_accuracy  # noqa: E402  (tools/, the script's folder)

import gearjax as gj  # noqa: E402
from gearjax._solution import RESULTS  # noqa: E402
from gearjax.papers.seed001 import TABLE4_IMPACT_FORCE, paper_optimum, seed_pair  # noqa: E402
from gearjax.sweep import regime_transition  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def main(accuracy: str = "reference", check_slices: int = 161) -> dict:
    acc = gj.Accuracy.preset(accuracy)
    pair = seed_pair()
    paper = paper_optimum().as_vector()
    plain = paper.at[jnp.array([0, 1, 4])].set(0.0)

    def scene(y, torque_Nm, rpm=5000.0, accuracy=acc):
        return gj.Scene(pair, gj.FlankModification.from_vector(y), effects=("impact",), accuracy=accuracy,
                        operating=gj.OperatingPoint(torque_Nm=torque_Nm, speed_rpm=rpm), pairs=(-2, -1, 0, 1, 2))

    def run(y, torque_Nm, rpm=5000.0, accuracy=acc):
        imp = gj.simulate(scene(y, torque_Nm, rpm, accuracy), throw=False).impact
        return {
            "torque_Nm": torque_Nm,
            "speed_rpm": rpm,
            "force_N": float(imp.force),
            "velocity_mm_per_s": float(imp.velocity),
            "regime": imp.regime_name,
            "pinion_roll_length_mm": float(imp.pinion_parameter),
            "face_position_mm": float(imp.slice_z),
            "stiffness_coefficient": float(imp.stiffness.coefficient),
            "stiffness_exponent": float(imp.stiffness.exponent),
            "fit_error": float(imp.stiffness.fit_error),
            "equivalent_mass_kg": float(imp.mass) * 1e3,
            "loaded_te_um": float(imp.loaded_te) * float(pair.base_radius[1]) * 1e3,
            "converged": bool(imp.result == RESULTS.successful),
        }

    table = []
    for t, (p_std, p_mod) in TABLE4_IMPACT_FORCE.items():
        s, m = run(plain, t), run(paper, t)
        table.append({"torque_Nm": t, "paper_standard_N": p_std, "standard": s, "paper_modified_N": p_mod, "modified": m})
    loads = [100.0, 200.0, 400.0, 600.0, 800.0, 1000.0, 1200.0, 1400.0, 1600.0]
    trajectory = {"standard": [run(plain, t) for t in loads], "modified": [run(paper, t) for t in loads]}
    below, above = regime_transition(scene(paper, 400.0), 4.0e5, 1.6e6, tolerance=1e-3)
    slow, quick = run(paper, 1000.0, 2500.0), run(paper, 1000.0, 5000.0)
    n = quick["stiffness_exponent"]
    speed = {
        "force_ratio_5000_over_2500": quick["force_N"] / slow["force_N"],
        "predicted_2_pow_2n_over_n_plus_1": 2.0 ** (2 * n / (n + 1)),
        "exponent_2n_over_n_plus_1": 2 * n / (n + 1),
    }
    check = None
    if check_slices:
        finer = check_accuracy.finer(acc, check_slices)
        differences, regimes_equal = [], True
        for row in table:
            for name, y in (("standard", plain), ("modified", paper)):
                other = run(y, row["torque_Nm"], accuracy=finer)
                row[name]["force_N_at_check"] = other["force_N"]
                row[name]["converged_at_check"] = other["converged"]
                differences.append(abs(row[name]["force_N"] / other["force_N"] - 1.0))
                regimes_equal &= other["regime"] == row[name]["regime"]
        check = {"face_slices": check_slices, "largest_force_difference": max(differences), "regimes_equal": regimes_equal}
    out = {
        "accuracy": {"preset": accuracy, "positions_per_pitch": acc.positions_per_pitch, "face_slices": acc.face_slices},
        "check": check,
        "table4": table,
        "trajectory": trajectory,
        "transition_torque_Nm": [below / 1e3, above / 1e3],
        "speed": speed,
    }
    (ROOT / "docs" / "results").mkdir(parents=True, exist_ok=True)
    (ROOT / "docs" / "results" / "seed001_impact.json").write_text(json.dumps(out, indent=1))
    _figure(pair, loads, trajectory, out["transition_torque_Nm"])
    _print(out)
    return out


def _figure(pair, loads, trajectory, transition):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    for name, m in (("standard", "o-"), ("modified", "s-")):
        rows = trajectory[name]
        axes[0].plot(loads, [r["force_N"] for r in rows], m, label=name)
        axes[1].plot(loads, [r["pinion_roll_length_mm"] for r in rows], m, label=name)
        for t, r in zip(loads, rows):
            axes[1].annotate(r["regime"][0], (t, r["pinion_roll_length_mm"]), textcoords="offset points", xytext=(3, 3), fontsize=8)
    for t, (ps, pm) in TABLE4_IMPACT_FORCE.items():
        axes[0].plot([t], [ps], "kx")
        axes[0].plot([t], [pm], "k+")
    axes[0].plot([], [], "kx", label="seed 001 standard")
    axes[0].plot([], [], "k+", label="seed 001 modified")
    for ax in axes:
        ax.axvspan(*transition, color="orange", alpha=0.3)
        ax.set_xlabel("pinion torque (N m)")
        ax.grid(alpha=0.3)
        ax.legend()
    axes[0].set_ylabel("impact force F_s (N), 5000 rpm")
    axes[1].axhline(float(pair.start_of_active_profile[0]), color="gray", ls="--")
    axes[1].set_ylabel("pinion roll length of the strike point (mm)")
    axes[1].set_title("s: surface, e: edge; dashed: start of active profile")
    fig.tight_layout()
    fig.savefig(ROOT / "docs" / "figures" / "impact_trajectory.png", dpi=110)


def _print(out):
    print("| load (N·m) | standard: seed 001 | gearjax | diff | modified: seed 001 | gearjax | regime | diff |")
    print("|---|---|---|---|---|---|---|---|")
    for row in out["table4"]:
        s, m = row["standard"], row["modified"]
        ds = s["force_N"] / row["paper_standard_N"] - 1
        dm = m["force_N"] / row["paper_modified_N"] - 1
        print(f"| {row['torque_Nm']:.0f} | {row['paper_standard_N']:.0f} N | {s['force_N']:.0f} N ({s['regime']}) | {ds:+.0%} "
              f"| {row['paper_modified_N']:.0f} N | {m['force_N']:.0f} N | {m['regime']} | {dm:+.0%} |")
    print("transition torque (N·m):", out["transition_torque_Nm"])
    print("accuracy:", out["accuracy"], "check:", out["check"])
    print("speed:", out["speed"])
    for name in ("standard", "modified"):
        print(name, [(r["torque_Nm"], round(r["pinion_roll_length_mm"], 3), r["regime"], round(r["force_N"])) for r in out["trajectory"][name]])


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--accuracy", default="reference", choices=["fast", "default", "reference"])
    parser.add_argument("--check-slices", type=int, default=161, help="face slices of the check of the Table 4 rows (0: none)")
    args = parser.parse_args()
    main(args.accuracy, args.check_slices)
