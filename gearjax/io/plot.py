"""Matplotlib figures (optional extra: `pip install gearjax[plot]`).

Every function draws on an `Axes` (a new figure when `ax` is None) and returns it. Lengths
are shown in mm, transmission error in micrometres along the line of action, angles in
degrees. Every function takes a `title`: a string, or a `Scene`, whose `scene_title` (pair,
operating point and accuracy; the maps over torque leave the torque out, and the speed where
they sweep it too) then heads the figure.
"""

from __future__ import annotations

import math

import numpy as np

from ..tca import ContactKind
from .report import family_words


def scene_title(scene, operating: bool = True, speed: bool | None = None) -> str:
    """A figure title naming its scene in an engineer's words: the pair (family, teeth,
    normal module, face width), the operating point where it has one, and the accuracy
    (positions per pitch × face slices), e.g. "involute helical gear pair z 29/71, m_n 5 mm,
    b 42 mm; 1000 N·m, 5000 rpm; 32 positions/pitch × 21 slices".

    Args:
        scene: the `Scene`.
        operating: show the torque and speed (False for figures that sweep the torque).
        speed: show the speed; as `operating` when None (a map over torque at one speed
            passes `operating=False, speed=True`).
    """
    pair = scene.pair
    report = pair.geometry_report()
    helix = report.get("helix_angle_deg")
    words = family_words(type(pair).__name__, None if helix is None else float(np.asarray(helix)))
    parts = [f"{words} z {pair.teeth[0]}/{pair.teeth[1]}"]
    for key, name in (("normal_module_mm", "m_n"), ("face_width_mm", "b")):
        if key in report:
            parts.append(f"{name} {float(np.asarray(report[key])):g} mm")
    load = []
    if operating and scene.operating.torque is not None:
        load.append(f"{float(np.asarray(scene.operating.torque)) / 1e3:g} N·m")
    rpm = float(np.asarray(scene.operating.speed)) * 30.0 / math.pi
    if (operating if speed is None else speed) and rpm != 0.0:
        load.append(f"{rpm:.6g} rpm")
    accuracy = f"{scene.accuracy.positions_per_pitch} positions/pitch × {scene.accuracy.face_slices} slices"
    return "; ".join([", ".join(parts)] + ([", ".join(load)] if load else []) + [accuracy])


def _title_text(title, operating: bool = True, speed: bool | None = None) -> str:
    """`title` itself, or the `scene_title` of a scene."""
    return title if isinstance(title, str) else scene_title(title, operating, speed)


def _title(ax, title, operating: bool = True, speed: bool | None = None):
    """Head `ax` with `title` (a string, or a scene named by `scene_title`, without the
    part of its operating point that the figure sweeps); returns `ax`."""
    if title is not None:
        ax.set_title(_title_text(title, operating, speed), fontsize="medium")
    return ax


def _axes(ax):
    if ax is not None:
        return ax
    try:
        import matplotlib.pyplot as plt
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ImportError("gearjax.io.plot needs matplotlib: pip install 'gearjax[plot]'") from err
    _, ax = plt.subplots(figsize=(6.4, 4.0))
    return ax


def transmission_error(result, ax=None, label=None, title=None, **kwargs):
    """Unloaded TE of a `TCAResult` (um along the line of action) against the pinion angle
    (deg)."""
    te = np.asarray(result.transmission_error_line) * 1e3
    return _title(_te_curve(ax, result.pinion_angle, te, "TE along line of action (um)", label, **kwargs), title)


def _te_curve(ax, pinion_angle, te_um, ylabel, label, **kwargs):
    """A TE curve (um) against the pinion angle (rad, shown in deg)."""
    ax = _axes(ax)
    ax.plot(np.degrees(np.asarray(pinion_angle)), te_um, label=label, **kwargs)
    ax.set_xlabel("pinion angle (deg)")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if label is not None:
        ax.legend()
    return ax


def contact_path(result, ax=None, tolerance=1e-4, cmap="viridis", title=None):
    """Contact points on the pinion flank over the cycle: axial position (mm) against roll
    length (mm), coloured by pinion angle; edge contacts are marked with crosses.

    A point is drawn where its separation is below `tolerance` (mm): the contact lines of
    line contact, or the binding point of localised contact.
    """
    ax = _axes(ax)
    touching = np.asarray(result.in_contact(tolerance))
    z = np.broadcast_to(np.asarray(result.slice_z), touching.shape)
    s = np.asarray(result.pinion_parameter)
    angle = np.broadcast_to(np.degrees(np.asarray(result.pinion_angle))[:, None, None], touching.shape)
    edge = ~np.asarray(result.kind == ContactKind.flank)
    flank = touching & ~edge
    sc = ax.scatter(z[flank], s[flank], c=angle[flank], s=10, cmap=cmap)
    if np.any(touching & edge):
        ax.scatter(z[touching & edge], s[touching & edge], c="r", marker="x", s=20, label="edge contact")
        ax.legend()
    ax.figure.colorbar(sc, ax=ax, label="pinion angle (deg)")
    ax.set_xlabel("axial position z (mm)")
    ax.set_ylabel("pinion roll length s (mm)")
    ax.grid(True, alpha=0.3)
    return _title(ax, title)


def separation_map(result, position: int, ax=None, title=None):
    """Initial separation (um) of every slice of every pair at one position (its pinion angle
    in the title, after `title` where one is given)."""
    ax = _axes(ax)
    sep = np.asarray(result.separation)[position] * 1e3
    z = np.asarray(result.slice_z)
    order = np.argsort(z)
    for k, row in zip(np.asarray(result.pair_index), sep):
        finite = np.isfinite(row[order])
        if finite.any():
            ax.plot(z[order][finite], row[order][finite], marker=".", label=f"pair {k}")
    ax.set_xlabel("axial position z (mm)")
    ax.set_ylabel("separation (um)")
    angle = f"pinion angle {math.degrees(float(np.asarray(result.pinion_angle)[position])):.2f} deg"
    ax.legend()
    ax.grid(True, alpha=0.3)
    return _title(ax, angle if title is None else f"{_title_text(title)}\n{angle}")


def loaded_transmission_error(ltca, ax=None, label=None, title=None, **kwargs):
    """Loaded TE of an `LTCAResult` (um along the line of action) against pinion angle."""
    te = np.asarray(ltca.transmission_error_line) * 1e3
    return _title(_te_curve(ax, ltca.pinion_angle, te, "loaded TE along line of action (um)", label, **kwargs), title)


def load_sharing(ltca, ax=None, title=None):
    """Share of the load carried by each tooth pair over the cycle."""
    ax = _axes(ax)
    angle = np.degrees(np.asarray(ltca.pinion_angle))
    share = np.asarray(ltca.load_share)
    for k, column in zip(np.asarray(ltca.pair_index), share.T):
        if column.max() > 1e-6:
            ax.plot(angle, column, label=f"pair {k}")
    ax.set_xlabel("pinion angle (deg)")
    ax.set_ylabel("load share (-)")
    ax.set_ylim(-0.02, 1.02)
    ax.legend()
    ax.grid(True, alpha=0.3)
    return _title(ax, title)


def contact_pattern(tca, ltca, ax=None, quantity="pressure", cmap="inferno", title=None):
    """Loaded contact pattern on the pinion flank over the cycle: every loaded point at its
    axial position (mm) and roll length (mm), coloured by Hertz pressure (MPa) or load (N)."""
    ax = _axes(ax)
    n = np.asarray(ltca.loads).shape[-1]
    value = np.asarray(ltca.pressure if quantity == "pressure" else ltca.loads)
    loaded = np.asarray(ltca.loads) > 1e-6 * np.asarray(ltca.loads).max()
    z = np.broadcast_to(np.asarray(ltca.slice_z), value.shape)
    s = np.asarray(tca.pinion_parameter)[..., :n]
    order = np.argsort(value[loaded])
    sc = ax.scatter(z[loaded][order], s[loaded][order], c=value[loaded][order], s=12, cmap=cmap)
    ax.figure.colorbar(sc, ax=ax, label="Hertz pressure (MPa)" if quantity == "pressure" else "load (N)")
    ax.set_xlabel("axial position z (mm)")
    ax.set_ylabel("pinion roll length s (mm)")
    ax.grid(True, alpha=0.3)
    return _title(ax, title)


def mesh_stiffness(ltca, ax=None, iso=None, title=None):
    """Tangent and secant mesh stiffness per unit face width over the cycle (N/(mm·um)),
    with ISO 6336's c_gamma_alpha as a line when `iso` (an `IsoStiffness`) is given."""
    ax = _axes(ax)
    angle = np.degrees(np.asarray(ltca.pinion_angle))
    ax.plot(angle, np.asarray(ltca.mesh_stiffness_tangent), label="tangent dP/dd")
    ax.plot(angle, np.asarray(ltca.mesh_stiffness_secant), "--", label="secant P/d")
    if iso is not None:
        ax.axhline(float(np.asarray(iso.mesh_stiffness)), color="k", lw=0.8, label="ISO 6336 c_gamma_alpha")
    ax.set_xlabel("pinion angle (deg)")
    ax.set_ylabel("mesh stiffness (N/(mm um))")
    ax.legend()
    ax.grid(True, alpha=0.3)
    return _title(ax, title)


def impact_force_map(torques_Nm, speeds_rpm, force_N, regime=None, ax=None, cmap="magma", title=None):
    """Mesh-in impact force F_s (N) over pinion torque (N·m, x) × speed (rpm, y), as
    `gearjax sweep` or `ImpactSweep` give it (`force_N[torque][speed]`); grid points with
    edge contact (`regime[torque][speed] == "edge"`) are marked with crosses. With a single
    torque or speed the map is drawn as curves against the other axis."""
    return _title(_force_map(torques_Nm, speeds_rpm, force_N, regime, ax, cmap,
                             ("pinion torque (N m)", "{:g} N m"), ("pinion speed (rpm)", "{:g} rpm")), title, False)


def regime_map(values, torques_Nm, force_N, regime, name="tip relief (um)", ax=None, cmap="magma", title=None):
    """The regime map: impact force (colour) and edge contact (crosses) over a design
    parameter (x; e.g. the tip relief amount of each design of a `design_sweep`) × pinion
    torque (N·m, y); `force_N[design][torque]`, `regime[design][torque]` ("surface" |
    "edge"). The boundary between plain cells and crosses is the torque at which the
    modification's clearance closes at the tip edge."""
    return _title(_force_map(values, torques_Nm, force_N, regime, ax, cmap, (name, name + " = {:g}"),
                             ("pinion torque (N m)", "{:g} N m")), title, False, True)


def _cell_edges(v):
    """Edges of the cells of sorted grid values `v`: midway between neighbours, and the first
    and last values themselves (the outer cells are half cells)."""
    v = np.asarray(v, float)
    return np.concatenate([v[:1], 0.5 * (v[1:] + v[:-1]), v[-1:]])


def _force_map(x, y, force_N, regime, ax, cmap, x_axis, y_axis):
    """F[x][y] as a colour map with edge contacts crossed, or as curves when an axis has
    one value; `x_axis`, `y_axis` are (label, legend format)."""
    ax = _axes(ax)
    x, y, f = np.asarray(x, float), np.asarray(y, float), np.asarray(force_N, float).reshape(np.size(x), np.size(y))
    edge = np.zeros(f.shape, bool) if regime is None else (np.asarray(regime) == "edge").reshape(f.shape)
    if x.size > 1 and y.size > 1:
        # Cells end at the outermost computed points: nothing is drawn where nothing was computed.
        mesh = ax.pcolormesh(_cell_edges(x), _cell_edges(y), f.T, shading="flat", cmap=cmap)
        ax.figure.colorbar(mesh, ax=ax, label="impact force F_s (N)")
        xx, yy = np.meshgrid(x, y, indexing="ij")
        ax.plot(xx.ravel(), yy.ravel(), ".", color="0.5", ms=3, clip_on=False)
        ax.plot(xx[edge], yy[edge], "x", color="c", ms=6, label="edge contact", clip_on=False)
        ax.set_xlim(x.min(), x.max())
        ax.set_ylim(y.min(), y.max())
        ax.set_xlabel(x_axis[0])
        ax.set_ylabel(y_axis[0])
        if edge.any():
            ax.legend(loc="lower left")
    else:
        along_x = x.size > 1
        line_axis, curve_axis = (x_axis, y_axis) if along_x else (y_axis, x_axis)
        abscissa, curves = (x, y) if along_x else (y, x)
        for k, value in enumerate(curves):
            values, crossed = (f[:, k], edge[:, k]) if along_x else (f[k, :], edge[k, :])
            (line,) = ax.plot(abscissa, values, "o-", label=curve_axis[1].format(value))
            ax.plot(abscissa[crossed], values[crossed], "x", color=line.get_color(), ms=9)
        ax.set_xlabel(line_axis[0])
        ax.set_ylabel("impact force F_s (N); x = edge contact")
        ax.legend()
    ax.grid(True, alpha=0.3)
    return ax


def harris_map(torques_Nm, lte_peak_to_peak_um, labels=None, ax=None, title=None):
    """Harris map: loaded TE peak-to-peak (um along the line of action) against pinion
    torque (N·m), one curve per design (`lte_peak_to_peak_um[design][torque]`)."""
    ax = _axes(ax)
    curves = np.atleast_2d(np.asarray(lte_peak_to_peak_um, float))
    for k, curve in enumerate(curves):
        ax.plot(np.asarray(torques_Nm, float), curve, "o-", label=None if labels is None else labels[k])
    ax.set_xlabel("pinion torque (N m)")
    ax.set_ylabel("LTE peak-to-peak (um)")
    if labels is not None:
        ax.legend()
    ax.grid(True, alpha=0.3)
    return _title(ax, title, False)


def optimisation_history(results, ax=None, title=None):
    """Convergence of one or more `OptimizationResult`s: the search's best objective (N or
    mm/s, at the search's accuracy) against objective evaluations, one curve per result
    (evaluations spread evenly over its steps); the certified value of its best design
    (at the certification accuracy) as a marker at its last evaluation count, and the
    initial design's objective as a dotted line."""
    ax = _axes(ax)
    results = [results] if hasattr(results, "history") else list(results)
    for r in results:
        per_step = r.evaluations / max(r.steps, 1)
        (line,) = ax.plot(per_step * np.arange(1, len(r.history) + 1), r.history, ".-", label=f"{r.method}: search")
        if r.certified_objective is not None:
            ax.plot([r.evaluations], [r.certified_objective], "*", ms=12, color=line.get_color(),
                    label=f"{r.method}: certified at '{r.certification.accuracy}'")
    ax.axhline(results[0].initial_objective, color="k", ls=":", lw=1.0, label="initial design")
    ax.set_xscale("log")
    ax.set_xlabel("objective evaluations")
    ax.set_ylabel("best objective (N, or mm/s for a velocity)")
    ax.legend()
    ax.grid(True, alpha=0.3, which="both")
    return _title(ax, title)


def pareto_front(result, x: int = 0, y: int = 1, colour: int | None = 2, ax=None, cmap="viridis", title=None):
    """A `ParetoResult`'s front: quantity `x` against quantity `y` (indices into
    `result.quantities`), a third as the colour; certified values where there are (the
    search's otherwise), the archive's other designs in grey."""
    ax = _axes(ax)
    names = [f"{q} ({u})" for q, u in zip(result.quantities, result.units)]
    ax.scatter(result.archive_values[:, x], result.archive_values[:, y], s=5, color="0.8",
               label=f"evaluated ('{result.accuracy}')")
    _, values = result.front
    which = "certified" if result.certified is not None else "search"
    accuracy = result.certification_accuracy if result.certified is not None else result.accuracy
    c = None if colour is None or values.shape[1] <= colour else values[:, colour]
    points = ax.scatter(values[:, x], values[:, y], c=c, cmap=cmap if c is not None else None, edgecolor="k", zorder=3,
                        label=f"front, {which} at '{accuracy}'")
    if c is not None:
        ax.figure.colorbar(points, ax=ax, label=names[colour])
    ax.set_xlabel(names[x])
    ax.set_ylabel(names[y])
    ax.legend(fontsize="small")
    ax.grid(True, alpha=0.3)
    return _title(ax, title)
