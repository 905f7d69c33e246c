"""Double-circular-arc gears (GB/T 12759): axial meshing facts (27)-(28) and the impact force
formula (7) against seed 000/003's Tables 1 and 2."""

import math

import pytest

from gearjax.geometry.double_arc import GBT12759Rack, axial_meshing
from gearjax.impact.double_arc import SEED_TABLES, impact_force, seed_tables


def test_formula_27_reproduces_the_seed_case():
    facts = axial_meshing(4.0, 15.0, 55.0)
    # the seed prints 48.55 / 41.85 / 6.70 / 6.45 mm
    assert round(float(facts.axial_pitch), 2) == 48.55
    assert round(float(facts.convex_to_concave), 2) == 41.85
    assert round(float(facts.concave_to_convex), 2) == 6.70
    assert round(float(facts.face_excess), 2) == 6.45
    assert bool(facts.condition_28)  # the case with three meshing points
    assert float(facts.axial_pitch) == pytest.approx(math.pi * 4.0 / math.sin(math.radians(15.0)), rel=1e-14)


def test_contact_height_of_the_rack():
    assert GBT12759Rack().contact_height == pytest.approx(0.545, abs=1e-4)


@pytest.mark.parametrize("table", ["table1", "table2"])
def test_formula_7_reproduces_tables_1_and_2_in_paper_units(table):
    out = seed_tables(paper_units=True)
    for paper, ours in zip(out[table]["paper"], out[table]["gearjax"]):
        assert float(f"{ours:.4g}") == pytest.approx(paper, rel=1e-3)  # four significant digits
        assert ours == pytest.approx(paper, rel=3e-4)


def test_consistent_units_are_sqrt_1000_smaller():
    paper = seed_tables(paper_units=True)
    si = seed_tables(paper_units=False)
    for table in ("table1", "table2"):
        for p, s in zip(paper[table]["gearjax"], si[table]["gearjax"]):
            assert p / s == pytest.approx(math.sqrt(1000.0), rel=1e-12)


def test_force_grows_as_the_square_root_of_stiffness_over_points():
    f1 = float(impact_force(50.0, 1e6, 3, [1e-3, 2e-3], [40.0, 60.0]))
    f2 = float(impact_force(50.0, 4e6, 3, [1e-3, 2e-3], [40.0, 60.0]))
    f3 = float(impact_force(50.0, 1e6, 12, [1e-3, 2e-3], [40.0, 60.0]))
    assert f2 == pytest.approx(2 * f1, rel=1e-12) and f3 == pytest.approx(f1 / 2, rel=1e-12)
    assert SEED_TABLES["stiffness"][0] == 1.8084e6


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: axial_meshing(0.0, 15.0, 55.0), "normal_module"),
        (lambda: axial_meshing(4.0, 0.0, 55.0), "helix_angle_deg"),
        (lambda: axial_meshing(4.0, 15.0, -1.0), "face_width"),
        (lambda: impact_force(-1.0, 1e6, 3, [1.0, 1.0], [1.0, 1.0]), "velocity"),
        (lambda: impact_force(1.0, 1e6, 0, [1.0, 1.0], [1.0, 1.0]), "meshing_points"),
        (lambda: impact_force(1.0, float("nan"), 3, [1.0, 1.0], [1.0, 1.0]), "stiffness"),
    ],
)
def test_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()
