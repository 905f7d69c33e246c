"""Hard cases of the double-circular-arc family; what is
checked and why is in `test_hard_cases.py`.

The 24/24 pair (m_n 4, β 15°, b 55): the axial pitch error Δ_α at 0 and at the bounds
±0.05 P_x the constructor allows, rigid TCA (the family's only stage; it has no
modification or torque to differentiate with respect to). Then random designs through the
same program.
"""

import numpy as np
import pytest
from _cases import (
    bad_fields,
    count_failures,
    failure_kinds,
    missed_contacts,
    one_by_one,
    random_count,
    random_double_arc,
)

import gearjax as gj
from gearjax.papers.double_arc import SEED_CASE

WINDOW = (-2, -1, 0, 1, 2, 3)
RANDOM = random_count(40)


def _cases():
    def pair(delta=0.0):
        return gj.DoubleArcGearPair(SEED_CASE["teeth"], SEED_CASE["normal_module"], SEED_CASE["helix_angle_deg"],
                                    SEED_CASE["face_width"], delta)

    limit = 0.05 * float(pair().axial_pitch) * (1 - 1e-9)
    return {"dca_delta_alpha_0": pair(0.0), "dca_delta_alpha_max": pair(limit), "dca_delta_alpha_min": pair(-limit)}


CASES = list(_cases())


@pytest.fixture(scope="module")
def double_arc():
    """TCA results of the cases then the random designs."""
    rng = np.random.default_rng(20261128)
    designs = list(_cases().values()) + [random_double_arc(rng, pairs=WINDOW) for _ in range(RANDOM)]
    return one_by_one([gj.Scene(p, pairs=WINDOW, accuracy="fast") for p in designs])


@pytest.mark.parametrize("i, name", list(enumerate(CASES)), ids=CASES)
def test_double_arc_stays_finite_and_converged(double_arc, i, name):
    assert bad_fields(double_arc, i) == []
    assert bool(np.asarray(double_arc.tca.valid[i]).any(axis=(1, 2)).all())  # a contact at every position
    assert missed_contacts(double_arc, i) == 0


@pytest.fixture(scope="module")
def random_failures(double_arc):
    """Failures of the random designs (`_cases.failures`); prints the counts."""
    return count_failures({"double_arc": (double_arc, len(CASES), len(CASES) + RANDOM)})


@pytest.mark.parametrize("kind", failure_kinds({}, ("non-finite", "tca")))
def test_random_designs_are_finite_and_converged(random_failures, kind):
    """40 random double-circular-arc designs (24/24: module, β, face width, Δ_α; TCA),
    seeded: every output finite, every solve converged, one kind of failure per test."""
    failed = random_failures["double_arc"][kind]
    assert failed == [], f"{len(failed)} of {RANDOM} designs: {failed}"
