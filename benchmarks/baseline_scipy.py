"""Plain NumPy/SciPy baselines of the involute problems gearjax solves, timed in one process.

    python benchmarks/baseline_scipy.py [--repeats 5] [--quick] [--growth]
                                        [--problems tca ltca_iso ltca_slice ltca_palmgren]

The scene is the built-in default one (`gearjax.io.scene_file.default_scene()`: seed 001's
29/71 helical pair with the paper's optimal modification); every problem uses the
plane-of-action TCA (`Accuracy(tca_method="plane_of_action")`). Each baseline solves the
same discrete problem as gearjax, and its results are checked against gearjax's before
anything is reported (an `AssertionError` otherwise):

1. `tca`: unloaded TE of 100 random designs (seed 001 bounds: y1, y2, y5 in
   [0.001, 0.015] m_n, y3, y4 in [0.1, 0.8] m_n, y6 in [0, 0.5 b)), 64 positions, 64 face
   slices. gearjax: `gj.simulate_designs(scene, modifications, outputs=TE)` (rigid scene:
   TCA only; the pair resolved once, the TE alone returned), and for comparison
   `jax.vmap(gj.simulate)` over `gj.stack_scenes(scenes)`, with the whole result and with
   the TE alone. Baseline: the same plane-of-action TE vectorised in NumPy
   over (design, position, pair, slice): the slice offset is minus the pinion flank's
   depth at the conjugate point (`FlankModification` formulas, transverse, over r_b2), TE
   the largest offset over pairs and slices, the midpoint maximum refined between slices
   by the same one Newton step on g'(z) = 0 as `gearjax/tca/peak.py` (closed-form
   derivatives of the parabolic reliefs and crowning).
2. `ltca_iso`: uniform-stiffness LTCA (`IsoCompliance`), 64 slices, 32 positions x 64
   torques. gearjax: `gj.load_sweep`. Baseline: per position and torque,
   $F_i = \\max(0, (q_i\\Theta - e_i)/c_i)$, $\\sum p_iF_i = T$, solved for $\\Theta$ by
   `scipy.optimize.brentq`.
3. `ltca_slice`: face-coupled LTCA (`SliceCompliance(hertz="linear")`, so the contact
   problem is a linear complementarity problem), 41 slices (5 pairs x 41 = 205 points),
   32 positions, 1 torque and 64 torques. gearjax: `gj.load_sweep`. Baseline: a dense
   active-set (principal pivoting) solve per position and torque of
   $y = CF + e - q\\Theta \\ge 0$, $F \\ge 0$, $F\\cdot y = 0$, $\\sum pF = T$
   (`scipy.linalg.solve` of the bordered system of the active set; one pivot at a time,
   warm-started from the previous torque, or from the previous position for its first).

4. `ltca_palmgren`: the same with Palmgren's contact law (`SliceCompliance()`, the
   default): $y = CF + aF^{0.9} + e - q\\Theta$, a nonlinear complementarity problem.
   Baseline: the same pivots, Newton's method on the bordered system of each active set,
   warm-started from the previous solve's loads.

The baselines' inputs (separations $e_i$, compliances $C$ or $c_i$, arms $p_i$, $q_i$) are
taken from gearjax's TCA and compliance model as NumPy arrays once, outside the timed
region, so both sides solve the identical problem; the gearjax time includes its TCA and
compliance, which makes the ratio conservative. The gearjax programs return only the
quantities the baselines compute (TE; loaded TE and loads), so XLA prunes the rest
(e.g. the LTCA's mesh-stiffness rates).

Reported per problem: baseline median, gearjax median (steady state, after a warm-up,
`block_until_ready`), gearjax compile time apart, ratio baseline / gearjax. `--growth`
adds the cost of problem 3 (one torque) against the number of points (11, 21, 41, 81
slices; points = 5 x slices) and fits the exponent of time ~ points^k on both sides.
Results: benchmarks/results/baseline_scipy.json, written after every case
(baseline_scipy_quick.json with `--quick`, whose sizes are a smoke test, not a measurement).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import NamedTuple

import equinox as eqx
import jax
import numpy as np
import scipy
import scipy.linalg
import scipy.optimize

import gearjax as gj  # before the first computation: it sets an XLA flag for the CPU backend

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import first_and_runs, machine, time_compiled_output, time_host, write  # noqa: E402
from tca import random_designs  # noqa: E402

from gearjax.io.scene_file import default_scene  # noqa: E402

#: Sizes of the full run and of `--quick` (a smoke test, not a measurement).
FULL = {
    "tca": {"designs": 100, "positions": 64, "slices": 64},
    "ltca_iso": {"positions": 32, "slices": 64, "loads": 64},
    "ltca_slice": {"positions": 32, "slices": 41, "loads": [1, 64]},
    "growth": {"positions": 32, "slices": [11, 21, 41, 81]},
}
QUICK = {
    "tca": {"designs": 8, "positions": 16, "slices": 16},
    "ltca_iso": {"positions": 8, "slices": 16, "loads": 4},
    "ltca_slice": {"positions": 8, "slices": 11, "loads": [1, 4]},
    "growth": {"positions": 8, "slices": [5, 11]},
}
#: Torques of the load sweeps (N·mm): 100 to 2000 N·m, as in benchmarks/ltca.py; the
#: single-torque rows use the default scene's 1000 N·m.
TORQUE_RANGE = (1.0e5, 2.0e6)
DESIGN_TORQUE = 1.0e6

#: Agreement asserted between baseline and gearjax (see `check`), on the cycle mean and
#: peak-to-peak of the (loaded) TE and on the curves themselves: `rtol` relative plus
#: `atol_um` absolute (µm along the line of action). The unloaded TE is the same
#: arithmetic on both sides and is about zero for these designs (an unmodified patch is
#: always in contact), hence absolute; gearjax's contact solve is smoothed
#: (`Accuracy.contact_smoothing`, 1e-6), the baselines are exact.
TOLERANCES = {
    "tca": {"rtol": 0.0, "atol_um": 1e-9},
    "ltca_iso": {"rtol": 1e-6, "atol_um": 1e-6},
    "ltca_slice": {"rtol": 1e-6, "atol_um": 1e-6},
    "ltca_palmgren": {"rtol": 1e-6, "atol_um": 1e-6},
}


# --------------------------------------------------------------------------- scenes
def base_scene():
    """The default scene (seed 001 pair, paper optimum)."""
    scene, _ = default_scene()
    return scene


def accuracy(positions: int, slices: int) -> gj.Accuracy:
    return gj.Accuracy(positions_per_pitch=positions, face_slices=slices, tca_method="plane_of_action")


def rigid_scene(pair, modification, acc, pairs=None) -> gj.Scene:
    """TCA only: no torque, no effects."""
    return gj.Scene(pair, modification, accuracy=acc, pairs=pairs)


def loaded_scene(pair, modification, acc, compliance) -> gj.Scene:
    return gj.Scene(
        pair, modification, accuracy=acc, compliance=compliance,
        operating=gj.OperatingPoint(torque=DESIGN_TORQUE),
    )


# --------------------------------------------------------------------------- geometry
class Involute(NamedTuple):
    """The constants of the plane-of-action problem (floats, mm and rad), read once from
    the resolved gearjax pair (ISO 21771 quantities; `gearjax/geometry/involute_section.py`)."""

    teeth: tuple[int, int]
    hand: int
    face_width: float
    base_radius: tuple[float, float]
    tan_working_pressure_angle: float
    line_of_action_length: float
    form_roll_length: tuple[float, float]
    tip_roll_length: tuple[float, float]
    start_of_active_profile: tuple[float, float]
    tan_base_helix: float
    cos_base_helix: float
    center_distance: float


def involute_constants(pair) -> Involute:
    p = pair.resolve()

    def two(x):
        x = np.asarray(x, dtype=float)
        return float(x[0]), float(x[1])

    return Involute(
        teeth=tuple(p.teeth), hand=int(p.hand), face_width=float(p.face_width),
        base_radius=two(p.base_radius),
        tan_working_pressure_angle=float(np.tan(float(p.working_pressure_angle))),
        line_of_action_length=float(p.line_of_action_length),
        form_roll_length=two(p.form_roll_length), tip_roll_length=two(p.tip_roll_length),
        start_of_active_profile=two(p.start_of_active_profile),
        tan_base_helix=float(np.tan(float(p.base_helix_angle))),
        cos_base_helix=float(np.cos(float(p.base_helix_angle))),
        center_distance=float(p.center_distance),
    )


def positions(geo: Involute, n: int) -> np.ndarray:
    """Pinion angles (rad): n per angular pitch, centred on 0 (`gearjax/tca/grid.py`)."""
    pitch = 2 * np.pi / geo.teeth[0]
    return -0.5 * pitch + pitch / n * np.arange(n)


def slice_positions(geo: Involute, n: int) -> np.ndarray:
    """Slice midpoints, then the two face ends (mm)."""
    b = geo.face_width
    return np.concatenate([b * ((np.arange(n) + 0.5) / n - 0.5), [-0.5 * b, 0.5 * b]])


# --------------------------------------------------------------------------- 1. TCA
def _relief_terms(y, s, w, geo: Involute):
    """Depth of seed 001's modification (mm) and its first and second derivatives with
    respect to roll length `s` and axial `w` (`gearjax/geometry/modification.py`)."""
    y1, y2, y3, y4, y5, y6 = y
    tip_start = geo.tip_roll_length[0] - y4
    root_end = geo.start_of_active_profile[0] + y3
    half_free = 0.5 * y6
    half_crowned = 0.5 * (geo.face_width - y6)
    tip = np.maximum(s - tip_start, 0.0)
    root = np.maximum(root_end - s, 0.0)
    crown = np.maximum(np.abs(w) - half_free, 0.0)
    depth = y2 * np.square(tip / y4) + y1 * np.square(root / y3) + y5 * np.square(crown / half_crowned)
    d_s = 2 * y2 * tip / y4**2 - 2 * y1 * root / y3**2
    d_ss = 2 * y2 / y4**2 * (tip > 0) + 2 * y1 / y3**2 * (root > 0)
    d_w = 2 * y5 * crown / half_crowned**2 * np.sign(w)
    d_ww = 2 * y5 / half_crowned**2 * (crown > 0)
    return depth, d_s, d_ss, d_w, d_ww


def te_numpy(geo: Involute, designs: np.ndarray, n_positions: int, n_slices: int, pairs, slices: bool = False):
    """Plane-of-action TE (rad, gear 2) of every design, (design, position): NumPy,
    vectorised over (design, position, pair, slice). With `slices`, also the TE at which
    each slice touches, (design, position, pair, slice), -inf off the active flanks."""
    rb1, rb2 = geo.base_radius
    ratio = geo.teeth[1] / geo.teeth[0]
    pitch = 2 * np.pi / geo.teeth[0]
    phi = positions(geo, n_positions)[None, :, None, None]
    k = np.asarray(pairs, dtype=float)[None, None, :, None]
    z = slice_positions(geo, n_slices)[None, None, None, :]
    y = tuple(designs[:, i, None, None, None] for i in range(6))
    lead1 = geo.hand * z * geo.tan_base_helix / rb1
    lead2 = geo.hand * z * geo.tan_base_helix / rb2
    # conjugate contact on the plane of action, and whether it is on both active flanks
    s1 = rb1 * (geo.tan_working_pressure_angle + (phi - k * pitch + lead1))
    s2 = geo.line_of_action_length - s1
    ok = ((s1 >= geo.form_roll_length[0]) & (s1 <= geo.tip_roll_length[0])
          & (s2 >= geo.form_roll_length[1]) & (s2 <= geo.tip_roll_length[1]))
    depth = _relief_terms(y, s1, z, geo)[0]
    slice_te = np.where(ok, -(depth / geo.cos_base_helix) / rb2 + (lead1 / ratio - lead2), -np.inf)
    mid = slice_te[..., :n_slices]
    best = np.argmax(mid, axis=-1)
    te_mid = np.take_along_axis(mid, best[..., None], -1)[..., 0]
    found = np.isfinite(te_mid)
    if n_slices >= 3:
        # one Newton step on g'(z) = 0 from the best midpoint (gearjax/tca/peak.py)
        zb = slice_positions(geo, n_slices)[best]
        s_b = np.take_along_axis(np.broadcast_to(s1[..., :n_slices], mid.shape), best[..., None], -1)[..., 0]
        yb = tuple(np.broadcast_to(v[..., 0], s_b.shape) for v in y)
        _, d_s, d_ss, d_w, d_ww = _relief_terms(yb, s_b, zb, geo)
        rate = geo.hand * geo.tan_base_helix  # ds1/dz; ds2/dz = -rate
        scale = -1.0 / (geo.cos_base_helix * rb2)
        d1 = scale * (d_s * rate + d_w) + geo.hand * geo.tan_base_helix * (1 / (rb1 * ratio) - 1 / rb2)
        d2 = scale * (d_ss * rate**2 + d_ww)
        low, high = _room(s_b, geo.line_of_action_length - s_b, rate, geo, 0.5 * geo.face_width / n_slices)
        te_mid = te_mid + np.where(found, _newton_rise(d1, d2, low, high), 0.0)
    te_ends = np.max(slice_te[..., n_slices:], axis=-1)
    te = np.max(np.maximum(te_mid, te_ends), axis=-1)
    return (te, slice_te) if slices else te


def _room(s1, s2, rate, geo: Involute, half_width):
    """Largest steps (down, up) in z before a contact parameter leaves the active flanks."""
    lo1, lo2 = geo.form_roll_length
    hi1, hi2 = geo.tip_roll_length
    with np.errstate(divide="ignore", invalid="ignore"):
        if rate > 0:
            up = np.minimum((hi1 - s1) / rate, (lo2 - s2) / -rate)
            down = np.minimum((s1 - lo1) / rate, (s2 - hi2) / -rate)
        elif rate < 0:
            up = np.minimum((lo1 - s1) / rate, (hi2 - s2) / -rate)
            down = np.minimum((s1 - hi1) / rate, (s2 - lo2) / -rate)
        else:
            up = down = np.full_like(s1, np.inf)
    return np.clip(down, 0.0, half_width), np.clip(up, 0.0, half_width)


def _newton_rise(d1, d2, low, high):
    concave = d2 < 0
    with np.errstate(divide="ignore", invalid="ignore"):
        step = np.clip(-d1 / np.where(concave, d2, -1.0), -low, high)
        rise = d1 * step + 0.5 * d2 * step**2
    return np.where(concave & np.isfinite(rise), np.maximum(rise, 0.0), 0.0)


# --------------------------------------------------------------------------- LTCA inputs
class ContactInputs(NamedTuple):
    """One scene's contact problems as NumPy arrays, valid points only per position."""

    te: np.ndarray  # (pos,) unloaded TE (rad)
    index: list  # per position: flat indices (pair x slice) of the valid points
    separation: list  # per position: e_i (mm)
    compliance: list  # per position: C (n, n) (mm/N)
    pinion_arm: list  # per position: p_i (mm)
    gear_arm: list  # per position: q_i (mm)
    shape: tuple  # (pos, pair, slice)
    nonlinear: list  # per position: a_i of the approach a_i F_i^e (mm/N^e; zeros for a linear law)
    exponent: float  # e (1 for a linear law)


def contact_inputs(scene: gj.Scene, tca) -> ContactInputs:
    """Separations, compliance matrices and moment arms of every position of `scene`,
    from gearjax's TCA result and compliance model (the call of
    `gearjax/ltca/analysis.py`; every slice weight is 1 with `extended_contact`)."""
    if not scene.extended_contact:
        raise ValueError("the baselines assume extended_contact=True (unit slice weights)")
    n_mid = scene.accuracy.face_slices
    valid = np.asarray(tca.valid)[..., :n_mid]
    model = scene.contact_model

    @eqx.filter_jit
    def matrices(pair, tca):
        points = model.compliance(pair, model.material, model.hub_radius, tca, n_mid,
                                  model.accuracy.quadrature_points, jax.numpy.ones(valid.shape))
        return points.matrix, points.nonlinear, points.exponent

    matrix, nonlinear, exponent = matrices(scene.pair.resolve(), tca)
    matrix, nonlinear = np.asarray(matrix), np.asarray(nonlinear)
    x = np.asarray(tca.pinion_point)[..., :n_mid, :]
    n = np.asarray(tca.normal)[..., :n_mid, :]
    # moment arms: p = (x x n)_z, q = -((x - O2) x n)_z
    p = x[..., 0] * n[..., 1] - x[..., 1] * n[..., 0]
    q = -((x[..., 0] - np.asarray(scene.pair.center_distance)) * n[..., 1] - x[..., 1] * n[..., 0])
    e = np.asarray(tca.separation)[..., :n_mid]
    n_pos = valid.shape[0]
    out = {key: [] for key in ("index", "separation", "compliance", "pinion_arm", "gear_arm", "nonlinear")}
    for i in range(n_pos):
        idx = np.flatnonzero(valid[i].ravel())
        out["index"].append(idx)
        out["separation"].append(e[i].ravel()[idx])
        out["compliance"].append(np.ascontiguousarray(matrix[i][np.ix_(idx, idx)]))
        out["pinion_arm"].append(p[i].ravel()[idx])
        out["gear_arm"].append(q[i].ravel()[idx])
        out["nonlinear"].append(nonlinear[i].ravel()[idx])
    return ContactInputs(te=np.asarray(tca.transmission_error), shape=valid.shape, exponent=float(exponent), **out)


# --------------------------------------------------------------------------- 2. iso LTCA
def iso_numpy(data: ContactInputs, torques: np.ndarray):
    """Θ (rad), (load, pos), of the uncoupled problem by `brentq` per position and torque."""
    rotation = np.empty((len(torques), len(data.te)))
    for i in range(len(data.te)):
        c = np.diag(data.compliance[i])
        e, p, q = data.separation[i], data.pinion_arm[i], data.gear_arm[i]
        slope, offset = q / c, e / c  # F = max(0, slope Θ - offset)
        lowest = np.min(e / q)
        total_slope, total_offset = p @ slope, p @ offset
        for j, torque in enumerate(torques):
            # below `lowest` nothing is loaded; at `high` even the linear extension (all
            # points loaded, some negatively) carries the torque (widened against rounding)
            high = max((torque + total_offset) / total_slope, lowest) * (1 + 1e-9)
            rotation[j, i] = scipy.optimize.brentq(
                _iso_residual, lowest, high, args=(p, slope, offset, torque), xtol=1e-300, rtol=4e-15
            )
    return rotation


def _iso_residual(theta, p, slope, offset, torque):
    return p @ np.maximum(slope * theta - offset, 0.0) - torque


# --------------------------------------------------------------------------- 3. slice LTCA
def lcp_active_set(C, e, p, q, torque, active, max_pivots):
    """Exact solution of $y = CF + e - q\\Theta \\ge 0$, $F \\ge 0$, $F\\cdot y = 0$,
    $p\\cdot F = T$ by principal pivoting on the active set: solve the bordered system of
    the active points, drop the most negative load, else add the most violated gap, one
    pivot at a time. Returns (F, Θ, active set, pivots)."""
    active = active.copy()
    load_tol = 1e-12 * torque / np.mean(p)
    gap_tol = 1e-12  # mm
    for pivots in range(max_pivots):
        if not active.any():
            active[np.argmin(e / q)] = True
        idx = np.flatnonzero(active)
        m = idx.size
        system = np.empty((m + 1, m + 1))
        system[:m, :m] = C[np.ix_(idx, idx)]
        system[:m, m] = -q[idx]
        system[m, :m] = p[idx]
        system[m, m] = 0.0
        rhs = np.concatenate([-e[idx], [torque]])
        x = scipy.linalg.solve(system, rhs, check_finite=False)
        loads, theta = x[:m], x[m]
        worst = np.argmin(loads)
        if loads[worst] < -load_tol:
            active[idx[worst]] = False
            continue
        F = np.zeros_like(e)
        F[idx] = loads
        gaps = C @ F + e - q * theta
        gaps[active] = np.inf
        worst = np.argmin(gaps)
        if gaps[worst] < -gap_tol:
            active[worst] = True
            continue
        return F, theta, active, pivots
    raise RuntimeError(f"active-set LCP solve did not converge in {max_pivots} pivots")


def ncp_active_set(C, a, exponent, e, p, q, torque, active, start, max_pivots):
    """Solution of the nonlinear complementarity problem $y = CF + aF^{e} + e_0 - q\\Theta
    \\ge 0$, $F \\ge 0$, $F\\cdot y = 0$, $p\\cdot F = T$ (Palmgren's law, $e$ = 0.9): on the
    active set, Newton's method on the bordered system (loads kept positive: no load loses
    more than 90 % in a step), then the same pivots as `lcp_active_set`: drop a point whose load tends to zero
    from above (below 1e-9 of the mean load), add the most violated gap. `start`: loads to
    start from (the previous solve's). Returns (F, Θ, active set, pivots, Newton steps)."""
    active = active.copy()
    gap_tol = 1e-12  # mm
    newton = 0
    theta = 0.0
    for pivots in range(max_pivots):
        if not active.any():
            active[np.argmin(e / q)] = True
        idx = np.flatnonzero(active)
        m = idx.size
        Ca, aa, ea, pa, qa = C[np.ix_(idx, idx)], a[idx], e[idx], p[idx], q[idx]
        mean = torque / np.sum(pa)  # the mean load of the active points
        F = np.where(start[idx] > 0, start[idx], torque / np.sum(pa))
        theta = np.max((Ca @ F + aa * F**exponent + ea) / qa)
        for _ in range(100):
            newton += 1
            r = np.concatenate([Ca @ F + aa * F**exponent + ea - qa * theta, [pa @ F - torque]])
            J = np.empty((m + 1, m + 1))
            J[:m, :m] = Ca + np.diag(exponent * aa * F ** (exponent - 1.0))
            J[:m, m] = -qa
            J[m, :m] = pa
            J[m, m] = 0.0
            dx = scipy.linalg.solve(J, -r, check_finite=False)
            # fraction to the boundary: no load loses more than 90 % in one step
            falling = dx[:m] < 0
            step = min(1.0, 0.9 * np.min(F[falling] / -dx[:m][falling])) if falling.any() else 1.0
            F, theta = F + step * dx[:m], theta + step * dx[m]
            if step == 1.0 and np.max(np.abs(dx[:m])) <= 1e-13 * np.max(F):
                break
            if np.min(F) < 1e-9 * mean:  # a point leaving contact: drop it below
                break
        worst = np.argmin(F)
        if F[worst] < 1e-9 * mean and m > 1:
            active[idx[worst]] = False
            start = start.copy()
            start[idx] = F
            continue
        full = np.zeros_like(e)
        full[idx] = F
        gaps = C @ full + a * full**exponent + e - q * theta
        gaps[active] = np.inf
        worst = np.argmin(gaps)
        if gaps[worst] < -gap_tol:
            active[worst] = True
            start = full
            continue
        return full, theta, active, pivots, newton
    raise RuntimeError(f"active-set NCP solve did not converge in {max_pivots} pivots")


def palmgren_numpy(data: ContactInputs, torques: np.ndarray):
    """Θ (rad), (load, pos), and the number of pivots of the Newton active-set solves;
    torques ascending. Warm start: the previous torque's active set and loads (the previous
    position's at the first torque)."""
    rotation = np.empty((len(torques), len(data.te)))
    pivots = 0
    size = int(np.prod(data.shape[1:]))
    first_active, first_loads = np.zeros(size, dtype=bool), np.zeros(size)
    for i in range(len(data.te)):
        C, a, e, p, q = (data.compliance[i], data.nonlinear[i], data.separation[i], data.pinion_arm[i],
                         data.gear_arm[i])
        index = data.index[i]
        active, loads = first_active[index], first_loads[index]
        for j, torque in enumerate(torques):
            loads, rotation[j, i], active, used, _ = ncp_active_set(C, a, data.exponent, e, p, q, torque, active, loads,
                                                                    20 * e.size + 50)
            pivots += used
            if j == 0:
                first_active, first_loads = np.zeros(size, dtype=bool), np.zeros(size)
                first_active[index], first_loads[index] = active, loads
    return rotation, pivots


def slice_numpy(data: ContactInputs, torques: np.ndarray):
    """Θ (rad), (load, pos), and the number of pivots of the dense active-set solves; torques
    ascending. Warm start: the previous torque's active set (the previous position's at
    the first torque)."""
    if data.exponent != 1.0:
        raise ValueError("slice_numpy solves the linear contact law; palmgren_numpy the nonlinear one")
    rotation = np.empty((len(torques), len(data.te)))
    pivots = 0
    first = np.zeros(int(np.prod(data.shape[1:])), dtype=bool)  # over (pair x slice)
    for i in range(len(data.te)):
        C, e, p, q = data.compliance[i], data.separation[i], data.pinion_arm[i], data.gear_arm[i]
        index = data.index[i]
        active = first[index]
        for j, torque in enumerate(torques):
            _, rotation[j, i], active, used = lcp_active_set(C, e, p, q, torque, active, 20 * e.size + 50)
            pivots += used
            if j == 0:
                first = np.zeros_like(first)
                first[index] = active
    return rotation, pivots


# --------------------------------------------------------------------------- checks
def check(name: str, baseline_lte, gearjax_lte, rb2: float) -> dict:
    """Cycle mean and peak-to-peak of the loaded TE (µm along the line of action) of both
    sides, (load, pos) each; asserts the agreement of `TOLERANCES[name]`."""
    tol = TOLERANCES[name]
    um = rb2 * 1e3
    b, g = np.atleast_2d(baseline_lte) * um, np.atleast_2d(gearjax_lte) * um
    stats = {}
    for key, fn in (("mean_um", lambda a: np.mean(a, -1)), ("p2p_um", lambda a: np.ptp(a, -1))):
        vb, vg = fn(b), fn(g)
        diff = np.abs(vb - vg)
        stats[key] = {"baseline": vb.tolist(), "gearjax": vg.tolist(), "max_abs_diff": float(diff.max())}
        _assert_close(name, key, diff, tol["rtol"] * np.abs(vg) + tol["atol_um"], tol)
    curve = np.max(np.abs(b - g))
    stats["curve_max_abs_diff_um"] = float(curve)
    _assert_close(name, "curve", curve, tol["rtol"] * np.max(np.abs(g)) + tol["atol_um"], tol)
    print(f"  check {name}: mean {_span(stats['mean_um'], 'baseline')} / {_span(stats['mean_um'], 'gearjax')} µm, "
          f"p2p {_span(stats['p2p_um'], 'baseline')} / {_span(stats['p2p_um'], 'gearjax')} µm "
          f"(baseline / gearjax); max |diff| mean {stats['mean_um']['max_abs_diff']:.2e}, "
          f"p2p {stats['p2p_um']['max_abs_diff']:.2e}, curves {curve:.2e} µm: within rtol {tol['rtol']:g} "
          f"+ {tol['atol_um']:g} µm", flush=True)
    return stats


def check_slices(geo: Involute, designs, batch, sizes) -> dict:
    """The TE is about zero for these designs (an unmodified patch of the flank is always
    in contact), so the TE check alone hardly tests the relief formulas: compare the TE at
    which every slice touches (`TCAResult.slice_te`, untimed) too, for a few designs."""
    tca = jax.jit(lambda s: jax.vmap(gj.simulate)(s).tca)(batch)
    _, slice_np = te_numpy(geo, designs, sizes["positions"], sizes["slices"], batch.pairs, slices=True)
    valid = np.asarray(tca.valid)
    if not np.array_equal(valid, np.isfinite(slice_np)):
        raise AssertionError("tca: baseline and gearjax disagree on which slices are on the active flanks")
    um = geo.base_radius[1] * 1e3
    diff = np.abs(slice_np[valid] - np.asarray(tca.slice_te)[valid]) * um
    depth = np.max(np.abs(slice_np[valid])) * um
    tol = TOLERANCES["tca"]
    _assert_close("tca", "slice_te", diff, tol["atol_um"], tol)
    print(f"  check tca slices: {valid.sum()} slice contacts of {len(designs)} designs, relief depth up to "
          f"{depth:.3f} µm, max |diff| {diff.max():.2e} µm", flush=True)
    return {"slice_contacts": int(valid.sum()), "max_depth_um": float(depth), "max_abs_diff_um": float(diff.max())}


def _assert_close(name, key, diff, limit, tol):
    if not np.all(diff <= limit):
        raise AssertionError(
            f"{name}: {key} of baseline and gearjax differ by up to {np.max(diff):.3e} µm, beyond "
            f"rtol {tol['rtol']:g} + atol {tol['atol_um']:g} µm"
        )


def _span(entry, side):
    v = np.asarray(entry[side])
    return f"{v.min():.6f}" if v.size == 1 or v.min() == v.max() else f"[{v.min():.4f}..{v.max():.4f}]"


# --------------------------------------------------------------------------- problems
def run_tca(sizes, repeats, out):
    scene0 = base_scene()
    geo = involute_constants(scene0.pair)
    acc = accuracy(sizes["positions"], sizes["slices"])
    designs = random_designs(sizes["designs"], float(scene0.pair.normal_module), geo.face_width)
    scenes = [rigid_scene(scene0.pair, gj.FlankModification.from_vector(y), acc, pairs=scene0.pairs) for y in designs]
    batch = gj.stack_scenes(scenes)
    # The public call for many designs of one pair: the pair resolved once, only the TE returned.
    scene = rigid_scene(scene0.pair, None, acc, pairs=scene0.pairs)
    modifications = gj.FlankModification.from_vector(designs)
    compile_s, run_s, runs, te_gj = first_and_runs(
        lambda: gj.simulate_designs(scene, modifications, outputs=_transmission_error), repeats=repeats)
    # The same through jax.vmap(gj.simulate) over stacked scenes (a copy of the pair per
    # design), once with the whole result returned, once with the TE alone.
    stacked = {}
    for key, fn in (("whole_result", jax.jit(jax.vmap(gj.simulate))),
                    ("te_only", jax.jit(lambda s: jax.vmap(gj.simulate)(s).tca.transmission_error))):
        first, median, _, _ = time_compiled_output(fn, batch, repeats=repeats)
        stacked[key] = {"compile_s": first, "run_s": median}
    base_s, base_runs, te_np = time_host(te_numpy, geo, designs, sizes["positions"], sizes["slices"], batch.pairs,
                                         repeats=repeats)
    stats = check("tca", te_np, np.asarray(te_gj), geo.base_radius[1])
    stats["slices"] = check_slices(geo, designs[:4], gj.stack_scenes(scenes[:4]), sizes)
    stats["vmap_simulate_over_stack_scenes"] = stacked
    print(f"  jax.vmap(gj.simulate) over gj.stack_scenes: whole result {stacked['whole_result']['run_s']:.4f} s, "
          f"TE only {stacked['te_only']['run_s']:.4f} s", flush=True)
    label = f"TCA plane of action: {sizes['designs']} designs x {sizes['positions']} positions, {sizes['slices']} slices"
    return _row(out, "tca", label, sizes, base_s, base_runs, "numpy vectorised", compile_s, run_s, runs,
                "gj.simulate_designs(scene, modifications, outputs=TE)", stats)


def _transmission_error(result):
    return result.tca.transmission_error


def _load_sweep_fn():
    # only the compared quantities leave the program, so XLA prunes the rest
    return jax.jit(lambda scene, torques: _lte_and_loads(gj.load_sweep(scene, torques=torques)))


def _lte_and_loads(sweep):
    return sweep.ltca.transmission_error, sweep.ltca.loads


def _loaded_inputs(scene):
    """The baselines' inputs (untimed), from the TCA of the same scene without its torque:
    the TCA that `load_sweep` runs once for all torques."""
    rigid = rigid_scene(scene.pair, scene.modification, scene.accuracy, pairs=scene.pairs)
    return contact_inputs(scene, gj.simulate(rigid).tca)


def run_iso(sizes, repeats, out):
    scene0 = base_scene()
    geo = involute_constants(scene0.pair)
    scene = loaded_scene(scene0.pair, scene0.modification, accuracy(sizes["positions"], sizes["slices"]), gj.IsoCompliance())
    torques = np.linspace(*TORQUE_RANGE, sizes["loads"])
    data = _loaded_inputs(scene)
    compile_s, run_s, runs, (lte_gj, _) = time_compiled_output(_load_sweep_fn(), scene, jax.numpy.asarray(torques),
                                                               repeats=repeats)
    base_s, base_runs, rotation = time_host(iso_numpy, data, torques, repeats=repeats)
    stats = check("ltca_iso", data.te[None, :] - rotation, np.asarray(lte_gj), geo.base_radius[1])
    label = (f"LTCA iso: {sizes['positions']} positions x {sizes['loads']} loads, {sizes['slices']} slices "
             f"({len(scene.pairs)} x {sizes['slices']} points)")
    return _row(out, "ltca_iso", label, sizes, base_s, base_runs, "scipy.optimize.brentq per position and load",
                compile_s, run_s, runs, "gj.load_sweep", stats)


def slice_scene(scene0, positions_per_pitch, slices, hertz="linear"):
    return loaded_scene(scene0.pair, scene0.modification, accuracy(positions_per_pitch, slices),
                        gj.SliceCompliance(hertz=hertz))


def run_slice(sizes, loads, repeats, out, key="ltca_slice", label_prefix="LTCA slice (linear Hertz)", hertz="linear"):
    scene0 = base_scene()
    geo = involute_constants(scene0.pair)
    scene = slice_scene(scene0, sizes["positions"], sizes["slices"], hertz)
    torques = np.linspace(*TORQUE_RANGE, loads) if loads > 1 else np.asarray([DESIGN_TORQUE])
    data = _loaded_inputs(scene)
    compile_s, run_s, runs, (lte_gj, _) = time_compiled_output(_load_sweep_fn(), scene, jax.numpy.asarray(torques),
                                                               repeats=repeats)
    solver = slice_numpy if hertz == "linear" else palmgren_numpy
    base_s, base_runs, (rotation, pivots) = time_host(solver, data, torques, repeats=repeats)
    stats = check("ltca_slice" if hertz == "linear" else "ltca_palmgren", data.te[None, :] - rotation,
                  np.asarray(lte_gj), geo.base_radius[1])
    points = len(scene.pairs) * sizes["slices"]
    label = f"{label_prefix}: {sizes['positions']} positions x {loads} loads, {points} points"
    contact_points = [len(i) for i in data.index]
    sizes = {**sizes, "loads": loads, "points": points, "baseline_pivots": pivots,
             "points_on_flanks": [min(contact_points), max(contact_points)]}
    method = ("dense active set (scipy.linalg.solve) per position and load" if hertz == "linear" else
              "dense active set with Newton on each set (scipy.linalg.solve) per position and load")
    return _row(out, key, label, sizes, base_s, base_runs, method, compile_s, run_s, runs, "gj.load_sweep", stats)


def _row(out, key, label, sizes, base_s, base_runs, base_method, compile_s, run_s, runs, gj_method, stats):
    row = {
        "problem": key, "label": label, "sizes": sizes,
        "baseline_method": base_method, "baseline_s": base_s, "baseline_runs_s": base_runs,
        "gearjax_method": gj_method, "gearjax_compile_s": compile_s, "gearjax_s": run_s, "gearjax_runs_s": runs,
        "ratio": base_s / run_s, "check": stats,
    }
    out["rows"].append(row)
    print(f"{label}: baseline {base_s:.4f} s, gearjax {run_s:.4f} s (compile {compile_s:.1f} s), "
          f"ratio {base_s / run_s:.2f}", flush=True)
    write(out["name"], out)
    return row


def run_growth(sizes, repeats, out):
    scene0 = base_scene()
    rows = []
    for n in sizes["slices"]:
        rows.append(run_slice({"positions": sizes["positions"], "slices": n}, 1, repeats, out, key="growth",
                              label_prefix="growth, LTCA slice (linear Hertz)"))
    points = np.asarray([r["sizes"]["points"] for r in rows], dtype=float)
    fit = {}
    for side in ("baseline_s", "gearjax_s"):
        slope, _ = np.polyfit(np.log(points), np.log([r[side] for r in rows]), 1)
        fit[side.removesuffix("_s")] = float(slope)
    out["growth_exponent"] = {**fit, "points": points.tolist(), "positions": sizes["positions"], "loads": 1,
                              "pairs": len(scene0.pairs)}
    write(out["name"], out)
    print(f"growth exponent (time ~ points^k): baseline k = {fit['baseline']:.2f}, gearjax k = {fit['gearjax']:.2f}",
          flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per side (median reported)")
    parser.add_argument("--quick", action="store_true", help="small smoke sizes (not a measurement)")
    parser.add_argument("--growth", action="store_true", help="also the slice problem's cost against points")
    parser.add_argument("--problems", nargs="*", default=["tca", "ltca_iso", "ltca_slice", "ltca_palmgren"],
                        choices=["tca", "ltca_iso", "ltca_slice", "ltca_palmgren"])
    parser.add_argument("--name", default=None, help="results file benchmarks/results/NAME.json "
                        "(default baseline_scipy, or baseline_scipy_quick with --quick)")
    args = parser.parse_args(argv)
    sizes = QUICK if args.quick else FULL
    name = args.name or ("baseline_scipy_quick" if args.quick else "baseline_scipy")
    out = {
        "name": name,
        "machine": {**machine(), "numpy": np.__version__, "scipy": scipy.__version__},
        "quick": args.quick, "repeats": args.repeats,
        "scene": "default (seed 001 pair, paper optimum; plane-of-action TCA)",
        "torques_Nmm": {"sweeps": list(TORQUE_RANGE), "single": DESIGN_TORQUE},
        "tolerances": TOLERANCES,
        "notes": [
            "ltca_slice and growth use SliceCompliance(hertz='linear') on both sides (an LCP); "
            "ltca_palmgren SliceCompliance() (Palmgren's law, an NCP).",
            "Baseline inputs (separations, compliance, arms) are taken from gearjax outside the timed "
            "region; the gearjax time includes its TCA and compliance.",
            "gearjax programs return only the compared quantities (TE; loaded TE and loads).",
            "The baselines drop the points whose conjugate contact is off the active flanks (about "
            "1.45 x slices per position, sizes.points_on_flanks); gearjax keeps all pairs x slices "
            "points, those with a separation of 1 mm.",
        ],
        "rows": [],
    }
    started = time.perf_counter()
    if "tca" in args.problems:
        run_tca(sizes["tca"], args.repeats, out)
    if "ltca_iso" in args.problems:
        run_iso(sizes["ltca_iso"], args.repeats, out)
    if "ltca_slice" in args.problems:
        for loads in sizes["ltca_slice"]["loads"]:
            run_slice({k: v for k, v in sizes["ltca_slice"].items() if k != "loads"}, loads, args.repeats, out)
    if "ltca_palmgren" in args.problems:
        for loads in sizes["ltca_slice"]["loads"]:
            run_slice({k: v for k, v in sizes["ltca_slice"].items() if k != "loads"}, loads, args.repeats, out,
                      key="ltca_palmgren", label_prefix="LTCA slice (Palmgren)", hertz="palmgren")
    if args.growth:
        run_growth(sizes["growth"], args.repeats, out)
    out["total_s"] = time.perf_counter() - started
    path = write(name, out)

    print(f"\n{'quick smoke sizes, not a measurement; ' if args.quick else ''}median of {args.repeats} runs; "
          "ratio = SciPy / gearjax")
    print("\n| problem | SciPy median (s) | gearjax median (s) | gearjax compile (s) | ratio |")
    print("|---|---:|---:|---:|---:|")
    for r in out["rows"]:
        print(f"| {r['label']} | {r['baseline_s']:.4f} | {r['gearjax_s']:.4f} | {r['gearjax_compile_s']:.1f} | "
              f"{r['ratio']:.2f} |")
    if "growth_exponent" in out:
        g = out["growth_exponent"]
        print(f"\ntime ~ points^k over {g['points']} points: SciPy k = {g['baseline']:.2f}, gearjax k = {g['gearjax']:.2f}")
    for note in out["notes"]:
        print(f"note: {note}")
    print(f"written {path}")


if __name__ == "__main__":
    main()
