r"""Seeds 000/003 (double-circular-arc gears, GB/T 12759): the paper's own formulas, tables
and the `gearjax reproduce dca` reproduction. Imports the core; nothing in the core imports it.

**Axial meshing facts**, formulas (27)–(28) (`axial_meshing`): the axial pitch, the axial
distances between the convex- and concave-flank contact points, and the meshing case with three
meshing points.

**Meshing impact force**, formula (7) (`formula7_impact_force`):

$$F_s = \frac{v_s}{\cos\alpha}\sqrt{\frac{K}{n}\,\frac{J_1J_2}{J_1R_2^2 + J_2R_1^2}}$$

with the impact velocity $v_s$, the meshing stiffness $K$, $n$ meshing points, and the gear
inertias $J_i$ about their axes with the pitch radii $R_i$. The seed's Tables 1 and 2 come
out to four digits with $n = 3$, solid discs $J = \pi\rho bR^4/2$ at the reference radius
($\rho = 7.85\times10^{-6}$ kg/mm³) and the tabulated $K$ and $v_s$ — but only in the seed's
mixed units: $v$ in mm/s, $K$ in N/mm and $J$ in kg·mm². Then $K J/R^2$ is in N·kg/mm² and
$v\sqrt{\cdot}$ in mm/s·√(N·kg)/mm, which is $\sqrt{1000}$ N, not N (1 kg = 1e-3 N·s²/mm).
In consistent units (N, mm, s, t) the same inputs give forces $\sqrt{1000} \approx 31.6$
times smaller. Every function here takes consistent units; `paper_units=True` (explicit,
never the default) returns the seed's numbers, labelled.

**The four meshing-impact states** (seed section 3.1): `four_state.py`.

**Reproduction** (`reproduce`, `summary`; `gearjax reproduce dca [--cross-check]`): formula (27)
against the seed's numbers, the four states against its velocities, Tables 1–2 in its units and
in N, the meshing stiffness $K$ of Table 1 computed on the loaded contact of the generated
surfaces (`meshing_stiffness`) with formula (7)'s forces for it, and optionally `cross_check_tca`: the first contacts found by the general TCA on the
generated surfaces (`handover_impacts`).
"""

from __future__ import annotations

import json
import math

import equinox as eqx
import jax
import jax.numpy as jnp

from ..accuracy import Accuracy
from .._custom_types import Array, ArrayLike, Scalar
from .._numerics import as_float
from .._validate import check_range
from ..geometry.double_arc import ZONE_NAMES, DoubleArcGearPair, GBT12759Rack
from ..impact.energy import gear_inertia
from ..tca.analysis import tooth_contact_analysis
from .four_state import (
    SEED_PINION_SPEED,
    SEED_PITCH_CIRCLE_ERROR,
    SEED_SPEED_RPM,
    SEED_VELOCITIES,
    STATES,
    four_state_impact,
)
from .meshing_stiffness import STIFFNESS_COLUMNS, meshing_stiffness

#: The seed case: m_n 4 mm, z 24/24, b 55 mm, beta 15 deg, alpha 24 deg, n = 3.
SEED_CASE = {"normal_module": 4.0, "teeth": (24, 24), "face_width": 55.0, "helix_angle_deg": 15.0,
             "pressure_angle_deg": 24.0, "meshing_points": 3}
#: Formula (27) for the seed case as the seed prints it (mm).
SEED_FORMULA_27 = {"axial_pitch": 48.55, "convex_to_concave": 41.85, "concave_to_convex": 6.70, "face_excess": 6.45}
#: Seed 000, Tables 1 and 2 (t1 < t2): columns concave mesh-in, concave mesh-out, convex
#: mesh-in, convex mesh-out. Stiffness N/mm, velocity mm/s, force in the seed's mixed unit
#: ($\sqrt{1000}$ N, see the module docstring).
#: (Seed 003 prints Table 1's stiffness row in another order; seed 000 has it right.)
SEED_TABLES = {
    "stiffness": (1.8084e6, 7.685e5, 1.771e6, 7.1088e5),
    "table1": {"velocity": (61.92, 61.92, 36.33, 36.33), "force": (4.816e4, 3.1392e4, 2.796e4, 1.7715e4)},
    "table2": {"velocity": (81.57, 81.57, 60.01, 60.01), "force": (6.344e4, 4.1354e4, 4.6185e4, 2.9261e4)},
}
#: The seed's driving torque (N·mm): 100 N·m.
SEED_TORQUE = 1.0e5
#: kg per tonne: the seed's inertias are in kg·mm², the engine's in t·mm².
_KG_PER_T = 1000.0


class AxialMeshing(eqx.Module):
    """Seed 003, formulas (27)–(28) (mm).

    Attributes:
        axial_pitch: $P_x = \\pi m_n/\\sin\\beta$.
        convex_to_concave: $q_{TA}$, axial distance from the convex-flank contact point to
            the concave-flank contact point of the same tooth.
        concave_to_convex: $q'_{TA} = P_x - q_{TA}$ (to the neighbouring tooth).
        face_excess: $\\Delta b = b - P_x$.
        condition_28: $\\Delta b < P_x - q_{TA}$, the meshing case the seed analyses
            (three meshing points, $n = 3$).
    """

    axial_pitch: Scalar
    convex_to_concave: Scalar
    concave_to_convex: Scalar
    face_excess: Scalar
    condition_28: jnp.ndarray


def axial_meshing(normal_module: ArrayLike, helix_angle_deg: ArrayLike, face_width: ArrayLike, rack: GBT12759Rack = GBT12759Rack()) -> AxialMeshing:
    r"""Formula (27): $P_x = \pi m_n/\sin\beta$, $\Delta b = b - P_x$,

    $$q_{TA} = \frac{0.5\pi m_n - 0.5j + 2l_a + 2e_a\cot\alpha}{\sin\beta}
    - 2\Big(\rho_a + \frac{e_a}{\sin\alpha}\Big)\cos\alpha\sin\beta,$$

    $q'_{TA} = P_x - q_{TA}$; formula (28) is the case $\Delta b < P_x - q_{TA}$. Arguments:
    normal module (mm), helix angle (deg), face width (mm), the basic rack (multiples of $m_n$).
    """
    check_range("normal_module", normal_module, 0.01, 100.0, unit="mm")
    check_range("helix_angle_deg", helix_angle_deg, 0.0, 45.0, low_inclusive=False, high_inclusive=False, unit="deg")
    check_range("face_width", face_width, 0.0, None, low_inclusive=False, unit="mm")
    m = as_float(normal_module)
    beta = as_float(helix_angle_deg) * (math.pi / 180.0)
    b = as_float(face_width)
    alpha = math.radians(rack.pressure_angle_deg)
    la, ea, ra, j = (m * v for v in (rack.convex_centre_offset, rack.convex_centre_shift, rack.convex_radius, rack.backlash))
    px = math.pi * m / jnp.sin(beta)
    q = (0.5 * math.pi * m - 0.5 * j + 2 * la + 2 * ea / math.tan(alpha)) / jnp.sin(beta) - 2 * (
        ra + ea / math.sin(alpha)
    ) * math.cos(alpha) * jnp.sin(beta)
    excess = b - px
    return AxialMeshing(px, q, px - q, excess, excess < px - q)


def formula7_impact_force(
    velocity: ArrayLike,
    stiffness: ArrayLike,
    meshing_points: int,
    inertia: ArrayLike,
    radius: ArrayLike,
    pressure_angle_deg: ArrayLike = 24.0,
    *,
    paper_units: bool = False,
) -> Scalar:
    """Seed 000/003's formula (7), the meshing impact force of double-circular-arc gears,
    $F_s = v_s/\\cos\\alpha\\,\\sqrt{K/n\\cdot J_1J_2/(J_1R_2^2 + J_2R_1^2)}$ (not the energy method
    of `gearjax.impact.energy.impact_force`).

    Args:
        velocity: impact velocity $v_s$ (mm/s).
        stiffness: meshing stiffness $K$ (N/mm).
        meshing_points: number $n$ of meshing points sharing $K$.
        inertia: $(J_1, J_2)$ on the last axis (t·mm²).
        radius: pitch radii $(R_1, R_2)$ on the last axis (mm).
        pressure_angle_deg: $\\alpha$ (deg).
        paper_units: False (default): the force in N. True: the seed's number, the formula
            evaluated with the inertia in kg·mm² (its mixed units), which is $\\sqrt{1000}$
            times the force in N; label it "paper units".
    """
    check_range("velocity", velocity, 0.0, None, unit="mm/s")
    check_range("stiffness", stiffness, 0.0, None, low_inclusive=False, unit="N/mm")
    check_range("inertia", inertia, 0.0, None, low_inclusive=False, unit="t·mm²")
    check_range("radius", radius, 0.0, None, low_inclusive=False, unit="mm")
    if not isinstance(meshing_points, int) or meshing_points < 1:
        raise ValueError(f"meshing_points must be an integer >= 1; got {meshing_points!r}")
    j = as_float(inertia) * _KG_PER_T if paper_units else as_float(inertia)
    r = as_float(radius)
    j1, j2 = j[..., 0], j[..., 1]
    r1, r2 = r[..., 0], r[..., 1]
    mass = j1 * j2 / (j1 * r2**2 + j2 * r1**2)
    alpha = as_float(pressure_angle_deg) * (math.pi / 180.0)
    return as_float(velocity) / jnp.cos(alpha) * jnp.sqrt(as_float(stiffness) / meshing_points * mass)


def seed_tables(paper_units: bool = False, stiffness=None) -> dict:
    """Tables 1 and 2 recomputed from formula (7) for the seed case (module docstring): solid
    steel discs ($\\rho$ = 7.85e-9 t/mm³) at the reference radius. Forces in N, or with
    `paper_units=True` in the seed's mixed units (inertia then reported in kg·mm²); with the
    seed's meshing stiffness row, or `stiffness` (N/mm, the four columns) instead."""
    c = SEED_CASE
    radius = c["normal_module"] * c["teeth"][0] / (2 * math.cos(math.radians(c["helix_angle_deg"])))
    j = gear_inertia(7.85e-9, c["face_width"], radius, 0.0)  # t mm^2; solid disc, no hub
    inertia = jnp.stack([j, j])
    radii = jnp.asarray([radius, radius])
    out = {
        "reference_radius_mm": radius,
        "inertia": float(j) * _KG_PER_T if paper_units else float(j),
        "units": "paper (kg mm^2, sqrt(1000) N)" if paper_units else "N",
    }
    for name in ("table1", "table2"):
        forces = [
            float(formula7_impact_force(v, k, c["meshing_points"], inertia, radii, c["pressure_angle_deg"], paper_units=paper_units))
            for v, k in zip(SEED_TABLES[name]["velocity"], SEED_TABLES["stiffness"] if stiffness is None else stiffness)
        ]
        out[name] = {"paper": list(SEED_TABLES[name]["force"]), "gearjax": forces}
    return out


class HandoverImpact(eqx.Module):
    """First contacts of incoming tooth pairs found by the general TCA (cross-check of the
    four-state model on the real surfaces), one row per hand-over in the cycle.

    Attributes:
        pinion_angle: position of the grid at which the new pair binds (rad).
        zone: 0 convex, 1 concave driving tooth of the new contact.
        kind: 0 flank, 1 gear-edge, 2 pinion-edge contact (TCA kinds).
        te_jump: rise of the TE at the hand-over (rad); > 0 is a strike.
        radius: distance (mm) from the pitch line to the common normal of the new contact,
            in the transverse plane (the seed's impact radius PE).
    """

    pinion_angle: Array
    zone: Array
    kind: Array
    te_jump: Array
    radius: Array


def handover_impacts(pair: DoubleArcGearPair, tca) -> HandoverImpact:
    """Hand-overs of a DCA TCA result (`tooth_contact_analysis` of a `DoubleArcGearPair`
    with an axial pitch error): wherever the binding (zone, tooth pair) changes between two
    grid positions, the new binding contact's normal line is measured from the pitch point
    $(R_1, 0)$ in the transverse plane. Resolved to the position grid (NumPy; not traced)."""
    import numpy as np

    pair_idx, slice_idx = (np.asarray(a) for a in tca.binding)
    zone = np.asarray(tca.pair_zone)[pair_idx]
    key = zone * 1000 + np.asarray(tca.pair_index)[pair_idx]
    te = np.asarray(tca.transmission_error)
    (kinds,) = jax.tree_util.tree_leaves(tca.kind)  # ContactKind item -> its index array
    kinds = np.asarray(kinds)
    pitch = np.array([float(pair.pitch_radius[0]), 0.0])
    rows = []
    n = len(te)
    for j in range(n):
        prev = (j - 1) % n
        if key[j] == key[prev]:
            continue
        p, s = pair_idx[j], slice_idx[j]
        point = np.asarray(tca.pinion_point[j, p, s])[:2]
        normal = np.asarray(tca.normal[j, p, s])[:2]
        normal = normal / np.linalg.norm(normal)
        d = pitch - point
        radius = abs(normal[0] * d[1] - normal[1] * d[0])
        rows.append((float(tca.pinion_angle[j]), int(zone[j]), int(kinds[j, p, s]), te[j] - te[prev], radius))
    cols = list(zip(*rows)) if rows else [()] * 5
    return HandoverImpact(*(jnp.asarray(c) for c in cols))


def seed_pair() -> DoubleArcGearPair:
    """The seed case (`SEED_CASE`) as a `DoubleArcGearPair` with the recalled GB/T 12759 rack."""
    c = SEED_CASE
    return DoubleArcGearPair(c["teeth"], c["normal_module"], c["helix_angle_deg"], c["face_width"])


def seed_scene_file(torque_Nm: float | None = None, speed_rpm: float | None = None,
                    analysis: dict[str, object] | None = None) -> str:
    """The seed case as a scene file (TOML text): its `[pair]`, with `[operating]` when a
    torque or speed is given and `[analysis]` holding `analysis`'s entries (e.g.
    `{"effects": ["impact"]}`)."""
    c = SEED_CASE
    lines = ["[pair]", 'family = "double_circular_arc"', f"teeth = [{c['teeth'][0]}, {c['teeth'][1]}]",
             f"normal_module = {c['normal_module']}", f"helix_angle_deg = {c['helix_angle_deg']}",
             f"face_width = {c['face_width']}"]
    operating = {"torque_Nm": torque_Nm, "speed_rpm": speed_rpm}
    if any(v is not None for v in operating.values()):
        lines += ["", "[operating]"] + [f"{k} = {v}" for k, v in operating.items() if v is not None]
    if analysis:
        lines += ["", "[analysis]"] + [f"{k} = {json.dumps(v)}" for k, v in analysis.items()]
    return "\n".join(lines) + "\n"


#: the accuracy of `reproduce`'s meshing stiffness: within 0.06 % of 128 positions per pitch
#: and of 81 face slices in every column, where `default` (32 x 21) is 3.1 % low in one
#: (`docs/validation.md`)
STIFFNESS_ACCURACY = "default@64x41"


def reproduce(cross_check: bool = False, accuracy: str = STIFFNESS_ACCURACY) -> dict:
    """`gearjax reproduce dca`: formula (27)-(28) for the seed case, the four states at the
    seed's 200 rpm and $\\Delta$ = 0.1 mm, and Tables 1-2 recomputed with formula (7) in the
    paper's mixed units (labelled) and in N, our meshing stiffness (`meshing_stiffness`, the
    seed pair at 100 N·m, at `accuracy`, a `PRESET` or `PRESET@PxS` spec: compiles the
    loaded contact, ~3 min the first time at the default 64 x 41) and the tables' forces
    with it. `cross_check` adds the general TCA on the generated surfaces with the same
    pitch error, both signs (~2 min, mostly compilation)."""
    setting = Accuracy.from_spec(accuracy)
    c = SEED_CASE
    facts = axial_meshing(c["normal_module"], c["helix_angle_deg"], c["face_width"])
    pair = seed_pair()
    states = four_state_impact(pair, SEED_PITCH_CIRCLE_ERROR, SEED_PINION_SPEED)
    omega = 2 * SEED_SPEED_RPM * 2 * math.pi / 60
    out = {
        "formula_27_mm": {k: {"paper": v, "gearjax": float(getattr(facts, k))} for k, v in SEED_FORMULA_27.items()},
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
    ours = [float(k) for k in meshing_stiffness(pair, SEED_TORQUE, setting).stiffness]
    out["mesh_stiffness_N_per_mm"] = ours
    out["paper_mesh_stiffness_N_per_mm"] = list(SEED_TABLES["stiffness"])
    out["mesh_stiffness_columns"] = [f"{'concave' if z else 'convex'} tooth meshing {kind}" for z, kind in STIFFNESS_COLUMNS]
    out["mesh_stiffness_setting"] = (f"loaded contact at 100 N·m, accuracy {accuracy!r} ({setting.positions_per_pitch} "
                                     f"positions per pitch, {setting.face_slices} face slices)")
    out["tables_with_our_stiffness_paper_units"] = seed_tables(paper_units=True, stiffness=ours)
    out["tables_with_our_stiffness_newton"] = seed_tables(paper_units=False, stiffness=ours)
    if cross_check:
        out["tca_cross_check"] = cross_check_tca(pair)
    return out


def cross_check_tca(pair: DoubleArcGearPair, positions_per_pitch: int = 32) -> list[dict]:
    """First contacts of incoming pairs on the generated surfaces (general TCA) with the
    seed's pitch-circle error, $\\Delta_\\alpha = \\mp\\Delta/\\tan\\beta$; velocities at the
    seed's speed (mm/s)."""
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


def summary(out: dict) -> str:
    """The text report of `reproduce()`'s result."""
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
    columns = ("concave in", "concave out", "convex in", "convex out")
    for t in ("table1", "table2"):
        for col, a, b, c in zip(columns, p[t]["paper"], p[t]["gearjax"], si[t]["gearjax"]):
            lines.append(f"  {t} {col:11s} paper {a:9.5g}  gearjax {b:9.5g} ({b / a - 1:+.1e})  | {c:8.1f} N")
    lines.append(f"  meshing stiffness K (N/mm), ours from the {out['mesh_stiffness_setting']}:")
    for col, a, b in zip(columns, out["paper_mesh_stiffness_N_per_mm"], out["mesh_stiffness_N_per_mm"]):
        lines.append(f"  {col:11s} paper {a:10.5g}  gearjax {b:10.5g}  (x{b / a:.3f})")
    ours_p, ours_n = out["tables_with_our_stiffness_paper_units"], out["tables_with_our_stiffness_newton"]
    lines.append("  formula (7) with our K, paper units | N:")
    for t in ("table1", "table2"):
        for col, a, b, c in zip(columns, ours_p[t]["paper"], ours_p[t]["gearjax"], ours_n[t]["gearjax"]):
            lines.append(f"  {t} {col:11s} paper {a:9.5g}  with our K {b:9.5g} (x{b / a:.3f})  | {c:8.1f} N")
    return "\n".join(lines)
