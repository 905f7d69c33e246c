"""Seed 002 (involute curvilinear-tooth gears): the seed case and the `gearjax reproduce
curvilinear` reproduction. Imports the core; nothing in the core imports it.

The seed pair d1 40, d2 60 mm (m 2, z 20/30), b 20 mm, α 20°, R_t 12 mm, pinion turned by
β1 = π/12. The contact line found by the general TCA is compared with the closed form (seed
002 eq. 18): its points with the arc $s_1 = r_{b1}(\\tan\\alpha_{wt} + \\varphi_1) - d(z)$ on
the plane of action, its length with $L = 2R_t\\arcsin(b/2R_t)$ for several $R_t$, and the
seed's contact parameter $\\theta_t' = \\arccos((1 + i_{12})R_{b1}/e) + \\beta_1 = 0.6109$.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..accuracy import Accuracy
from ..geometry.curvilinear import CurvilinearGearPair
from ..tca import tooth_contact_analysis

#: The seed case: z 20/30, module (mm), pressure angle (deg), face width (mm), tooth-trace
#: radius R_t (mm), the pinion's turn beta1 (rad) and the printed contact parameter theta_t' (rad).
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


def reproduce() -> dict:
    """`gearjax reproduce curvilinear`: theta_t' and the contact line at R_t = 12, 15, 30, 100
    and 1e6 mm (general TCA against eq. 18), lengths in mm."""
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


def summary(out: dict) -> str:
    """The text report of `reproduce()`'s result."""
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
