"""How well the point-contact LTCA locates each contact between the face slices, on the
double-circular-arc seed pair's rigid TCA (`gearjax.ltca.point_analysis.closest_contact`).

    python benchmarks/studies/dca_peak_location.py [--slices 21 41 81] [--reference 321]

Runs the rigid TCA on a fine grid of pinion angles (0.01° over the seed pair's strike
windows at 25-200 N·m, -8.4..-6.2° and 4.6..6.4°) with S face slices, locates every pair's
point contact and compares its rigid TE, and that TE's slope along the pinion angle, with
those located on `--reference` slices. The slope is what enters the mesh-in impact's normal
velocity (through the loaded TE of the pairs in mesh), so its error is the one that
matters: a slope error of 1 µrad/deg moves the seed pair's strike velocity by about
0.06 mm/s at 200 rpm. Slopes are differences that do not straddle a change of the two
slices the contact is interpolated between (as the impact's forward-mode derivative sees
them). Contacts within 5 µrad of the largest located peak (the pairs in mesh at light
load), split by their distance d from the nearer face end in slice spacings h = b/S.
Prints one JSON line per slice count.
"""

from __future__ import annotations

import argparse
import json
import time
import tomllib

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from gearjax.io.scene_file import scene_from_dict  # noqa: E402
from gearjax.ltca.point_analysis import closest_contact  # noqa: E402
from gearjax.papers.double_arc import seed_scene_file  # noqa: E402
from gearjax.pipeline import prepare  # noqa: E402
from gearjax.tca import tooth_contact_analysis  # noqa: E402

STEP_DEG = 0.01
WINDOWS_DEG = ((-8.4, -6.2), (4.6, 6.4))
NEAR_TOP_RAD = 5e-6


def located(slices: int, angles_deg: np.ndarray, window: np.ndarray) -> dict[str, np.ndarray]:
    """`closest_contact` of the seed pair's rigid TCA at `slices` face slices and the given
    pinion angles, pairs (-1, 0, 1) of both zones; `key` names the two slices a contact is
    interpolated between, with the angle's `window` (-1 out of mesh)."""
    text = seed_scene_file(analysis={"positions_per_pitch": 32, "face_slices": slices})
    scene = prepare(scene_from_dict(tomllib.loads(text)))
    pair = scene.pair.resolve()
    tca = jax.jit(lambda p: tooth_contact_analysis(pair, scene.depth, accuracy=scene.accuracy, pairs=(-1, 0, 1),
                                                   pinion_angles=p))(jnp.radians(jnp.asarray(angles_deg)))
    contact = closest_contact(tca)
    start, other = (np.asarray(x) for x in contact["between"][:2])
    return {"te": np.asarray(contact["te"]), "gap": np.asarray(contact["gap"]), "z": np.asarray(contact["z"]),
            "key": np.where(np.isfinite(contact["gap"]), (window[:, None] * 1000 + start) * 1000 + other, -1),
            "face_width": float(pair.face_width)}


def slopes(te: np.ndarray, key: np.ndarray, step: float) -> np.ndarray:
    """d te / d angle (per unit of `step`) along axis 0, by differences within runs of the
    same `key`: central inside a run, one-sided at its ends, NaN for a run of one."""
    forward = np.where(key[1:] == key[:-1], (te[1:] - te[:-1]) / step, np.nan)
    pad = np.full((1,) + te.shape[1:], np.nan)
    ahead, behind = np.concatenate([forward, pad]), np.concatenate([pad, forward])
    return np.where(np.isnan(ahead), behind, np.where(np.isnan(behind), ahead, 0.5 * (ahead + behind)))


def errors(run: dict, reference: dict, slices: int) -> dict:
    """TE and slope errors of `run` against `reference`, for the in-mesh contacts, split by
    the distance from the nearer face end (µrad, µrad/deg)."""
    micro = 1e6
    in_mesh = np.isfinite(reference["gap"])
    top = np.max(np.where(in_mesh, reference["te"], -np.inf), axis=-1, keepdims=True)
    near_top = in_mesh & (reference["te"] > top - NEAR_TOP_RAD) & np.isfinite(run["gap"])
    slope_run = slopes(run["te"], run["key"], STEP_DEG)
    slope_ref = slopes(reference["te"], reference["key"], STEP_DEG)
    spacing = run["face_width"] / slices
    distance = (0.5 * run["face_width"] - np.abs(reference["z"])) / spacing
    out = {"slices": slices, "spacing_mm": round(spacing, 3)}
    for name, where in (("within_h_of_an_end", distance < 1.0), ("mid_face", distance >= 1.0)):
        ok = near_top & where & np.isfinite(slope_run) & np.isfinite(slope_ref)
        d_te = np.abs(run["te"] - reference["te"])[ok] * micro
        d_slope = np.abs(slope_run - slope_ref)[ok] * micro
        out[name] = {"contacts": int(ok.sum()), "te_error_max_urad": round(float(d_te.max(initial=0.0)), 3),
                     "slope_error_rms_urad_per_deg": round(float(np.sqrt(np.mean(d_slope**2))) if d_slope.size else 0.0, 3),
                     "slope_error_max_urad_per_deg": round(float(d_slope.max(initial=0.0)), 3)}
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slices", type=int, nargs="+", default=[21, 41, 81])
    parser.add_argument("--reference", type=int, default=321)
    args = parser.parse_args(argv)
    grids = [np.arange(lo, hi + 1e-9, STEP_DEG) for lo, hi in WINDOWS_DEG]
    angles = np.concatenate(grids)
    window = np.concatenate([np.full(g.size, i) for i, g in enumerate(grids)])
    start = time.perf_counter()
    reference = located(args.reference, angles, window)
    for slices in args.slices:
        line = errors(located(slices, angles, window), reference, slices)
        line["reference_slices"] = args.reference
        line["elapsed_s"] = round(time.perf_counter() - start, 1)
        print(json.dumps(line), flush=True)


if __name__ == "__main__":
    main()
