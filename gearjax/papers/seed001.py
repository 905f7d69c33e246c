"""Seed 001 (mesh-in impact of involute helical gears): its case, its optimal modification,
its impact-force table and the note on its centre distance. Imports the core; nothing in the
core imports it. The reproduction itself is `benchmarks/studies/reproduce_seed001.py`.

The seed's printed numbers are kept as printed (micrometres, N·m, rpm) and converted to the
engine's units (mm, N·mm, rad/s) where they are used.
"""

from __future__ import annotations

import functools

import jax.numpy as jnp

from ..accuracy import Accuracy
from ..geometry.involute import InvoluteGearPair
from ..geometry.modification import FlankModification

#: The note every reproduction of the case carries: the seed's centre distance is impossible.
SEED_001_NOTE = (
    "seed 001 states a = 261.0 mm, which is inconsistent with beta = 27.5 deg and x1 = x2 = 0 "
    "(261.0 mm would need x1 + x2 = -2.87; it is close to r_b1 + r_b2): gearjax uses "
    "x1 = x2 = 0 and the standard a = 281.85 mm"
)

#: The seed case: teeth, normal module (mm), normal pressure angle (deg), helix angle (deg),
#: face width (mm), and its design speed (rpm, as printed).
SEED_001_CASE = {"teeth": (29, 71), "normal_module": 5.0, "pressure_angle_deg": 20.0,
                 "helix_angle_deg": 27.5, "face_width": 42.0, "speed_rpm": 5000.0}

#: Table 2: the optimal modification y1...y6 in micrometres, as printed.
TABLE2_OPTIMUM_UM = (5.9, 6.8, 3800.0, 4300.0, 6.2, 4600.0)

#: Table 4: impact force (N) of the standard and of the optimally modified pair at 5000 rpm,
#: keyed by the pinion torque in N·m as printed.
TABLE4_IMPACT_FORCE = {400.0: (3250.0, 2300.0), 1000.0: (5829.0, 1981.0), 1600.0: (8950.0, 5370.0)}


def seed_pair() -> InvoluteGearPair:
    """The seed's 29/71 pair with x1 = x2 = 0 and the standard centre distance 281.85 mm
    (see `SEED_001_NOTE`)."""
    c = SEED_001_CASE
    return InvoluteGearPair(c["teeth"], c["normal_module"], c["pressure_angle_deg"], c["helix_angle_deg"], c["face_width"])


def paper_optimum() -> FlankModification:
    """Seed 001's optimal modification (its Table 2): y = (5.9, 6.8, 3800, 4300, 6.2, 4600) um.

    Note that its tip relief length 4.3 mm exceeds the paper's own bound of 0.8 m_n = 4.0 mm.
    """
    return FlankModification.from_micrometres(jnp.array(TABLE2_OPTIMUM_UM))


#: The pinion torques (N·m) of the strike point's trajectory on the flank (the seed's Table 3
#: follows it over the load).
TRAJECTORY_LOADS_NM = (100.0, 200.0, 400.0, 600.0, 800.0, 1000.0, 1200.0, 1400.0, 1600.0)

#: The window of tooth pairs of the reproduction's scenes: two either side of the pair in
#: mesh, so the incoming pair is found at every load.
REPRODUCTION_PAIRS = (-2, -1, 0, 1, 2)


def reproduce(accuracy: str | Accuracy = "reference", check_slices: int = 0,
              trajectory_loads_Nm=TRAJECTORY_LOADS_NM, transition: bool = True) -> dict:
    """The seed's mesh-in impact beside gearjax's, at 5 000 rpm: Table 4 (the standard pair,
    i.e. the paper's optimum without its relief and crowning amounts, and the paper's
    optimum at 400/1 000/1 600 N·m), the strike point's trajectory over
    `trajectory_loads_Nm` (N·m), the torque bracket of the surface-to-edge switch of the
    paper's optimum (`regime_transition`, 1e-3 relative; `transition=False` skips it) and
    the speed exponent $F_s \\propto v^{2n/(n+1)}$ from 2 500 and 5 000 rpm.

    Args:
        accuracy: an `Accuracy` or a spec (`PRESET` or `PRESET@PxS`); the published table is
            at `reference`.
        check_slices: face slices of a second evaluation of the Table 4 rows
            (`Accuracy.finer`), recorded beside them with the largest relative force
            difference and whether every regime agrees; 0: no check.

    Returns a dict of plain numbers (units in the keys); every row says whether its stages
    converged (`converged`), and nothing stops at one that did not.
    """
    from ..sweep import regime_transition

    acc = accuracy if isinstance(accuracy, Accuracy) else Accuracy.from_spec(accuracy)
    paper = paper_optimum().as_vector()
    plain = paper.at[jnp.array([0, 1, 4])].set(0.0)
    run = functools.partial(_strike, seed_pair(), accuracy=acc)
    table = []
    for torque, (paper_standard, paper_modified) in TABLE4_IMPACT_FORCE.items():
        table.append({"torque_Nm": torque, "paper_standard_N": paper_standard, "standard": run(plain, torque),
                      "paper_modified_N": paper_modified, "modified": run(paper, torque)})
    loads = [float(t) for t in trajectory_loads_Nm]
    trajectory = {"standard": [run(plain, t) for t in loads], "modified": [run(paper, t) for t in loads]}
    bracket = None
    if transition:
        below, above = regime_transition(_scene(seed_pair(), paper, 400.0, accuracy=acc), low_Nm=400.0, high_Nm=1600.0,
                                         tolerance=1e-3)
        bracket = [float(below) / 1e3, float(above) / 1e3]
    slow, quick = run(paper, 1000.0, 2500.0), run(paper, 1000.0, 5000.0)
    n = quick["stiffness_exponent"]
    speed = {
        "force_ratio_5000_over_2500": quick["force_N"] / slow["force_N"],
        "predicted_2_pow_2n_over_n_plus_1": 2.0 ** (2 * n / (n + 1)),
        "exponent_2n_over_n_plus_1": 2 * n / (n + 1),
    }
    check = _check(table, {"standard": plain, "modified": paper}, acc.finer(check_slices)) if check_slices else None
    return {
        "note": SEED_001_NOTE,
        "accuracy": {"positions_per_pitch": acc.positions_per_pitch, "face_slices": acc.face_slices},
        "check": check,
        "table4": table,
        "trajectory": trajectory,
        "transition_torque_Nm": bracket,
        "speed": speed,
    }


def _scene(pair, y, torque_Nm, rpm=SEED_001_CASE["speed_rpm"], *, accuracy: Accuracy):
    from ..operating import OperatingPoint
    from ..scene import Scene

    return Scene(pair, FlankModification.from_vector(y), effects=("impact",), accuracy=accuracy,
                 operating=OperatingPoint(torque_Nm=torque_Nm, speed_rpm=rpm), pairs=REPRODUCTION_PAIRS)


def _strike(pair, y, torque_Nm, rpm=SEED_001_CASE["speed_rpm"], *, accuracy: Accuracy) -> dict:
    """The impact of design `y` (engine units) of `pair` at one operating point, as plain numbers."""
    from .._solution import RESULTS
    from ..pipeline import simulate

    impact = simulate(_scene(pair, y, torque_Nm, rpm, accuracy=accuracy), throw=False).impact
    return {
        "torque_Nm": torque_Nm,
        "speed_rpm": rpm,
        "force_N": float(impact.force),
        "velocity_mm_per_s": float(impact.velocity),
        "regime": impact.regime_name,
        "pinion_roll_length_mm": float(impact.pinion_parameter),
        "face_position_mm": float(impact.slice_z),
        "stiffness_coefficient": float(impact.stiffness.coefficient),
        "stiffness_exponent": float(impact.stiffness.exponent),
        "fit_error": float(impact.stiffness.fit_error),
        "equivalent_mass_kg": float(impact.mass) * 1e3,
        "loaded_te_um": float(impact.loaded_te) * float(pair.base_radius[1]) * 1e3,
        "converged": bool(impact.result == RESULTS.successful),
    }


def _check(table: list[dict], designs: dict, finer: Accuracy) -> dict:
    """Table 4's rows evaluated again at `finer`, recorded in the rows: the largest relative
    force difference and whether every regime agrees."""
    differences, regimes_equal = [], True
    for row in table:
        for name, y in designs.items():
            other = _strike(seed_pair(), y, row["torque_Nm"], accuracy=finer)
            row[name]["force_N_at_check"] = other["force_N"]
            row[name]["converged_at_check"] = other["converged"]
            differences.append(abs(row[name]["force_N"] / other["force_N"] - 1.0))
            regimes_equal &= other["regime"] == row[name]["regime"]
    return {"face_slices": finer.face_slices, "largest_force_difference": max(differences),
            "regimes_equal": bool(regimes_equal)}


def summary(out: dict) -> str:
    """The text report of `reproduce()`'s result: Table 4 beside gearjax's forces, the
    switch's torque bracket, the speed exponent and the accuracy and its check."""
    acc, check = out["accuracy"], out["check"]
    lines = [
        "Seed 001: mesh-in impact of the 29/71 helical pair at 5000 rpm (Table 4)",
        f"  note: {out['note']}",
        f"  accuracy: {acc['positions_per_pitch']} positions per pitch, {acc['face_slices']} face slices; "
        + ("not checked against a finer setting (--check-slices N)" if check is None else
           f"checked at {check['face_slices']} face slices: forces within {100 * check['largest_force_difference']:.2f} %, "
           f"regimes {'the same' if check['regimes_equal'] else 'DIFFERENT'}"),
        "  load (N m) | standard: seed 001 | gearjax          | modified: seed 001 | gearjax",
    ]
    for row in out["table4"]:
        s, m = row["standard"], row["modified"]
        flag = lambda r: "" if r["converged"] else " (not converged)"  # noqa: E731
        lines.append(f"  {row['torque_Nm']:10.0f} | {row['paper_standard_N']:16.0f} N | {s['force_N']:7.0f} N {s['regime']:>7}"
                     f"{flag(s)} | {row['paper_modified_N']:16.0f} N | {m['force_N']:7.0f} N {m['regime']}{flag(m)}")
    if out["transition_torque_Nm"] is not None:
        low, high = out["transition_torque_Nm"]
        lines.append(f"  the paper's optimum switches from a flank to a tip-edge strike between {low:.1f} and {high:.1f} N m")
    sp = out["speed"]
    lines.append(f"  F_s(5000 rpm) / F_s(2500 rpm) = {sp['force_ratio_5000_over_2500']:.4f}; "
                 f"2^(2n/(n+1)) = {sp['predicted_2_pow_2n_over_n_plus_1']:.4f}")
    return "\n".join(lines)
