"""`gearjax reproduce ...`: a paper's quantities beside gearjax's.

* `dca` (seeds 000/003): formula (27)-(28) for m_n 4, z 24/24, b 55 mm, beta 15 deg, and
  Tables 1-2 recomputed with formula (7) in the paper's mixed units and in consistent units.

* `curvilinear` (seed 002): the seed pair d1 40, d2 60 mm (m 2, z 20/30), b 20 mm, α 20°,
  R_t 12 mm, pinion turned by β1 = π/12. The contact line found by the general TCA is
  compared with the closed form (seed 002 eq. 18): its points with the arc
  $s_1 = r_{b1}(\\tan\\alpha_{wt} + \\varphi_1) - d(z)$ on the plane of action, its length with
  $L = 2R_t\\arcsin(b/2R_t)$ for several $R_t$, and the seed's contact parameter
  $\\theta_t' = \\arccos((1 + i_{12})R_{b1}/e) + \\beta_1 = 0.6109$.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .accuracy import Accuracy
from .geometry.curvilinear import CurvilinearGearPair
from .tca import tooth_contact_analysis

SEED_002 = {"teeth": (20, 30), "module": 2.0, "pressure_angle_deg": 20.0, "face_width": 20.0,
            "tooth_trace_radius": 12.0, "beta1": math.pi / 12, "theta_t_prime": 0.6109}


@eqx.filter_jit
def _tca(pair, accuracy, angles):
    return tooth_contact_analysis(pair, accuracy=accuracy, pinion_angles=angles, pairs=(-1, 0, 1))


def contact_line(pair: CurvilinearGearPair, mid_roll_length: float, face_slices: int = 81) -> dict:
    """General-TCA contact line of tooth pair 0 when the mid-face contact sits at pinion roll
    length `mid_roll_length` (mm): its length (polyline through the slice contacts, face
    ends included) and its largest distance from the closed-form arc on the plane of action."""
    rb1 = float(pair.base_radius[0])
    phi = mid_roll_length / rb1 - math.tan(float(pair.working_pressure_angle))
    acc = Accuracy(face_slices=face_slices)
    tca = _tca(pair, acc, jnp.asarray([phi]))
    k = list(np.asarray(tca.pair_index)).index(0)
    z = np.asarray(tca.slice_z)
    order = np.argsort(z)
    points = np.asarray(tca.pinion_point)[0, k][order]
    arc = np.stack([np.asarray(pair.line_of_action_point(mid_roll_length - pair.lead_displacement(zz), zz)) for zz in z[order]])
    return {
        "all_slices_in_contact": bool(np.all(np.asarray(tca.valid)[0, k]) and np.all(np.asarray(tca.separation)[0, k] < 1e-9)),
        "length_mm": float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1))),
        "closed_form_length_mm": float(pair.contact_line_length),
        "max_distance_from_arc_mm": float(np.max(np.linalg.norm(points - arc, axis=1))),
        "te_rad": float(np.asarray(tca.transmission_error)[0]),
    }


def curvilinear() -> dict:
    s = SEED_002
    rows = []
    for radius in (12.0, 15.0, 30.0, 100.0, 1e6):
        pair = CurvilinearGearPair(s["teeth"], s["module"], s["pressure_angle_deg"], s["face_width"], radius)
        row = contact_line(pair, 9.6)
        row["tooth_trace_radius_mm"] = radius
        rows.append(row)
    pair = CurvilinearGearPair(s["teeth"], s["module"], s["pressure_angle_deg"], s["face_width"], s["tooth_trace_radius"])
    i12 = s["teeth"][1] / s["teeth"][0]
    theta = math.acos((1 + i12) * float(pair.base_radius[0]) / float(pair.center_distance)) + s["beta1"]
    return {
        "pair": {k: v for k, v in s.items() if k not in ("beta1", "theta_t_prime")},
        "theta_t_prime": {"paper": s["theta_t_prime"], "gearjax": theta},
        "contact_lines": rows,
    }


def summary_curvilinear(out: dict) -> str:
    t = out["theta_t_prime"]
    lines = [
        "Seed 002: involute curvilinear-tooth gears, z 20/30, m 2 mm, b 20 mm, alpha 20 deg",
        f"  theta_t' = arccos((1 + i12) R_b1 / e) + beta1: paper {t['paper']:.4f}, gearjax {t['gearjax']:.4f}",
        "  contact line (general TCA, mid-face contact at roll length 9.6 mm) vs eq. 18:",
        "  R_t (mm) | L = 2 R_t asin(b/2R_t) | TCA polyline | rel. diff | max off arc (mm) | TE (rad)",
    ]
    for r in out["contact_lines"]:
        lines.append(
            f"  {r['tooth_trace_radius_mm']:8.4g} | {r['closed_form_length_mm']:22.6f} | {r['length_mm']:12.6f} | "
            f"{r['length_mm'] / r['closed_form_length_mm'] - 1:+9.1e} | {r['max_distance_from_arc_mm']:16.1e} | {r['te_rad']:.1e}"
        )
    return "\n".join(lines)


def dca(cross_check: bool = False) -> dict:
    """Seeds 000/003. `cross_check` adds the general TCA on the generated surfaces with the
    same pitch error, both signs (~2 min, mostly compilation)."""
    from .geometry.double_arc import DoubleArcGearPair, axial_meshing
    from .impact.double_arc import (
        SEED_PITCH_CIRCLE_ERROR, SEED_SPEED_RPM, SEED_VELOCITIES, STATES, four_state_impact, seed_tables,
    )

    facts = axial_meshing(4.0, 15.0, 55.0)
    paper = {"axial_pitch": 48.55, "convex_to_concave": 41.85, "concave_to_convex": 6.70, "face_excess": 6.45}
    pair = DoubleArcGearPair((24, 24), 4.0, 15.0, 55.0)
    states = four_state_impact(pair, SEED_PITCH_CIRCLE_ERROR, SEED_SPEED_RPM)
    omega = 2 * SEED_SPEED_RPM * 2 * math.pi / 60
    out = {
        "formula_27_mm": {k: {"paper": v, "gearjax": float(getattr(facts, k))} for k, v in paper.items()},
        "condition_28": bool(facts.condition_28),
        "tables_paper_units": seed_tables(paper_units=True),
        "tables_newton": seed_tables(paper_units=False),
        "four_states": [
            {
                "state": name,
                "paper_radius_mm": v / omega,
                "radius_mm": float(states.radius[k]),
                "exact_radius_mm": float(states.exact_radius[k]),
                "paper_velocity_mm_per_s": v,
                "velocity_mm_per_s": float(states.velocity[k]),
            }
            for k, (name, v) in enumerate(zip(STATES, SEED_VELOCITIES))
        ],
    }
    if cross_check:
        out["tca_cross_check"] = dca_cross_check(pair)
    return out


def dca_cross_check(pair, positions_per_pitch: int = 32) -> list[dict]:
    """First contacts of incoming pairs on the generated surfaces (general TCA) with the
    seed's pitch-circle error, $\\Delta_\\alpha = \\mp\\Delta/\\tan\\beta$."""
    from .geometry.double_arc import ZONE_NAMES
    from .impact.double_arc import SEED_PITCH_CIRCLE_ERROR, SEED_SPEED_RPM, handover_impacts
    from .tca.analysis import tooth_contact_analysis

    rows = []
    axial = SEED_PITCH_CIRCLE_ERROR / math.tan(float(pair.helix_angle))
    omega = 2 * SEED_SPEED_RPM * 2 * math.pi / 60
    for sign, label in ((-1.0, "t1 < t2"), (1.0, "t1 > t2")):
        p = eqx.tree_at(lambda q: q.axial_pitch_error, pair, jnp.asarray(sign * axial))
        tca = tooth_contact_analysis(p, accuracy=Accuracy(positions_per_pitch=positions_per_pitch))
        h = handover_impacts(p, tca)
        for j in range(1, len(h.radius)):  # row 0 compares the cycle's ends (TE is not periodic)
            if float(h.pinion_angle[j]) == float(tca.pinion_angle[0]):
                continue
            rows.append({
                "case": label, "zone": ZONE_NAMES[int(h.zone[j])], "kind": int(h.kind[j]),
                "te_jump_urad": 1e6 * float(h.te_jump[j]), "radius_mm": float(h.radius[j]),
                "velocity_mm_per_s": float(h.radius[j]) * omega,
            })
    return rows


def summary_dca(out: dict) -> str:
    lines = ["Seeds 000/003: double circular arc gears (GB/T 12759), m_n 4, z 24/24, b 55 mm, beta 15 deg",
             "  formula (27), mm:        paper    gearjax"]
    for k, v in out["formula_27_mm"].items():
        lines.append(f"  {k:20s} {v['paper']:9.2f} {v['gearjax']:10.4f}")
    lines.append(f"  formula (28) dB < P_x - q_TA: {out['condition_28']} (three meshing points)")
    p, si = out["tables_paper_units"], out["tables_newton"]
    lines.append("  four-state impact radius (formulas 9-26, repaired), 200 rpm, Delta 0.1 mm:")
    lines.append("  state                        paper PE   gearjax PE   rel.     exact (15)  v_s paper  v_s gearjax")
    for r in out["four_states"]:
        lines.append(
            f"  {r['state']:27s} {r['paper_radius_mm']:9.4f} {r['radius_mm']:11.4f} {r['radius_mm'] / r['paper_radius_mm'] - 1:+8.1e}"
            f" {r['exact_radius_mm']:11.4f} {r['paper_velocity_mm_per_s']:10.2f} {r['velocity_mm_per_s']:11.2f}"
        )
    if "tca_cross_check" in out:
        lines.append("  general TCA on the generated surfaces (first contact of the incoming pair, grid-resolved):")
        for r in out["tca_cross_check"]:
            lines.append(
                f"  {r['case']} {r['zone']:22s} kind {r['kind']}  TE jump {r['te_jump_urad']:+8.1f} urad"
                f"  PE {r['radius_mm']:.4f} mm  v_s {r['velocity_mm_per_s']:.2f} mm/s"
            )
    lines.append("  formula (7), paper units (kg mm^2; sqrt(1000) N) | consistent units (N):")
    for t in ("table1", "table2"):
        for col, a, b, c in zip(("concave in", "concave out", "convex in", "convex out"), p[t]["paper"], p[t]["gearjax"], si[t]["gearjax"]):
            lines.append(f"  {t} {col:11s} paper {a:9.5g}  gearjax {b:9.5g} ({b / a - 1:+.1e})  | {c:8.1f} N")
    return "\n".join(lines)
