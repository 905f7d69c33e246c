"""Hard cases of the curvilinear family; what is checked and
why is in `test_hard_cases.py`.

Seed 002's 20/30 pair: the tooth-trace radius from just above b/2 (its lower limit) to
1e9 b (a straight spur tooth), with a modification, TCA, LTCA and impact, and the
derivatives with respect to the modification and the torque. Then random curvilinear
designs through the same forward program.
"""

import jax.numpy as jnp
import numpy as np
import pytest
from _cases import (
    PAPER_UM,
    bad_fields,
    count_failures,
    derivatives,
    failure_kinds,
    forward,
    missed_contacts,
    random_count,
    random_curvilinear,
    scene,
)

import gearjax as gj

WINDOW = (-2, -1, 0, 1, 2)
RANDOM = random_count(260)


def _cases():
    width = 20.0
    y = PAPER_UM / 1000.0 * (2.0 / 5.0)  # the seed 001 optimum scaled to m = 2 mm
    y[5] = 4.0
    radii = {"curvilinear_seed002": 12.0, "curvilinear_Rt_to_half_b": 0.5 * width * 1.0001,
             "curvilinear_Rt_1e9_b": 1e9 * width}
    return {name: (gj.CurvilinearGearPair((20, 30), 2.0, 20.0, width, radius), y, dict(torque_Nm=100.0))
            for name, radius in radii.items()}


CASES = list(_cases())


@pytest.fixture(scope="module")
def curvilinear():
    """Results (TCA, LTCA, impact) of the cases then the random designs; derivatives of the
    cases."""
    rng = np.random.default_rng(20261127)
    cases = list(_cases().values())
    designs = cases + [random_curvilinear(rng, pairs=WINDOW) for _ in range(RANDOM)]
    result = forward([scene(p, y, pairs=WINDOW, **kw) for p, y, kw in designs])
    value, tangent, _ = derivatives([scene(p, y, pairs=WINDOW, effects=("ltca",), **kw) for p, y, kw in cases])
    return result, value, tangent


@pytest.mark.parametrize("i, name", list(enumerate(CASES)), ids=CASES)
def test_curvilinear_stays_finite_and_converged(curvilinear, i, name):
    result, value, tangent = curvilinear
    assert bad_fields(result, i) == []
    assert missed_contacts(result, i) == 0
    assert gj.enum_name(result.ltca.result)[i] == "successful"
    assert bool(np.all(np.asarray(result.ltca.converged[i])))
    assert gj.enum_name(result.impact.result)[i] == "successful", int(result.impact.search_steps[i])
    assert np.all(np.isfinite(np.asarray(value[i]))) and np.all(np.isfinite(np.asarray(tangent[i])))


def test_curvilinear_straight_limit_is_the_spur_pair(curvilinear):
    """R_t = 1e9 b: the curvilinear pair's unloaded TE equals the spur involute pair's of
    the same data and modification (TCA only) to 1e-3 of its peak-to-peak + 1e-9 rad."""
    result, _, _ = curvilinear
    pair, y, _ = _cases()["curvilinear_Rt_1e9_b"]
    spur = gj.InvoluteGearPair((20, 30), 2.0, 20.0, 0.0, 20.0)
    s = gj.Scene(spur, gj.FlankModification.from_vector(jnp.asarray(y)), pairs=WINDOW, accuracy="fast")
    expected = np.asarray(gj.simulate(s).tca.transmission_error)
    got = np.asarray(result.tca.transmission_error[CASES.index("curvilinear_Rt_1e9_b")])
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-3 * np.ptp(expected) + 1e-9)


@pytest.fixture(scope="module")
def random_failures(curvilinear):
    """Failures of the random designs (`_cases.failures`); prints the counts."""
    return count_failures({"curvilinear": (curvilinear[0], len(CASES), len(CASES) + RANDOM)})


# No failure is known on these 260 designs at the `fast` preset (the first-contact
# searches converge since the TCA checks that an edge contact is a maximum of the offset).
RANDOM_KNOWN = {}


@pytest.mark.parametrize("kind", failure_kinds(RANDOM_KNOWN))
def test_random_designs_are_finite_and_converged(random_failures, kind):
    """260 random curvilinear designs (20/30: module, α, face width, R_t from 0.55 b to 5 b,
    shifts, modification, errors, torque; TCA, LTCA, impact), seeded: every output finite,
    every solve converged, one kind of failure per test."""
    failed = random_failures["curvilinear"][kind]
    assert failed == [], f"{len(failed)} of {RANDOM} designs: {failed}"
