r"""Seed 000/003's meshing impact force of double-circular-arc gears, formula (7).

$$F_s = \frac{v_s}{\cos\alpha}\sqrt{\frac{K}{n}\,\frac{J_1J_2}{J_1R_2^2 + J_2R_1^2}}$$

with the impact velocity $v_s$, the meshing stiffness $K$, $n$ meshing points, and the gear
inertias $J_i$ about their axes with the pitch radii $R_i$. The seed's Tables 1 and 2 come
out to four digits with $n = 3$, solid discs $J = \pi\rho bR^4/2$ at the reference radius
($\rho = 7.85\times10^{-6}$ kg/mm³) and the tabulated $K$ and $v_s$ — but only in the seed's
mixed units: $v$ in mm/s, $K$ in N/mm and $J$ in kg·mm². Then $K J/R^2$ is in N·kg/mm² and
$v\sqrt{\cdot}$ in mm/s·√(N·kg)/mm, which is $\sqrt{1000}$ N, not N (1 kg = 1e-3 N·s²/mm).
In consistent units (N, mm, s, t) the same inputs give forces $\sqrt{1000} \approx 31.6$
times smaller. `paper_units=True` reproduces the tables, labelled; everything else uses
consistent units.

The four impact states, their radii (formulas 9–26) and the general first-contact search on
the real surfaces are not implemented yet (the rack's concave side is needed first).
"""

from __future__ import annotations

import math

import jax.numpy as jnp

from .._custom_types import ArrayLike, Scalar
from .._numerics import as_float
from .._validate import check_range
from .energy import gear_inertia

#: Seed 000, Tables 1 and 2 (t1 < t2): columns concave mesh-in, concave mesh-out, convex
#: mesh-in, convex mesh-out. Stiffness N/mm, velocity mm/s, force N (the seed's units).
#: (Seed 003 prints Table 1's stiffness row in another order; seed 000 has it right.)
SEED_TABLES = {
    "stiffness": (1.8084e6, 7.685e5, 1.771e6, 7.1088e5),
    "table1": {"velocity": (61.92, 61.92, 36.33, 36.33), "force": (4.816e4, 3.1392e4, 2.796e4, 1.7715e4)},
    "table2": {"velocity": (81.57, 81.57, 60.01, 60.01), "force": (6.344e4, 4.1354e4, 4.6185e4, 2.9261e4)},
}
#: The seed case: m_n 4 mm, z 24/24, b 55 mm, beta 15 deg, alpha 24 deg, n = 3.
SEED_CASE = {"normal_module": 4.0, "teeth": (24, 24), "face_width": 55.0, "helix_angle_deg": 15.0,
             "pressure_angle_deg": 24.0, "meshing_points": 3}


def impact_force(
    velocity: ArrayLike,
    stiffness: ArrayLike,
    meshing_points: int,
    inertia: ArrayLike,
    radius: ArrayLike,
    pressure_angle_deg: ArrayLike = 24.0,
    *,
    paper_units: bool = False,
) -> Scalar:
    """Formula (7). Consistent units: velocity mm/s, stiffness N/mm, inertia t·mm², radii
    mm, force N. With `paper_units=True` the inertia is in kg·mm² and the result is the
    seed's number (labelled "paper units"; $\\sqrt{1000}$ times the force in N)."""
    check_range("velocity", velocity, 0.0, None, unit="mm/s")
    check_range("stiffness", stiffness, 0.0, None, low_inclusive=False, unit="N/mm")
    check_range("inertia", inertia, 0.0, None, low_inclusive=False)
    check_range("radius", radius, 0.0, None, low_inclusive=False, unit="mm")
    if not isinstance(meshing_points, int) or meshing_points < 1:
        raise ValueError(f"meshing_points must be an integer >= 1; got {meshing_points!r}")
    j = as_float(inertia)
    r = as_float(radius)
    j1, j2 = j[..., 0], j[..., 1]
    r1, r2 = r[..., 0], r[..., 1]
    mass = j1 * j2 / (j1 * r2**2 + j2 * r1**2)
    alpha = as_float(pressure_angle_deg) * (math.pi / 180.0)
    return as_float(velocity) / jnp.cos(alpha) * jnp.sqrt(as_float(stiffness) / meshing_points * mass)


def seed_tables(paper_units: bool = True) -> dict:
    """Tables 1 and 2 recomputed from formula (7) for the seed case (see module docstring)."""
    c = SEED_CASE
    radius = c["normal_module"] * c["teeth"][0] / (2 * math.cos(math.radians(c["helix_angle_deg"])))
    density = 7.85e-6 if paper_units else 7.85e-9  # kg/mm^3 (paper) or t/mm^3
    j = gear_inertia(density, c["face_width"], radius, 0.0)  # solid disc, no hub
    inertia = jnp.stack([j, j])
    radii = jnp.asarray([radius, radius])
    out = {"reference_radius_mm": radius, "inertia": float(j), "units": "paper (kg mm^2, sqrt(1000) N)" if paper_units else "N"}
    for name in ("table1", "table2"):
        forces = [
            float(impact_force(v, k, c["meshing_points"], inertia, radii, c["pressure_angle_deg"]))
            for v, k in zip(SEED_TABLES[name]["velocity"], SEED_TABLES["stiffness"])
        ]
        out[name] = {"paper": list(SEED_TABLES[name]["force"]), "gearjax": forces}
    return out
