"""Pareto-front utilities on host arrays: the non-dominated filter, the hypervolume, a
spread-out subset.

Every function minimises: rows are points, columns quantities in their minimised sense
(a maximised quantity negated, `Quantity.sense`). Rows with a non-finite entry are never
on a front and add no volume.
"""

from __future__ import annotations

import numpy as np


def nondominated(points) -> np.ndarray:
    """Mask of the rows no other row dominates (no worse in every column and better in one);
    of equal rows the first is kept."""
    F = np.atleast_2d(np.asarray(points, float))
    finite = np.all(np.isfinite(F), axis=1)
    keep = finite.copy()
    for i in np.flatnonzero(finite):
        others = F[finite]
        no_worse = np.all(others <= F[i], axis=1)
        better = np.any(others < F[i], axis=1)
        if np.any(no_worse & better):
            keep[i] = False
    for i in np.flatnonzero(keep):  # equal rows: the first
        same = np.flatnonzero(keep & np.all(F == F[i], axis=1))
        keep[same[same > i]] = False
    return keep


def hypervolume(points, reference) -> float:
    """The volume dominated by the points and bounded by `reference` (the Lebesgue measure
    of $\\bigcup_p [p, r]$), exact: slices along the last column (Hypervolume by Slicing
    Objectives, While et al., IEEE TEC 10, 2006), a sweep in two dimensions."""
    F = np.atleast_2d(np.asarray(points, float))
    r = np.asarray(reference, float)
    if F.shape[-1] != r.shape[0]:
        raise ValueError(f"reference has {r.shape[0]} entries; the points have {F.shape[-1]} columns")
    F = F[np.all(np.isfinite(F), axis=1) & np.all(F < r, axis=1)]
    return _volume(F[nondominated(F)] if len(F) else F, r)


def _volume(F: np.ndarray, r: np.ndarray) -> float:
    if len(F) == 0:
        return 0.0
    if F.shape[1] == 1:
        return float(r[0] - F[:, 0].min())
    if F.shape[1] == 2:
        F = F[np.argsort(F[:, 0], kind="stable")]
        volume, height = 0.0, r[1]
        for x, y in F:
            if y < height:
                volume += (r[0] - x) * (height - y)
                height = y
        return float(volume)
    F = F[np.argsort(F[:, -1], kind="stable")]
    volume = 0.0
    for i in range(len(F)):
        upper = F[i + 1, -1] if i + 1 < len(F) else r[-1]
        if upper > F[i, -1]:
            below = F[: i + 1, :-1]
            volume += _volume(below[nondominated(below)], r[:-1]) * (upper - F[i, -1])
    return float(volume)


def spread(points, count: int) -> np.ndarray:
    """Indices of at most `count` rows spread over the points: each quantity's lowest row
    first, then, one at a time, the row farthest (scaled by each column's range) from those
    chosen (a farthest-point selection)."""
    F = np.atleast_2d(np.asarray(points, float))
    if len(F) <= count:
        return np.arange(len(F))
    width = np.ptp(F, axis=0)
    scaled = (F - F.min(axis=0)) / np.where(width > 0, width, 1.0)
    chosen = list(dict.fromkeys(int(np.argmin(F[:, j])) for j in range(F.shape[1])))[:count]
    distance = np.min(np.linalg.norm(scaled[:, None] - scaled[chosen][None], axis=-1), axis=1)
    while len(chosen) < count:
        i = int(np.argmax(distance))
        chosen.append(i)
        distance = np.minimum(distance, np.linalg.norm(scaled - scaled[i], axis=-1))
    return np.asarray(chosen)


def distinct(designs, atol: float = 1e-9) -> np.ndarray:
    """Mask keeping the first of rows equal within `atol` (mm) in every column."""
    D = np.atleast_2d(np.asarray(designs, float))
    keep = np.ones(len(D), bool)
    for i in range(len(D)):
        if keep[i]:
            same = np.all(np.abs(D[i + 1:] - D[i]) <= atol, axis=1)
            keep[i + 1:] &= ~same
    return keep
