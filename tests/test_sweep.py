"""Batched load and impact sweeps and the regime-transition bisection: values against single
runs, the speed law, units and argument checks."""

import json

import equinox as eqx
import numpy as np
import pytest

import gearjax.sweep
from gearjax import Accuracy, OperatingPoint, Scene, simulate
from gearjax.cli import main
from gearjax.impact import ImpactRegime
from gearjax.papers.seed001 import paper_optimum
from gearjax.scene_file import DEFAULT_SCENE_TOML, parse_scene
from gearjax.sweep import design_sweep, impact_sweep, load_sweep, regime_transition

TINY = Accuracy(positions_per_pitch=4, face_slices=3)


def test_load_sweep_matches_single_scenes_in_either_unit(seed_pair):
    """The vmapped sweep against one `simulate` per torque (a loop); N·m and N·mm inputs
    give the same torques, so the same numbers."""
    scene = Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=1.0), accuracy=TINY)
    torques_Nm = [0.0, 300.0, 1000.0]
    sweep = load_sweep(scene, torques_Nm=torques_Nm)
    again = load_sweep(scene, [0.0, 3.0e5, 1.0e6])
    np.testing.assert_array_equal(np.asarray(sweep.ltca.transmission_error), np.asarray(again.ltca.transmission_error))
    np.testing.assert_array_equal(np.asarray(sweep.ltca.torque), [0.0, 3.0e5, 1.0e6])
    np.testing.assert_allclose(np.asarray(sweep.torques_Nm), torques_Nm, rtol=1e-15)
    for i, t in enumerate(torques_Nm):
        single = simulate(Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=t), accuracy=TINY)).ltca
        np.testing.assert_allclose(
            np.asarray(sweep.ltca.transmission_error[i]), np.asarray(single.transmission_error), rtol=1e-9, atol=1e-15
        )


#: The default scene at the `fast` accuracy: the API and the command-line tests sweep the
#: same scene structure and grid shape, so they share one compiled program.
FAST_SCENE = DEFAULT_SCENE_TOML.replace('accuracy = "default"', 'accuracy = "fast"')
GRID = ([400.0, 1600.0], [2500.0, 5000.0])


@pytest.fixture(scope="module")
def impact_grid():
    scene, _ = parse_scene(FAST_SCENE)
    return scene, impact_sweep(scene, torques_Nm=GRID[0], speeds_rpm=GRID[1])


def test_impact_sweep_equals_single_runs_and_follows_the_speed_law(impact_grid):
    """Torque × speed grid in one call: every grid point equals `simulate` of the same scene
    at that operating point (1e-9), surface contact at 400 N·m and edge contact at
    1600 N·m for the paper optimum; and from the grid alone, the force at twice the speed is
    $2^{2n/(n+1)}$ times the force (energy method, $F \\propto v^{2n/(n+1)}$) at every load."""
    scene, sweep = impact_grid
    impact = sweep.impact
    assert impact.force.shape == (2, 2)
    np.testing.assert_allclose(np.asarray(sweep.torques_Nm), GRID[0], rtol=1e-15)
    np.testing.assert_allclose(np.asarray(sweep.speeds_rpm), GRID[1], rtol=1e-15)
    np.testing.assert_array_equal(np.asarray(impact.regime == ImpactRegime.edge), [[False, False], [True, True]])
    for i, t in enumerate(GRID[0]):
        for j, n in enumerate(GRID[1]):
            at = eqx.tree_at(lambda s: s.operating, scene, OperatingPoint(torque_Nm=t, speed_rpm=n))
            single = simulate(at).impact
            for field in ("force", "velocity", "pinion_angle", "approach"):
                np.testing.assert_allclose(float(getattr(impact, field)[i, j]), float(getattr(single, field)),
                                           rtol=1e-9, err_msg=f"{field} at {t} N·m, {n} rpm")
            np.testing.assert_allclose(np.asarray(impact.pinion_point[i, j]), np.asarray(single.pinion_point), rtol=1e-9)
        exponent = float(impact.stiffness.exponent[i, 0])
        assert float(impact.force[i, 1] / impact.force[i, 0]) == pytest.approx(2.0 ** (2 * exponent / (exponent + 1)), rel=1e-9)


def test_design_sweep_rows_equal_each_designs_own_sweeps(impact_grid):
    """Two designs (the paper optimum and six times its root relief) in one call: each row
    equals `impact_sweep` of that design alone (1e-9), the speed-free sweep (the Harris
    map's input) gives the same LTE, and the deeper root relief (the pinion's root meets
    the gear's tip at mesh-in) keeps flank-on-flank contact at 1600 N·m, where the paper
    optimum strikes with the gear's tip edge."""
    scene, sweep = impact_grid
    relieved = eqx.tree_at(lambda s: s.modification.root_relief, scene, 6.0 * scene.modification.root_relief)
    designs = design_sweep([scene, relieved], torques_Nm=GRID[0], speeds_rpm=GRID[1])
    harris = design_sweep([scene, relieved], torques_Nm=GRID[0])
    assert designs.impact.force.shape == (2, 2, 2) and harris.impact is None
    for k, single in enumerate((sweep, impact_sweep(relieved, torques_Nm=GRID[0], speeds_rpm=GRID[1]))):
        np.testing.assert_allclose(np.asarray(designs.impact.force[k]), np.asarray(single.impact.force), rtol=1e-9)
        np.testing.assert_array_equal(np.asarray(designs.impact.regime == ImpactRegime.edge)[k],
                                      np.asarray(single.impact.regime == ImpactRegime.edge))
        np.testing.assert_allclose(np.asarray(designs.ltca.lte_peak_to_peak_line[k]),
                                   np.asarray(single.ltca.lte_peak_to_peak_line), rtol=1e-9)
    np.testing.assert_allclose(np.asarray(harris.ltca.lte_peak_to_peak_line),
                               np.asarray(designs.ltca.lte_peak_to_peak_line), rtol=1e-9)
    edge = np.asarray(designs.impact.regime == ImpactRegime.edge)
    assert edge[0, 1].all() and not edge[1, 1].any()


def test_cli_sweep_writes_the_grid_as_json_npz_and_plots(impact_grid, tmp_path, capsys):
    """`gearjax sweep` of the same scene and grid (given as a range and as a list): the
    documented keys, [torque][speed] nesting, values equal to the API's, the arrays in
    sweep.npz and the two figures."""
    _, sweep = impact_grid
    path = tmp_path / "scene.toml"
    path.write_text(FAST_SCENE)
    out = tmp_path / "run"
    assert main(["sweep", str(path), "--torque-Nm", "400:1600:2", "--speed-rpm", "2500,5000",
                 "--out", str(out), "--json", "--plot"]) == 0
    printed = json.loads(capsys.readouterr().out)["sweep"]
    written = json.loads((out / "sweep.json").read_text())["sweep"]
    assert printed["torque_Nm"] == written["torque_Nm"] == GRID[0]
    assert written["speed_rpm"] == pytest.approx(GRID[1], rel=1e-15)
    np.testing.assert_allclose(written["impact_force_N"], np.asarray(sweep.impact.force), rtol=1e-12)
    assert written["impact_regime"] == [["surface", "surface"], ["edge", "edge"]]
    assert len(written["lte_peak_to_peak_um"]) == 2 and all(v > 0 for v in written["lte_peak_to_peak_um"])
    arrays = np.load(out / "sweep.npz")
    np.testing.assert_array_equal(arrays["impact_force_N"], np.asarray(written["impact_force_N"]))
    for name in ("sweep_force_map.png", "sweep_harris.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("devices", ["gpu0", [], [0, 1]])
def test_sweeps_reject_bad_devices_before_computing(seed_pair, no_compute, devices):
    scene = Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=400.0), effects=("impact",), accuracy=TINY)
    with pytest.raises(ValueError, match="^devices must be None, 'all' or a"):
        impact_sweep(scene, torques_Nm=[400.0], speeds_rpm=[1000.0], devices=devices)


@pytest.mark.parametrize(
    "option, value, match",
    [
        ("--torque-Nm", "", "--torque-Nm: empty list"),
        ("--torque-Nm", "100,abc", "--torque-Nm: 'abc' is not a number"),
        ("--torque-Nm", "100,-5", "--torque-Nm: values must be finite numbers >= 0; got -5"),
        ("--torque-Nm", "nan", "--torque-Nm: values must be finite numbers >= 0; got nan"),
        ("--speed-rpm", "1000:5000:0", "--speed-rpm: the count of start:stop:count must be an integer >= 1; got 0"),
        ("--speed-rpm", "5000:1000:3", "--speed-rpm: the range stop 1000 is below its start 5000"),
        ("--speed-rpm", "1:2", "--speed-rpm: a range is start:stop:count"),
    ],
)
def test_cli_sweep_rejects_bad_lists_with_status_2(option, value, match, capsys):
    args = {"--torque-Nm": "400", "--speed-rpm": "5000"} | {option: value}
    assert main(["sweep", "--torque-Nm", args["--torque-Nm"], "--speed-rpm", args["--speed-rpm"]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("gearjax: error: ") and match in err[0], err


@pytest.fixture
def no_compute(monkeypatch):
    """Fail if a sweep gets as far as computing: the checks must come first."""

    def refuse(*args, **kwargs):
        raise AssertionError("computed before the arguments were checked")

    monkeypatch.setattr(gearjax.sweep, "_load_sweep", refuse)
    monkeypatch.setattr(gearjax.sweep, "_impact_sweep", refuse)
    monkeypatch.setattr(gearjax.sweep, "simulate", refuse)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(), r"exactly one of torques \(N·mm\) and torques_Nm \(N·m\); got neither"),
        (dict(torques=[1.0], torques_Nm=[1.0]), r"exactly one of torques .* got both"),
        (dict(torques=[]), r"^torques must be a non-empty 1-D array of pinion torques \(N·mm\)"),
        (dict(torques_Nm=[[1.0, 2.0]]), r"^torques_Nm must be a non-empty 1-D array .*\(N·m\)"),
        (dict(torques_Nm=5.0), r"^torques_Nm must be a non-empty 1-D array"),
        (dict(torques=[1.0e5, -1.0]), r"^torques must be in \[0, 1e\+12\] N·mm; got -1 N·mm"),
        (dict(torques_Nm=[-2.0]), r"^torques_Nm must be in \[0, 1e\+09\] N·m; got -2 N·m"),
        (dict(torques_Nm=[100.0, float("nan")]), r"^torques_Nm must be a finite number"),
    ],
)
def test_load_sweep_rejects_bad_torques_before_computing(seed_pair, no_compute, kwargs, match):
    scene = Scene(seed_pair, accuracy=TINY)
    with pytest.raises(ValueError, match=match):
        load_sweep(scene, **kwargs)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(high=1.6e6), r"exactly one of low \(N·mm\) and low_Nm \(N·m\); got neither"),
        (dict(low=4.0e5, low_Nm=400.0, high=1.6e6), r"exactly one of low .* got both"),
        (dict(low_Nm=400.0, high=1.6e6, high_Nm=1600.0), r"exactly one of high .* got both"),
        (dict(low_Nm=-1.0, high_Nm=1600.0), r"^low_Nm must be in \[0, 1e\+09\] N·m"),
        (dict(low=4.0e5, high=float("inf")), r"^high must be a finite number"),
        (dict(low_Nm=[400.0], high_Nm=1600.0), r"^low_Nm must be a scalar torque \(N·m\)"),
        (dict(low_Nm=1600.0, high_Nm=400.0), r"^low_Nm must be below high_Nm"),
        (dict(low_Nm=400.0, high_Nm=1600.0, tolerance=0.0), r"^tolerance must be in \(0, 1\)"),
    ],
)
def test_regime_transition_rejects_bad_bounds_before_computing(seed_pair, no_compute, kwargs, match):
    scene = Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=400.0), effects=("impact",), accuracy=TINY)
    with pytest.raises(ValueError, match=match):
        regime_transition(scene, **kwargs)


def test_regime_transition_needs_the_impact_effect(seed_pair, no_compute):
    scene = Scene(seed_pair, operating=OperatingPoint(torque_Nm=400.0), accuracy=TINY)
    with pytest.raises(ValueError, match="effects including 'impact'"):
        regime_transition(scene, low_Nm=400.0, high_Nm=1600.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(torques_Nm=[400.0]), r"exactly one of speeds \(rad/s\) and speeds_rpm \(rpm\); got neither"),
        (dict(torques_Nm=[400.0], speeds=[1.0], speeds_rpm=[1.0]), r"exactly one of speeds .* got both"),
        (dict(torques_Nm=[400.0], speeds_rpm=[]), r"^speeds_rpm must be a non-empty 1-D array of pinion speeds \(rpm\)"),
        (dict(torques_Nm=[400.0], speeds_rpm=[1000.0, -5.0]), r"^speeds_rpm must be in \[0, .*\] rpm; got -5 rpm"),
        (dict(torques_Nm=[400.0], speeds=[float("nan")]), r"^speeds must be a finite number"),
        (dict(torques_Nm=[-1.0], speeds_rpm=[1000.0]), r"^torques_Nm must be in \[0, 1e\+09\] N·m"),
    ],
)
def test_impact_sweep_rejects_bad_grids_before_computing(seed_pair, no_compute, kwargs, match):
    scene = Scene(seed_pair, paper_optimum(), operating=OperatingPoint(torque_Nm=400.0), effects=("impact",), accuracy=TINY)
    with pytest.raises(ValueError, match=match):
        impact_sweep(scene, **kwargs)


def test_impact_sweep_needs_the_impact_effect(seed_pair, no_compute):
    scene = Scene(seed_pair, operating=OperatingPoint(torque_Nm=400.0), accuracy=TINY)
    with pytest.raises(ValueError, match="impact_sweep needs a scene with effects including 'impact'"):
        impact_sweep(scene, torques_Nm=[400.0], speeds_rpm=[1000.0])
