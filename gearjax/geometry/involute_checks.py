"""Physical feasibility checks of involute pairs (concrete values only): undercut, pointed
tips, centre distance consistency, tip clearance, interference and contact ratio. Each
failure is a `ValueError` naming the parameter to change and its allowed range."""

from __future__ import annotations

import math

import numpy as np


def check_feasible(pair, center_distance) -> None:
    """Physical feasibility of the pair (concrete values only): undercut, pointed tips,
    interference, tip clearance, contact ratio and centre distance consistency."""
    z1, z2 = pair.teeth
    s_form = np.asarray(pair.form_roll_length)
    for i, name in enumerate(("pinion", "gear")):
        if np.any(s_form[..., i] < 0):
            x_min = _min_shift_without_undercut(pair, i)
            raise ValueError(
                f"profile_shift[{i}] gives an undercut {name} (z={pair.teeth[i]}): the involute "
                f"would start below the base circle; profile_shift[{i}] must be >= {x_min:.4f}"
            )
    tip = np.asarray(pair.tip_thickness)
    for i, name in enumerate(("pinion", "gear")):
        if np.any(tip[..., i] <= 0.0):
            raise ValueError(
                f"profile_shift[{i}] / addendum_coefficient give a pointed {name} tip "
                f"(tip thickness {np.min(tip[..., i]):.4f} mm); tip thickness must be > 0 mm"
            )
    if center_distance is not None:
        a = np.asarray(pair.center_distance)
        given = np.asarray(center_distance, dtype=float)
        if np.any(np.abs(given - a) > 1e-6 * np.maximum(1.0, a)):
            alpha_t = np.asarray(pair.transverse_pressure_angle)
            a0 = np.asarray(pair.reference_center_distance)
            ratio = a0 * np.cos(alpha_t) / given
            if np.all(np.abs(ratio) < 1):
                alpha_w = np.arccos(ratio)
                needed = (
                    (np.tan(alpha_w) - alpha_w - (np.tan(alpha_t) - alpha_t))
                    * (z1 + z2)
                    / (2 * np.tan(np.asarray(pair.normal_pressure_angle)))
                )
                hint = f"; center_distance={_fmt(given)} mm would need x1 + x2 = {_fmt(needed)}"
            else:
                hint = (
                    f"; center_distance={_fmt(given)} mm is not reachable by any profile shift "
                    f"(it is at most a0*cos(alpha_t) = {_fmt(a0 * np.cos(alpha_t))} mm)"
                )
            shifts = np.asarray(pair.profile_shift)
            raise ValueError(
                f"center_distance={_fmt(given)} mm is inconsistent with profile_shift "
                f"x1 + x2 = {_fmt(shifts[..., 0] + shifts[..., 1])}, which gives a = {_fmt(a)} mm "
                f"(zero backlash){hint}; omit center_distance to derive it"
            )
    a = np.asarray(pair.center_distance)
    clearance = a[..., None] - np.asarray(pair.tip_radius) - np.asarray(pair.root_radius)[..., ::-1]
    if np.any(clearance < 0.0):
        raise ValueError(
            "addendum_coefficient / dedendum_coefficient leave no tip clearance: a tip circle "
            f"cuts the mating root circle (clearance {np.min(clearance):.4f} mm must be >= 0 mm)"
        )
    s_start = np.asarray(pair.start_of_active_profile)
    for i, name in enumerate(("pinion", "gear")):
        if np.any(s_start[..., i] < s_form[..., i] - 1e-9):
            raise ValueError(
                f"profile_shift / addendum_coefficient cause tip interference: the "
                f"{('gear', 'pinion')[i]} tip reaches below the {name}'s involute (start of "
                f"active profile {np.min(s_start[..., i]):.4f} mm < form roll length "
                f"{np.min(s_form[..., i]):.4f} mm, as roll lengths)"
            )
    eps = np.asarray(pair.total_contact_ratio)
    eps_a = np.asarray(pair.transverse_contact_ratio)
    if np.any(eps < 1.0) or np.any(eps_a <= 0.0):
        raise ValueError(
            "the pair's total contact ratio eps_alpha + eps_beta = "
            f"{np.min(eps):.4f} must be >= 1 (eps_alpha = {np.min(eps_a):.4f}); increase "
            "face_width, helix_angle_deg or addendum_coefficient"
        )


def _min_shift_without_undercut(pair, gear: int) -> float:
    alpha_t = float(np.asarray(pair.transverse_pressure_angle).ravel()[0])
    alpha_n = float(np.asarray(pair.normal_pressure_angle).ravel()[0])
    mn = float(np.asarray(pair.normal_module).ravel()[0])
    rb = float(np.asarray(pair.base_radius)[..., gear].ravel()[0])
    hf = float(np.asarray(pair.dedendum_coefficient)[..., gear].ravel()[0])
    rho = float(np.asarray(pair.root_radius_coefficient)[..., gear].ravel()[0])
    return hf - rho * (1 - math.sin(alpha_n)) - rb * math.tan(alpha_t) * math.sin(alpha_t) / mn


def _fmt(value: np.ndarray) -> str:
    flat = np.ravel(value)
    return f"{flat[0]:.4f}" if flat.size == 1 else "[" + ", ".join(f"{v:.4f}" for v in flat[:4]) + "]"

