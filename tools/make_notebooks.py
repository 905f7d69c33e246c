"""Writes the notebooks from their cell sources (outputs are not committed).

    python tools/make_notebooks.py
"""

from pathlib import Path

import nbformat as nbf

HERE = Path(__file__).resolve().parent.parent / "notebooks"

SETUP = """\
import jax
jax.config.update("jax_enable_x64", True)   # float64, the reference precision
import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import gearjax as gj
from gearjax.io import plot"""


def notebook(cells):
    nb = nbf.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nb.cells = [nbf.v4.new_markdown_cell(c[3:]) if c.startswith("md:") else nbf.v4.new_code_cell(c) for c in cells]
    for i, cell in enumerate(nb.cells):
        cell.id = f"cell-{i:02d}"  # stable ids: regenerating does not churn the files
    return nb


NB01 = [
    "md:# 01 — Involute helical pair: geometry and unloaded TCA\n\n"
    "The seed 001 pair (z 29/71, m_n 5 mm, beta 27.5 deg, b 42 mm). The paper states a = 261.0 mm, "
    "which is inconsistent with its helix angle and zero profile shift; gearjax uses the standard "
    "a = 281.85 mm.",
    SETUP + "\nfrom gearjax.papers.seed001 import paper_optimum",
    """pair = gj.InvoluteGearPair((29, 71), normal_module=5.0, pressure_angle_deg=20.0,
                           helix_angle_deg=27.5, face_width=42.0)
print(f"a = {float(pair.center_distance):.3f} mm, r_b = {np.asarray(pair.base_radius)} mm")
print(f"eps_alpha = {float(pair.transverse_contact_ratio):.3f}, eps_beta = {float(pair.overlap_ratio):.3f}")""",
    "md:## Transmission error with and without modification\n\n"
    "Unmodified conjugate flanks have zero TE. The paper's optimal modification leaves a "
    "central unmodified zone that some contact line always crosses, so its *unloaded* TE is "
    "also zero; a heavier modification (long reliefs, short unmodified centre) shows the TE "
    "that relief and crowning create.",
    """acc = gj.Accuracy(positions_per_pitch=24, face_slices=15)
heavy = gj.FlankModification(root_relief=0.015, tip_relief=0.015, root_relief_length=9.0,
                             tip_relief_length=9.0, crowning=0.012, unmodified_length=4.0)
results = {
    "unmodified": gj.simulate(gj.Scene(pair, accuracy=acc)).tca,
    "paper optimum (Table 2)": gj.simulate(gj.Scene(pair, paper_optimum(), accuracy=acc)).tca,
    "heavy modification": gj.simulate(gj.Scene(pair, heavy, accuracy=acc)).tca,
}
ax = None
for name, r in results.items():
    ax = plot.transmission_error(r, ax=ax, label=name)
    print(f"{name:25s} TE p-p = {float(r.te_peak_to_peak_line) * 1e3:.3f} um")""",
    "md:## Path of contact on the pinion flank\n\n"
    "Unmodified: straight contact lines inclined at the base helix angle. Modified: the "
    "binding contact moves within the unmodified zone.",
    """fig, axes = plt.subplots(1, 2, figsize=(12, 4))
plot.contact_path(results["unmodified"], ax=axes[0], tolerance=1e-6)
axes[0].set_title("unmodified: contact lines")
plot.contact_path(results["heavy modification"], ax=axes[1], tolerance=1e-4)
axes[1].set_title("heavy modification: contact within 0.1 um")""",
    "md:## Edge contact\n\n"
    "A base pitch deviation f_pb = -5 um makes the next pair come into mesh early: before its "
    "start of active profile, the gear's tip edge touches the pinion flank (red crosses). The "
    "general TCA finds these contacts; the plane-of-action fast path cannot.",
    """errors = gj.MeshErrors(base_pitch_deviation=-0.005)
r = gj.simulate(gj.Scene(pair, errors=errors, accuracy=acc)).tca
fig, axes = plt.subplots(1, 2, figsize=(12, 4))
plot.transmission_error(r, ax=axes[0])
plot.contact_path(r, ax=axes[1], tolerance=1e-5)
pair_idx, slice_idx = (np.asarray(a) for a in r.binding)
kinds = r.kind_name[np.arange(r.pinion_angle.size), pair_idx, slice_idx]
print("binding contact kinds over the cycle:", sorted(set(kinds.tolist())))""",
]


NB03 = [
    "md:# 03 — Involute curvilinear-tooth gears\n\n"
    "Seed 002's pair (z 20/30, m 2 mm, b 20 mm, α 20°): every transverse section is an "
    "involute, displaced along the base circle by d(z) = R_t − √(R_t² − z²), so the tooth "
    "trace is an arc of radius R_t. The general TCA finds line contact along an arc of the "
    "plane of action of length L = 2 R_t asin(b/2R_t) (seed 002, eq. 18).",
    SETUP + "\nimport jax.numpy as jnp\nfrom gearjax.papers.curvilinear import contact_line",
    """radii = [10.5, 12.0, 15.0, 30.0, 1e6]
fig, ax = plt.subplots(figsize=(6, 4))
for radius in radii:
    pair = gj.CurvilinearGearPair((20, 30), 2.0, 20.0, 20.0, radius)
    z = np.linspace(-10, 10, 81)
    s1 = 9.6 - np.asarray(pair.lead_displacement(z))
    ax.plot(z, s1, label=f"R_t = {radius:g} mm: L = {float(pair.contact_line_length):.3f} mm")
ax.set_xlabel("axial position z (mm)"); ax.set_ylabel("pinion roll length of the contact (mm)")
ax.set_title("contact lines on the plane of action"); ax.legend(fontsize=8); ax.grid(alpha=0.3)""",
    "md:## General TCA against the closed form",
    """for radius in (12.0, 15.0, 100.0):
    line = contact_line(gj.CurvilinearGearPair((20, 30), 2.0, 20.0, 20.0, radius), 9.6)
    print(f"R_t {radius:6.1f}: TCA length {line['length_mm']:.6f} mm, eq. 18 {line['closed_form_length_mm']:.6f} mm, "
          f"max distance from the arc {line['max_distance_from_arc_mm']:.1e} mm, TE {line['te_rad']:.1e} rad")""",
    "md:## Profile relief: TE against the tooth-trace radius\n\nWith root and tip relief the "
    "TE dip depends on how the curved contact lines cross the relief zones; a large R_t "
    "behaves like the spur gear.",
    """acc = gj.Accuracy(positions_per_pitch=24, face_slices=15)
mod = gj.FlankModification(root_relief=0.01, tip_relief=0.01, root_relief_length=4.5, tip_relief_length=4.5)
fig, ax = plt.subplots(figsize=(6, 4))
for radius in (11.0, 13.0, 20.0, 1e6):
    pair = gj.CurvilinearGearPair((20, 30), 2.0, 20.0, 20.0, radius)
    plot.transmission_error(gj.simulate(gj.Scene(pair, mod, accuracy=acc)).tca, ax=ax, label=f"R_t = {radius:g} mm")""",
]


NB04 = [
    "md:# 04 — Loaded tooth contact analysis\n\n"
    "The seed 001 pair with the paper's optimal modification under load: loaded transmission "
    "error against load, load sharing, the contact pattern on the flank and the mesh stiffness "
    "over the cycle. The slice model couples potential-energy tooth compliance, Sainsot's fillet "
    "foundation and Palmgren's line contact; the iso model is ISO 6336-1 method B as a uniform "
    "line stiffness.",
    SETUP + "\nfrom gearjax.sweep import load_sweep\nfrom gearjax.ltca import iso_mesh_stiffness, IsoCompliance"
    "\nfrom gearjax.papers.seed001 import paper_optimum",
    """pair = gj.InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0)
acc = gj.Accuracy(positions_per_pitch=24, face_slices=15)
scene = gj.Scene(pair, paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0), accuracy=acc)
torques_Nm = np.array([0.0, 100.0, 250.0, 400.0, 700.0, 1000.0, 1300.0, 1600.0, 2000.0])
sweep = load_sweep(scene, torques_Nm=torques_Nm)
lte = np.asarray(sweep.ltca.transmission_error_line) * 1e3
print("converged everywhere:", bool(np.all(np.asarray(sweep.ltca.converged))))""",
    "md:## Loaded TE against load\n\nThe mean loaded TE grows almost linearly with load; its "
    "peak-to-peak fluctuation is smallest near the load the modification was designed for.",
    """fig, axes = plt.subplots(1, 2, figsize=(12, 4))
for i in (1, 3, 5, 8):
    plot.loaded_transmission_error(jax.tree_util.tree_map(lambda x: x[i], sweep.ltca), ax=axes[0],
                                   label=f"{torques_Nm[i]:.0f} N m")
axes[1].plot(torques_Nm, np.ptp(lte, axis=1), "o-", label="peak-to-peak")
axes[1].plot(torques_Nm, -lte.mean(axis=1) / 10, "s--", label="-mean / 10")
axes[1].set_xlabel("pinion torque (N m)"); axes[1].set_ylabel("LTE (um)"); axes[1].legend(); axes[1].grid(alpha=0.3)""",
    "md:## Load sharing, contact pattern and mesh stiffness at 1000 N·m",
    """design = jax.tree_util.tree_map(lambda x: x[5], sweep.ltca)
fig, axes = plt.subplots(1, 3, figsize=(17, 4))
plot.load_sharing(design, ax=axes[0])
plot.contact_pattern(sweep.tca, design, ax=axes[1])
plot.mesh_stiffness(design, ax=axes[2], iso=iso_mesh_stiffness(pair))
print(f"max load share {float(design.max_load_share):.3f}, max pressure {float(design.max_pressure):.0f} MPa, "
      f"mean stiffness {float(design.mean_mesh_stiffness):.2f} N/(mm um) vs ISO c_ga "
      f"{float(iso_mesh_stiffness(pair).mesh_stiffness):.2f}")""",
    "md:## Compliance models\n\nThe iso model (uniform line stiffness) against the slice model, "
    "for the unmodified pair at 1000 N·m.",
    """plain = gj.Scene(pair, operating=gj.OperatingPoint(torque_Nm=1000.0), accuracy=acc)
iso_scene = gj.Scene(pair, operating=gj.OperatingPoint(torque_Nm=1000.0), accuracy=acc, compliance=IsoCompliance())
ax = None
for name, sc in (("slice", plain), ("iso", iso_scene)):
    r = gj.simulate(sc).ltca
    ax = plot.loaded_transmission_error(r, ax=ax, label=f"{name}: p-p {float(r.lte_peak_to_peak_line) * 1e3:.2f} um")""",
]


NB05 = [
    "md:# 05 — Mesh-in impact\n\n"
    "Seed 001's question: under load the teeth in mesh deflect, so the next pair strikes "
    "early, off the line of action. gearjax finds that first contact with the general TCA and "
    "the LTCA (the incoming pair's rigid gap closed by the loaded approach of the others), "
    "takes the normal velocity from the real kinematics, fits the local force-approach curve "
    "$F = K_s\\delta^n$ and applies the energy method. The grid here is coarser than the "
    "default (16 positions, 9 slices) to keep the notebook quick.",
    SETUP + "\nimport jax.numpy as jnp\nfrom gearjax.impact import ImpactRegime",
    """pair = gj.InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0)
acc = gj.Accuracy(positions_per_pitch=16, face_slices=9)
paper = jnp.array([5.9, 6.8, 3800.0, 4300.0, 6.2, 4600.0]) / 1000.0   # Table 2, mm
plain = paper.at[jnp.array([0, 1, 4])].set(0.0)                        # no relief, same program

def impact(y, torque_Nm, rpm=5000.0):
    scene = gj.Scene(pair, gj.FlankModification.from_vector(y), effects=("impact",), accuracy=acc,
                     operating=gj.OperatingPoint(torque_Nm=torque_Nm, speed_rpm=rpm), pairs=(-2, -1, 0, 1, 2))
    return gj.simulate(scene).impact

loads = np.array([100.0, 250.0, 400.0, 600.0, 800.0, 1000.0, 1300.0, 1600.0])
std = [impact(plain, t) for t in loads]
mod = [impact(paper, t) for t in loads]
for name, rows in (("standard", std), ("modified", mod)):
    print(name, [f"{float(r.force):.0f} N ({r.regime_name})" for r in rows])""",
    "md:## Impact force against load and speed\n\nThe standard pair strikes with its tip edge at "
    "every load, harder as the load grows. The modified pair enters flank-on-flank at light "
    "load, until the deflection exceeds the reliefs and the gear's tip edge strikes again. "
    "Against speed the force grows as $\\omega^{2n/(n+1)}$.",
    """fig, axes = plt.subplots(1, 2, figsize=(12, 4))
for name, rows, m in (("standard", std, "o-"), ("modified (paper optimum)", mod, "s-")):
    axes[0].plot(loads, [float(r.force) for r in rows], m, label=name)
axes[0].set_xlabel("pinion torque (N m)"); axes[0].set_ylabel("impact force F_s (N)"); axes[0].legend(); axes[0].grid(alpha=0.3)
rpms = np.array([1000.0, 2000.0, 3500.0, 5000.0, 7000.0])
for name, y, m in (("standard", plain, "o-"), ("modified", paper, "s-")):
    f = [float(impact(y, 1000.0, n).force) for n in rpms]
    axes[1].loglog(rpms, f, m, label=name)
n = float(std[5].stiffness.exponent)
axes[1].loglog(rpms, f[-2] * (rpms / 5000.0) ** (2 * n / (n + 1)), "k:", label=f"slope 2n/(n+1) = {2 * n / (n + 1):.3f}")
axes[1].set_xlabel("pinion speed (rpm)"); axes[1].set_ylabel("F_s at 1000 N m (N)"); axes[1].legend(); axes[1].grid(alpha=0.3, which="both")""",
    "md:## The impact point on the pinion flank\n\nRoll length (height on the flank) and face "
    "position of the strike point against load: the edge strikes move up the pinion flank as "
    "the load grows (seed 001, Table 3); the modified pair's flank contact moves towards the "
    "edge until the regime switches.",
    """fig, ax = plt.subplots(figsize=(6, 4))
for name, rows, m in (("standard", std, "o-"), ("modified", mod, "s-")):
    ax.plot(loads, [float(r.pinion_parameter) for r in rows], m, label=name)
    for t, r in zip(loads, rows):
        ax.annotate(r.regime_name[0], (t, float(r.pinion_parameter)), textcoords="offset points", xytext=(4, 4), fontsize=8)
ax.axhline(float(pair.start_of_active_profile[0]), color="gray", ls="--", label="start of active profile")
ax.set_xlabel("pinion torque (N m)"); ax.set_ylabel("pinion roll length of M (mm)"); ax.legend(); ax.grid(alpha=0.3)""",
    "md:## Regime map: load × relief amount\n\nThe paper's optimum scaled by a factor; "
    "edge contact (1) where the loaded approach beats the relief at the gear's tip edge.",
    """scales = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 3.0])
grid = np.array([[int(impact(paper.at[jnp.array([0, 1, 4])].multiply(s), t).regime == ImpactRegime.edge) for t in loads] for s in scales])
fig, ax = plt.subplots(figsize=(6, 3.5))
ax.imshow(grid, origin="lower", aspect="auto", cmap="coolwarm", extent=(0, len(loads), 0, len(scales)))
ax.set_xticks(np.arange(len(loads)) + 0.5, [f"{t:.0f}" for t in loads]); ax.set_yticks(np.arange(len(scales)) + 0.5, scales)
ax.set_xlabel("pinion torque (N m)"); ax.set_ylabel("relief amounts x paper optimum"); ax.set_title("blue: surface, red: edge")""",
]


NB06 = [
    "md:# 06 — Optimising the modification for a small mesh-in impact\n\n"
    "Seed 001's six parameters (root/tip relief amount and length, crowning, unmodified "
    "length) tuned to minimise the energy-method impact force $F_s$ at 1000 N·m, 5000 rpm, by "
    "the genetic algorithm and by projected gradient descent. Small runs at the `fast` "
    "accuracy so the notebook runs in a few minutes; each run ends by evaluating its best "
    "candidates again at the `reference` accuracy and keeps the best of those certified values "
    "(a search finds the designs where its own discretisation errs most in its favour). "
    "`tools/optimize_seed001.py` runs the paper's 40 x 30.",
    SETUP + "\nfrom gearjax import optimize as go\nfrom gearjax.papers.seed001 import paper_optimum, seed_pair",
    """scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                 effects=("impact",), accuracy="fast")
objective = go.Objective.create(scene)
space = go.DesignSpace.for_scene(scene, tip_relief_length=(0.5, 4.5))   # the paper's y4 = 4.3 mm needs > 0.8 m_n
print("lower (mm):", np.asarray(space.lower)); print("upper (mm):", np.asarray(space.upper))""",
    "md:## GA and gradient descent\n\nThe GA evaluates its whole population in one compiled call "
    "per generation; the gradient method runs its starts together, one call of value and "
    "gradient per iteration. Both count evaluations per design and load.",
    """ga = go.genetic(objective, space, config=go.GAConfig(population=12), generations=8, seed=0)
gd = go.gradient_descent(objective, space, config=go.GradientConfig(starts=2, iterations=10), seed=0)
for r in (ga, gd):
    print(f"{r.method:9s} best {r.best_objective:8.1f} N at 'fast', certified {r.certified_objective:8.1f} N at "
          f"'{r.certification.accuracy}', after {r.evaluations} evaluations (start: paper optimum {r.initial_objective:.0f} N at 'fast')")
fig, ax = plt.subplots(figsize=(6, 4))
for r in (ga, gd):
    per = r.evaluations / r.steps
    ax.plot(per * np.arange(1, r.steps + 1), r.history, ".-", label=r.method)
ax.set_xscale("log"); ax.set_xlabel("objective evaluations"); ax.set_ylabel("best F_s (N)"); ax.legend(); ax.grid(alpha=0.3, which="both")""",
    "md:## The optimum modification as a flank map\n\nDepth removed from the pinion flank "
    "(µm) over roll length (profile) and face position (lead).",
    """best = min((ga, gd), key=lambda r: r.certified_objective)
mod = go.modification_from_design(best.best_design)
zone = scene.pair.contact_zones()[0]
start, tip = (float(v) for v in zone.relief_coordinates(0))
s, w = np.meshgrid(np.linspace(start, tip, 60), np.linspace(-21.0, 21.0, 60))
depth = np.asarray(mod.depth(s, w, start, tip, 42.0)) * 1e3
fig, ax = plt.subplots(figsize=(6, 4))
c = ax.contourf(w, s, depth, 20, cmap="viridis"); fig.colorbar(c, label="depth (µm)")
ax.set_xlabel("face position w (mm)"); ax.set_ylabel("roll length s (mm)")
print(go.design_dict(best.best_design))""",
    "md:## Impact force against load: standard, paper optimum, our optimum\n\nOne compiled "
    "`simulate` serves every load (the torque is an array, not a static setting).",
    """designs = {"standard": np.array([0.0, 0.0, 1.0, 1.0, 0.0, 0.0]), "paper optimum": np.asarray(paper_optimum().as_vector()),
           "optimum (1000 N m)": best.best_design}
loads = np.array([400.0, 700.0, 1000.0, 1300.0, 1600.0])
fig, ax = plt.subplots(figsize=(6, 4))
for name, y in designs.items():
    rows = [gj.simulate(go.Objective.create(scene, torques_Nm=[t]).scene_for(y), throw=False).impact for t in loads]
    ax.plot(loads, [float(r.force) if r.result == gj.RESULTS.successful else np.nan for r in rows], "o-", label=name)
    print(name, [r.regime_name for r in rows])
ax.set_xlabel("pinion torque (N m)"); ax.set_ylabel("F_s (N)"); ax.legend(); ax.grid(alpha=0.3)""",
]


def main():
    HERE.mkdir(exist_ok=True)
    nbf.write(notebook(NB01), HERE / "01_involute_tca.ipynb")
    nbf.write(notebook(NB03), HERE / "03_curvilinear.ipynb")
    nbf.write(notebook(NB04), HERE / "04_ltca.ipynb")
    nbf.write(notebook(NB05), HERE / "05_mesh_in_impact.ipynb")
    nbf.write(notebook(NB06), HERE / "06_optimisation.ipynb")


if __name__ == "__main__":
    main()
