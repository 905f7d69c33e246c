"""Matplotlib figures (optional extra: `pip install gearjax[plot]`).

Every function draws on an `Axes` (a new figure when `ax` is None) and returns it. Lengths
are shown in mm, transmission error in micrometres along the line of action, angles in
degrees.
"""

from __future__ import annotations

import math

import numpy as np

from .tca import ContactKind


def _axes(ax):
    if ax is not None:
        return ax
    try:
        import matplotlib.pyplot as plt
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ImportError("gearjax.plot needs matplotlib: pip install 'gearjax[plot]'") from err
    _, ax = plt.subplots(figsize=(6.4, 4.0))
    return ax


def transmission_error(result, ax=None, label=None, **kwargs):
    """Unloaded TE of a `TCAResult` (um along the line of action) against the pinion angle
    (deg)."""
    te = np.asarray(result.transmission_error_line) * 1e3
    return _te_curve(ax, result.pinion_angle, te, "TE along line of action (um)", label, **kwargs)


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


def contact_path(result, ax=None, tolerance=1e-4, cmap="viridis"):
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
    return ax


def separation_map(result, position: int, ax=None):
    """Initial separation (um) of every slice of every pair at one position."""
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
    ax.set_title(f"pinion angle {math.degrees(float(np.asarray(result.pinion_angle)[position])):.2f} deg")
    ax.legend()
    ax.grid(True, alpha=0.3)
    return ax


def loaded_transmission_error(ltca, ax=None, label=None, **kwargs):
    """Loaded TE of an `LTCAResult` (um along the line of action) against pinion angle."""
    te = np.asarray(ltca.transmission_error_line) * 1e3
    return _te_curve(ax, ltca.pinion_angle, te, "loaded TE along line of action (um)", label, **kwargs)


def load_sharing(ltca, ax=None):
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
    return ax


def contact_pattern(tca, ltca, ax=None, quantity="pressure", cmap="inferno"):
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
    return ax


def mesh_stiffness(ltca, ax=None, iso=None):
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
    return ax
