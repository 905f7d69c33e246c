"""Seed 001 (mesh-in impact of involute helical gears): its case, its optimal modification,
its impact-force table and the note on its centre distance. Imports the core; nothing in the
core imports it. The reproduction itself is `tools/reproduce_seed001.py`.

The seed's printed numbers are kept as printed (micrometres, N·m, rpm) and converted to the
engine's units (mm, N·mm, rad/s) where they are used.
"""

from __future__ import annotations

import jax.numpy as jnp

from ..geometry.involute import InvoluteGearPair
from ..geometry.modification import FlankModification

#: The note every reproduction of the case carries: the seed's centre distance is impossible.
SEED_001_NOTE = (
    "seed 001 states a = 261.0 mm, which is inconsistent with beta = 27.5 deg and x1 = x2 = 0 "
    "(261.0 mm would need x1 + x2 = -2.87; it is close to r_b1 + r_b2): gearjax uses "
    "x1 = x2 = 0 and the standard a = 281.85 mm"
)

#: The seed case: teeth, normal module (mm), normal pressure angle (deg), helix angle (deg),
#: face width (mm), and its design speed (rpm, as printed).
SEED_001_CASE = {"teeth": (29, 71), "normal_module": 5.0, "pressure_angle_deg": 20.0,
                 "helix_angle_deg": 27.5, "face_width": 42.0, "speed_rpm": 5000.0}

#: Table 2: the optimal modification y1...y6 in micrometres, as printed.
TABLE2_OPTIMUM_UM = (5.9, 6.8, 3800.0, 4300.0, 6.2, 4600.0)

#: Table 4: impact force (N) of the standard and of the optimally modified pair at 5000 rpm,
#: keyed by the pinion torque in N·m as printed.
TABLE4_IMPACT_FORCE = {400.0: (3250.0, 2300.0), 1000.0: (5829.0, 1981.0), 1600.0: (8950.0, 5370.0)}


def seed_pair() -> InvoluteGearPair:
    """The seed's 29/71 pair with x1 = x2 = 0 and the standard centre distance 281.85 mm
    (see `SEED_001_NOTE`)."""
    c = SEED_001_CASE
    return InvoluteGearPair(c["teeth"], c["normal_module"], c["pressure_angle_deg"], c["helix_angle_deg"], c["face_width"])


def paper_optimum() -> FlankModification:
    """Seed 001's optimal modification (its Table 2): y = (5.9, 6.8, 3800, 4300, 6.2, 4600) um.

    Note that its tip relief length 4.3 mm exceeds the paper's own bound of 0.8 m_n = 4.0 mm.
    """
    return FlankModification.from_micrometres(jnp.array(TABLE2_OPTIMUM_UM))
