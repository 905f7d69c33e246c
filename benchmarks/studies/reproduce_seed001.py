"""Seed 001 reproduction: mesh-in impact force against load (Table 4), the strike-point
trajectory on the flank (Table 3) and the speed exponent.

    python benchmarks/studies/reproduce_seed001.py [--accuracy reference] [--check-slices 161]

Writes docs/results/seed001_impact.json and docs/figures/impact_trajectory.png and prints
the table of `docs/impact.md`: `gearjax.papers.seed001.reproduce` (also `gearjax reproduce
seed001`) at a preset (default `reference`: 128 positions per pitch, 81 face slices),
float64, its Table 4 rows evaluated again with `--check-slices` face slices (0: no check;
`Accuracy.finer`).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

from gearjax.papers.seed001 import (  # noqa: E402
    TABLE4_IMPACT_FORCE,
    TRAJECTORY_LOADS_NM,
    reproduce,
    seed_pair,
    summary,
)

ROOT = Path(__file__).resolve().parents[2]


def main(accuracy: str = "reference", check_slices: int = 161) -> dict:
    out = reproduce(accuracy, check_slices)
    out["accuracy"]["preset"] = accuracy
    (ROOT / "docs" / "results").mkdir(parents=True, exist_ok=True)
    (ROOT / "docs" / "results" / "seed001_impact.json").write_text(json.dumps(out, indent=1))
    _figure(seed_pair(), TRAJECTORY_LOADS_NM, out["trajectory"], out["transition_torque_Nm"])
    print(summary(out))
    for name in ("standard", "modified"):
        print(name, [(r["torque_Nm"], round(r["pinion_roll_length_mm"], 3), r["regime"], round(r["force_N"]))
                     for r in out["trajectory"][name]])
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


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--accuracy", default="reference", choices=["fast", "default", "reference"])
    parser.add_argument("--check-slices", type=int, default=161, help="face slices of the check of the Table 4 rows (0: none)")
    args = parser.parse_args()
    main(args.accuracy, args.check_slices)
