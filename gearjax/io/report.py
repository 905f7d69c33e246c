"""Presentation layer: results as a JSON-ready dictionary and a readable summary.

Units switch here to what engineers read: micrometres, microradians, degrees, N·m, rpm.
Every key carries its unit; the keys are documented in the README ("JSON output").
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._solution import RESULTS, enum_message, enum_name
from ..geometry import FAMILIES
from ..ltca import COMPLIANCE_MODELS
from ..pipeline import SimulationResult
from ..scene import Scene
from ..tca import ContactKind
from ..units import UM_PER_MM, URAD_PER_RAD


def _f(x) -> float:
    return float(np.asarray(x))


def _list(x, scale=1.0) -> list[float]:
    return [float(v) * scale for v in np.asarray(x).ravel()]


@eqx.filter_jit
def _quantities(result: SimulationResult) -> dict:
    """What the report derives from a result, in one compiled program (a fresh process
    compiles it once per result structure, where each of its operations would be an eager
    program of its own)."""
    tca, ltca = result.tca, result.ltca
    out = {
        "te_peak_to_peak": tca.te_peak_to_peak,
        "te_peak_to_peak_line": tca.te_peak_to_peak_line,
        "binding": tca.binding,
        "edge": tca.kind != ContactKind.flank,
        "contact_slices": jnp.sum(tca.in_contact(1e-7), axis=(1, 2)),
    }
    if ltca is not None:
        names = ("lte_peak_to_peak", "lte_peak_to_peak_line", "load_share", "normal_load", "mean_mesh_stiffness",
                 "mesh_stiffness_tangent", "mesh_stiffness_secant", "max_load_share", "max_pressure")
        out |= {name: getattr(ltca, name) for name in names}
    return out


def geometry_dict(scene: Scene) -> dict:
    """The pair's `geometry_report()` as plain numbers (lists per gear)."""
    pair = scene.pair
    out = {"family": type(pair).__name__, "teeth": list(pair.teeth)}
    for key, value in pair.resolve().geometry_report().items():
        array = np.asarray(value)
        out[key] = float(array) if array.ndim == 0 else _list(array)
    return out


def tca_dict(scene: Scene, result: SimulationResult, q: dict) -> dict:
    """The TCA's figures; `q`: `_quantities(result)`."""
    tca = result.tca
    te = np.asarray(tca.transmission_error)
    rb = float(np.asarray(tca.action_radius)[1])
    valid = np.asarray(tca.valid)
    pair_idx, slice_idx = (np.asarray(a) for a in q["binding"])
    binding_edge = np.asarray(q["edge"])[np.arange(te.size), pair_idx, slice_idx]
    return {
        "method": scene.accuracy.tca_method,
        "positions": int(te.size),
        "te_peak_to_peak_urad": _f(q["te_peak_to_peak"]) * URAD_PER_RAD,
        "te_peak_to_peak_um": _f(q["te_peak_to_peak_line"]) * UM_PER_MM,
        "te_mean_um": float(np.mean(te)) * rb * UM_PER_MM,
        "pinion_angle_deg": _list(tca.pinion_angle, 180.0 / math.pi),
        "te_urad": _list(te, URAD_PER_RAD),
        "te_um": _list(te, rb * UM_PER_MM),
        "edge_contact_positions": int(np.sum(binding_edge)),
        "pairs": [int(k) for k in np.asarray(tca.pair_index)],
        "contact_slices_per_position": [int(v) for v in np.asarray(q["contact_slices"])],
        "valid_slice_contacts": int(valid.sum()),
        "unconverged_solves": int(np.asarray(tca.unconverged).sum()),
        "result": enum_name(tca.result),
    }


def ltca_dict(scene: Scene, result: SimulationResult, q: dict) -> dict:
    """The loaded contact's figures; `q`: `_quantities(result)`."""
    ltca = result.ltca
    rb2 = float(np.asarray(ltca.action_radius)[1])
    lte = np.asarray(ltca.transmission_error)
    share = np.asarray(q["load_share"])
    point = {}
    if ltca.point_contact is not None:
        contact = ltca.point_contact
        heaviest = np.unravel_index(np.argmax(np.asarray(contact.loads)), np.shape(contact.loads))
        point = {"contact_ellipse_semi_axes_mm": [float(np.asarray(contact.semi_major)[heaviest]),
                                                  float(np.asarray(contact.semi_minor)[heaviest])],
                 "max_pair_load_N": float(np.asarray(contact.loads)[heaviest])}
    return {
        "compliance": type(scene.compliance).__name__,
        "extended_contact": scene.extended_contact,
        "torque_Nm": _f(ltca.torque) / 1000.0,
        "normal_load_N": float(np.mean(np.asarray(q["normal_load"]))),
        "lte_peak_to_peak_um": _f(q["lte_peak_to_peak_line"]) * UM_PER_MM,
        "lte_peak_to_peak_urad": _f(q["lte_peak_to_peak"]) * URAD_PER_RAD,
        "lte_mean_um": float(np.mean(lte)) * rb2 * UM_PER_MM,
        "lte_um": _list(lte, rb2 * UM_PER_MM),
        "mean_mesh_stiffness_N_per_mm_um": _f(q["mean_mesh_stiffness"]),
        "mesh_stiffness_tangent_N_per_mm_um": _list(q["mesh_stiffness_tangent"]),
        "mesh_stiffness_secant_N_per_mm_um": _list(q["mesh_stiffness_secant"]),
        "max_load_share": _f(q["max_load_share"]),
        "max_pressure_MPa": _f(q["max_pressure"]),
        "load_share_per_pair": [_list(row) for row in share.T],
        "converged": bool(np.all(np.asarray(ltca.converged))),
        "result": enum_name(ltca.result),
    } | point


def impact_dict(scene: Scene, result: SimulationResult) -> dict:
    """The impact's figures; for a pair of several contact zones (double circular arc),
    `{"zones": [...]}`, one entry per zone's incoming pair with its `zone` name."""
    imp = result.impact
    names = scene.pair.zone_names  # the impact has a zone axis where the pair has several zones
    if len(names) == 1:
        return _one_impact(imp, result.ltca.action_radius)
    return {"zones": [{"zone": names[z]} | _one_impact(jax.tree_util.tree_map(lambda x: x[z], imp),
                                                       result.ltca.action_radius)
                      for z in range(len(names))]}


def _one_impact(imp, action_radius) -> dict:
    stiff = imp.stiffness
    return {
        "force_N": _f(imp.force),
        "velocity_mm_per_s": _f(imp.velocity),
        "regime": imp.regime_name,
        "contact_kind": enum_name(imp.kind),
        "point_mm": _list(imp.pinion_point),
        "gear_point_mm": _list(imp.gear_point),
        "normal": _list(imp.normal),
        "pinion_roll_length_mm": _f(imp.pinion_parameter),
        "gear_roll_length_mm": _f(imp.gear_parameter),
        "face_position_mm": _f(imp.slice_z),
        "pinion_angle_deg": _f(imp.pinion_angle) * 180.0 / math.pi,
        "loaded_te_um": _f(imp.loaded_te) * float(np.asarray(action_radius)[1]) * UM_PER_MM,
        "stiffness_coefficient_N_per_mm_n": _f(stiff.coefficient),
        "stiffness_exponent": _f(stiff.exponent),
        "stiffness_fit_error": _f(stiff.fit_error),
        "equivalent_mass_kg": _f(imp.mass) * 1e3,
        "base_radius_equivalent_mass_kg": _f(imp.base_radius_mass) * 1e3,
        "approach_um": _f(imp.approach) * UM_PER_MM,
        "kinetic_energy_J": _f(imp.kinetic_energy) * 1e-3,
        "converged": enum_name(imp.result) == enum_name(RESULTS.successful),
        "result": enum_name(imp.result),
    }


def result_dict(scene: Scene, result: SimulationResult, notes: list[str] | None = None) -> dict:
    """Everything `gearjax run --json` prints."""
    q = _quantities(result)
    out = {"geometry": geometry_dict(scene), "tca": tca_dict(scene, result, q)}
    if result.ltca is not None:
        out["ltca"] = ltca_dict(scene, result, q)
    if result.impact is not None:
        out["impact"] = impact_dict(scene, result)
    out["operating"] = {
        "torque_Nm": None if scene.operating.torque is None else _f(scene.operating.torque) / 1000.0,
        "speed_rpm": _f(scene.operating.speed) * 60.0 / (2 * math.pi),
    }
    out["analysis"] = {
        "effects": sorted({"tca"} | set(scene.effects)),
        "positions_per_pitch": scene.accuracy.positions_per_pitch,
        "face_slices": scene.accuracy.face_slices,
        "dtype": scene.accuracy.dtype,
    }
    if notes:
        out["notes"] = notes
    return out


#: The families and compliance models in an engineer's words (`summary`).
FAMILY_WORDS = {cls.__name__: cls.scene_file.description for cls in FAMILIES}
COMPLIANCE_WORDS = {cls.__name__: cls.scene_file.description for cls in COMPLIANCE_MODELS}
#: Where a contact kind's edge strikes (`summary`).
CONTACT_WORDS = {
    "flank": "flank on flank", "gear_tip_edge": "the gear's tip edge on the pinion flank",
    "pinion_tip_edge": "the pinion's tip edge on the gear flank",
}


def _impacts(out: dict) -> list[dict]:
    """The impact entries of `result_dict`'s output: none, one, or one per contact zone."""
    if "impact" not in out:
        return []
    return out["impact"].get("zones", [out["impact"]])


def family_words(family: str, helix_angle_deg: float | None = None) -> str:
    """A family (class name) in an engineer's words; an involute pair with no helix angle
    is a spur pair."""
    if family == "InvoluteGearPair" and helix_angle_deg == 0.0:
        return "involute spur gear pair"
    return FAMILY_WORDS.get(family, family)


def _family_words(g: dict) -> str:
    return family_words(g["family"], g.get("helix_angle_deg"))


def summary(out: dict) -> str:
    """Readable multi-line summary of `result_dict` output, in an engineer's words: units on
    every number, a zero said to be one by construction, the sign convention of the TE."""
    g, t = out["geometry"], out["tca"]
    lines = [f"gearjax — {_family_words(g)}, z = {g['teeth'][0]}/{g['teeth'][1]}"]
    if "working_pressure_angle_deg" in g:
        lines += [
            f"  m_n {g['normal_module_mm']:.4g} mm, beta {g['helix_angle_deg']:.4g} deg, b {g['face_width_mm']:.4g} mm",
            f"  centre distance            a        = {g['center_distance_mm']:.3f} mm",
            f"  working pressure angle     alpha_wt = {g['working_pressure_angle_deg']:.3f} deg",
            f"  base radii                 r_b      = {g['base_radius_mm'][0]:.3f} / {g['base_radius_mm'][1]:.3f} mm",
            f"  transverse base pitch      p_bt     = {g['transverse_base_pitch_mm']:.3f} mm",
            f"  contact ratios             eps_a    = {g['transverse_contact_ratio']:.3f}, eps_b = {g['overlap_ratio']:.3f}",
        ]
    method = "on the plane of action" if t["method"] == "plane_of_action" else "on the flank surfaces"
    te_line = f"  TE peak-to-peak            = {t['te_peak_to_peak_urad']:.3f} µrad = {t['te_peak_to_peak_um']:.4f} µm (line of action)"
    if abs(t["te_peak_to_peak_urad"]) < 1e-3:  # zero to the contact solves' tolerance
        te_line += ": none, some pair touches on unmodified (conjugate) flanks at every position"
    lines += [
        f"Unloaded TCA ({method}, {t['positions']} positions, tooth pairs {t['pairs']})",
        te_line,
        f"  TE mean                    = {t['te_mean_um']:.4f} µm (negative: the gear behind its rigid position)",
        f"  edge contacts              = {t['edge_contact_positions']} of {t['positions']} positions",
    ]
    if t["unconverged_solves"]:
        lines.append(f"  warning: {t['unconverged_solves']} contact solves did not converge (raise newton_max_steps)")
    if "ltca" in out:
        lt = out["ltca"]
        lines += [
            f"Loaded TCA ({lt['torque_Nm']:.6g} N·m, normal load {lt['normal_load_N']:.6g} N; "
            f"{COMPLIANCE_WORDS.get(lt['compliance'], lt['compliance'])})",
            f"  LTE peak-to-peak           = {lt['lte_peak_to_peak_um']:.4f} µm, mean {lt['lte_mean_um']:.3f} µm "
            "(negative: the gear behind its rigid position)",
            f"  mean mesh stiffness        = {lt['mean_mesh_stiffness_N_per_mm_um']:.3f} N/(mm µm) per face width",
            f"  max load share             = {lt['max_load_share']:.3f}, max Hertz pressure {lt['max_pressure_MPa']:.0f} MPa",
        ]
        if "contact_ellipse_semi_axes_mm" in lt:
            a, b = lt["contact_ellipse_semi_axes_mm"]
            lines.append(f"  contact ellipse            = {a:.3f} × {b:.3f} mm semi-axes under the largest pair load, "
                         f"{lt['max_pair_load_N']:.0f} N")
        if lt["result"] != "successful":
            lines.append(f"  warning: {enum_message(getattr(RESULTS, lt['result']))}")
    for im in _impacts(out):
        zone = f", {im['zone']}" if "zone" in im else ""
        parameter = "profile parameter" if "zone" in im else "roll length"  # involute flanks: roll lengths
        lines += [
            f"Mesh-in impact{zone} ({im['regime']} strike: {CONTACT_WORDS.get(im['contact_kind'], im['contact_kind'])})",
            f"  impact force               F_s = {im['force_N']:.0f} N, normal velocity v_n = {im['velocity_mm_per_s']:.1f} mm/s",
            f"  local stiffness            F = {im['stiffness_coefficient_N_per_mm_n']:.4g} delta^{im['stiffness_exponent']:.3f} (N, mm)",
            f"  point M                    pinion {parameter} {im['pinion_roll_length_mm']:.3f} mm at z = {im['face_position_mm']:.2f} mm; "
            f"m_eq = {im['equivalent_mass_kg']:.3f} kg",
        ]
        if im["result"] != "successful":
            lines.append(f"  warning: {enum_message(getattr(RESULTS, im['result']))}")
    for note in out.get("notes", []):
        lines.append(f"Note: {note}")
    return "\n".join(lines)
