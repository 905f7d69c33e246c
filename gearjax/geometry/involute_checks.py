"""The involute section's inputs: its scene-file keys, the range of each parameter, and the
physical feasibility of a pair (concrete values only): undercut, pointed tips, centre
distance consistency, tip clearance, interference and contact ratio. Each failure is a
`ValueError` naming the parameter to change and its allowed range."""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from .._custom_types import Array, ArrayLike, Float
from .._numerics import as_float
from .._validate import check_int, check_range

#: Scene-file keys of the involute section (`SceneFileSpec.keys`) that the involute
#: families share: (constructor keyword, kind, unit in the file, factor to engine units).
SECTION_SCENE_KEYS = {
    "teeth": ("teeth", "teeth", "", 1.0),
    "normal_module": ("normal_module", "number", "mm", 1.0),
    "pressure_angle_deg": ("pressure_angle_deg", "number", "deg", 1.0),
    "face_width": ("face_width", "number", "mm", 1.0),
    "center_distance": ("center_distance", "number", "mm", 1.0),
    "profile_shift": ("profile_shift", "number_or_pair", "", 1.0),
    "addendum_coefficient": ("addendum_coefficient", "number_or_pair", "", 1.0),
    "dedendum_coefficient": ("dedendum_coefficient", "number_or_pair", "", 1.0),
    "root_radius_coefficient": ("root_radius_coefficient", "number_or_pair", "", 1.0),
}



def check_section_inputs(
    teeth,
    normal_module,
    pressure_angle_deg,
    helix_angle_deg,
    face_width,
    profile_shift,
    addendum_coefficient,
    dedendum_coefficient,
    root_radius_coefficient,
) -> tuple[int, int]:
    """Range checks of the section's parameters (units as in the families' constructors);
    returns the validated $(z_1, z_2)$."""
    if not isinstance(teeth, (tuple, list)) or len(teeth) != 2:
        raise ValueError(f"teeth must be a pair (z1, z2) of integers >= 5; got {teeth!r}")
    z1 = check_int("teeth[0] (pinion)", teeth[0], 5, 2000)
    z2 = check_int("teeth[1] (gear)", teeth[1], 5, 2000)
    check_range("normal_module", normal_module, 0.01, 100.0, unit="mm")
    check_range("pressure_angle_deg", pressure_angle_deg, 10.0, 35.0, unit="deg")
    check_range("helix_angle_deg", helix_angle_deg, 0.0, 45.0, high_inclusive=False, unit="deg")
    check_range("face_width", face_width, 0.0, None, low_inclusive=False, unit="mm")
    check_range("profile_shift", profile_shift, -1.0, 1.5)
    check_range("addendum_coefficient", addendum_coefficient, 0.3, 1.6)
    check_range("dedendum_coefficient", dedendum_coefficient, 0.5, 2.0)
    check_range("root_radius_coefficient", root_radius_coefficient, 0.0, 0.6)
    return z1, z2


def per_gear(value: ArrayLike) -> Float[Array, "2"]:
    """`value` as a per-gear pair (..., 2): a scalar (or a batch of them) is used for both."""
    arr = as_float(value)
    if arr.ndim == 0 or arr.shape[-1] != 2:
        arr = jnp.stack([arr, arr], axis=-1)
    return arr


def check_feasible(pair, center_distance) -> None:
    """Physical feasibility of the pair (concrete values only): undercut, pointed tips,
    interference, tip clearance, contact ratio and centre distance consistency."""
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
        _check_center_distance(pair, center_distance)
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


def _check_center_distance(pair, center_distance) -> None:
    """A given centre distance must be the zero-backlash one of the profile shifts; the
    error says which $x_1 + x_2$ the given value would need, if any."""
    z1, z2 = pair.teeth
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

