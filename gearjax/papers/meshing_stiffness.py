r"""Seeds 000/003's meshing stiffness $K$ (Table 1: concave and convex tooth, meshing in and
out) computed on the loaded contact of the generated surfaces. Imports the core; nothing in
the core imports it.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._custom_types import Array, ArrayLike
from ..accuracy import Accuracy
from ..geometry.double_arc import DoubleArcGearPair
from ..operating import OperatingPoint
from ..pipeline import simulate
from ..scene import Scene

#: Table 1's columns: (contact zone, the pair meshing in or out); zone 1 is the concave
#: driving tooth, zone 0 the convex one (`ZONE_NAMES`).
STIFFNESS_COLUMNS = ((1, "in"), (1, "out"), (0, "in"), (0, "out"))


class MeshingStiffness(eqx.Module):
    """Table 1's meshing stiffness $K$ computed on the loaded contact of the generated
    surfaces (`meshing_stiffness`), in the order of `STIFFNESS_COLUMNS`.

    Attributes:
        stiffness: $K$ of each column (N/mm), mean over its events in the cycle (NaN where
            the cycle holds none).
        events: the number of hand-overs of the column's kind in the cycle (a pair of the
            zone entering, or leaving, the load).
        pinion_angle: the first such hand-over of each column (rad; NaN where none).
    """

    stiffness: Array
    events: Array
    pinion_angle: Array


def meshing_stiffness(pair: DoubleArcGearPair, torque: ArrayLike, accuracy: Accuracy | str = "default") -> MeshingStiffness:
    r"""The seed's meshing stiffness $K$ (Table 1) as gearjax defines and computes it.

    The seed takes $K$ from other works and does not define it; formula (7) divides it
    among the $n$ meshing points, so it is read here as the **whole mesh's stiffness** seen
    along the normal of the pair that meshes in or out: at each grid position where a pair
    of the zone carries load and did not at the two positions before (meshing in), or
    does and will not at the two positions after (meshing out),

    $$K = \frac{\mathrm dT_2/\mathrm d\Theta}{m_k^2}$$

    with the loaded contact's tangent mesh stiffness $\mathrm dT_2/\mathrm d\Theta$ (N·mm/rad,
    `PointContactLoads.mesh_stiffness`, every pair in contact) and that pair's arm $m_k$ (mm,
    its normal displacement per radian of the gear's lag). A pair's own stiffness would not
    do: under the Hertz law it vanishes as $F^{1/3}$ at its first contact. $K$ is taken at the
    hand-over itself, the angle where the pair's closing $m_k\Theta - e_k$ crosses zero
    between two grid positions, extrapolated linearly from the two positions on the side
    where the pair carries no load (there $K$ is smooth; on the other side the pair's own
    stiffness grows as its load to the 1/3, with an unbounded slope at the hand-over).

    Args:
        pair: the pair (the seed's: `gearjax.papers.double_arc.seed_pair()`).
        torque: pinion torque (N·mm; the seed's: 1e5).
        accuracy: of the loaded contact (at least 21 face slices, `ToothSectionCompliance`).

    Returns:
        `MeshingStiffness` (NumPy-resolved; not traced).
    """
    result = simulate(Scene(pair, operating=OperatingPoint(torque=torque), accuracy=accuracy))
    point = result.ltca.point_contact
    n = len(np.asarray(result.tca.pinion_angle))
    zone, index = np.asarray(result.tca.pair_zone), np.asarray(result.tca.pair_index)

    def periodic(x, fill):
        """`x` (pos, pair) over the cycle's pitch, two positions added at each end: a pitch
        on, pair k stands where pair k − 1 stood (same zone); `fill` where that pair is
        outside the window."""
        def shifted(rows, by):
            out = np.full_like(rows, fill)
            for j in range(len(index)):
                partner = np.flatnonzero((zone == zone[j]) & (index == index[j] + by))
                if partner.size:
                    out[:, j] = rows[:, partner[0]]
            return out
        return np.concatenate([shifted(x[n - 2:], 1), x, shifted(x[:2], -1)])

    def extend(x):
        """A quantity of the whole mesh, (pos,), over the cycle's pitch with two positions
        added at each end: the same a pitch on."""
        return np.concatenate([x[n - 2:], x, x[:2]])

    pitch = 2 * math.pi / pair.teeth[0]
    angle = np.asarray(result.tca.pinion_angle)
    angle = extend(angle) + np.concatenate([np.full(2, -pitch), np.zeros(n), np.full(2, pitch)])
    on = periodic(np.asarray(point.loads), 0.0) > 0.0
    arms, gaps = periodic(np.asarray(point.arms), 1.0), periodic(np.asarray(point.gaps), np.inf)
    rotation, mesh = extend(np.asarray(point.rotation)), extend(np.asarray(point.mesh_stiffness))
    stiffness = mesh[:, None] / arms**2
    closing = rotation[:, None] * arms - np.where(np.isfinite(gaps), gaps, 0.0)  # > 0: the pair is loaded
    values, counts, angles = [], [], []
    for z, kind in STIFFNESS_COLUMNS:
        found = []
        step = -1 if kind == "in" else 1  # towards the positions where the pair is unloaded
        for k in np.flatnonzero(zone == z):
            for p in range(2, n + 2):  # the cycle's own positions, each hand-over once
                near, far = p + step, p + 2 * step
                if not on[p, k] or on[near, k] or on[far, k] or not np.isfinite(gaps[[near, far], k]).all():
                    continue
                # the hand-over, where the pair's closing crosses zero between p and `near`,
                # and K there extrapolated from the unloaded side, where it is smooth (on the
                # loaded side the pair's own stiffness grows as its load to the 1/3)
                t = closing[near, k] / (closing[near, k] - closing[p, k])
                found.append((stiffness[near, k] + t * (stiffness[near, k] - stiffness[far, k]),
                              angle[near] + t * (angle[p] - angle[near])))
        counts.append(len(found))
        values.append(float(np.mean([f[0] for f in found])) if found else math.nan)
        # the hand-overs' angles wrapped into the cycle's pitch, the first of them
        wrapped = [angle[2] + (f[1] - angle[2]) % pitch for f in found]
        angles.append(float(min(wrapped)) if found else math.nan)
    return MeshingStiffness(jnp.asarray(values), jnp.asarray(counts), jnp.asarray(angles))
