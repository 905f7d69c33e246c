"""The mesh-in impact force converges in the face slices (`docs/impact_convergence.md`).

Designs of seed 001's pair at 1 000 N·m and 5 000 rpm whose force, before the first contact
was found continuously along the face, flipped between a flank and a tip-edge strike with
the slice count (the GA and gradient optima of that time), the paper's optimum, and the two
random designs of the study with the largest error at the `default` preset's 21 slices.
One program per slice count for all of them (`simulate_designs`); the whole study, 33 designs
at 21/41/81/161 slices, is `benchmarks/studies/impact_convergence.py`.
"""

import numpy as np
import pytest

from gearjax import Accuracy, FlankModification, OperatingPoint, Scene, enum_name, simulate_designs
from gearjax.papers.seed001 import paper_optimum

#: 81 slices, between 41 and 161 in the study, is left out to save its compilation (~40 s)
SLICES = (21, 41, 161)
#: (y1, ..., y6) in mm: root and tip relief, their lengths, crowning, unmodified length
DESIGNS = {
    "GA optimum, flipped flank/edge": [0.024398921672800573, 0.04673654456449089, 0.5, 0.5, 0.024453622726389186, 19.02663786347871],
    "gradient optimum, flipped flank/edge": [0.005, 0.005, 0.5, 0.5, 0.055428183023778506, 10.428838675732258],
    "paper optimum": None,
    "study's random 6": None,
    "study's random 18": None,
}


def _designs():
    # the study's random designs: seed 0, uniform within seed 001's bounds
    lower = np.array([0.005, 0.005, 0.5, 0.5, 0.005, 0.0])
    upper = np.array([0.075, 0.075, 4.0, 4.0, 0.075, 21.0])
    random = lower + (upper - lower) * np.random.default_rng(0).uniform(size=(19, 6))
    filled = dict(DESIGNS)
    filled["paper optimum"] = np.asarray(paper_optimum().as_vector())
    filled["study's random 6"] = random[6]
    filled["study's random 18"] = random[18]
    return np.stack([np.asarray(y, dtype=float) for y in filled.values()])


def _impact(result):
    return result.impact.force, result.impact.regime, result.impact.result


@pytest.fixture(scope="module")
def forces(seed_pair):
    designs = FlankModification.from_vector(_designs())
    out = {}
    for slices in SLICES:
        scene = Scene(seed_pair, operating=OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0), effects=("impact",),
                      accuracy=Accuracy.preset("default").replace(face_slices=slices))
        force, regime, code = simulate_designs(scene, designs, outputs=_impact, batch_size=1)
        assert set(enum_name(code)) == {"successful"}, (slices, enum_name(code))
        out[slices] = np.asarray(force), enum_name(regime)
    return out


def test_the_strike_keeps_its_regime_from_21_slices_on(forces):
    regimes = np.array([forces[n][1] for n in SLICES])
    assert (regimes == regimes[-1]).all(), dict(zip(SLICES, regimes.tolist()))
    # the designs strike both ways: the check covers flank and edge strikes
    assert {"surface", "edge"} <= set(regimes[-1])


def test_the_force_is_within_3_percent_of_161_slices_from_41_on(forces):
    finest = forces[161][0]
    for n in (41,):
        error = np.abs(forces[n][0] / finest - 1.0)
        assert error.max() <= 0.03, (n, dict(zip(DESIGNS, error.round(4).tolist())))
