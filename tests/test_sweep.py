"""Batched load and impact sweeps and the regime-transition bisection: values against single
runs, the speed law, units and argument checks."""

import json
import signal
import subprocess
import sys
import textwrap

import equinox as eqx
import numpy as np
import pytest

import gearjax.sweep.loads
import gearjax.sweep.transition
from gearjax import Accuracy, OperatingPoint, Scene, simulate
from gearjax.cli import main
from gearjax.impact import ImpactRegime
from gearjax.papers.seed001 import paper_optimum
from gearjax.io.scene_file import DEFAULT_SCENE_TOML, parse_scene
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
GRID = (np.linspace(400.0, 1600.0, 7).tolist(), [2500.0, 5000.0])
#: Root relief of the designs of `design_sweep`, as multiples of the paper optimum's: the
#: deeper the relief, the later the gear's tip edge strikes (none below 1600 N·m at 6×).
ROOT_RELIEF_FACTORS = (1.0, 2.0, 6.0)


@pytest.fixture(scope="module")
def impact_grid():
    scene, _ = parse_scene(FAST_SCENE)
    return scene, impact_sweep(scene, torques_Nm=GRID[0], speeds_rpm=GRID[1])


def test_impact_sweep_equals_single_runs_and_follows_the_speed_law(impact_grid):
    """Torque × speed grid in one call: every grid point equals `simulate` of the same scene
    at that operating point (1e-9; the strike's velocity, force and approach 1e-7, see
    below), surface contact at 400 N·m and edge contact from
    600 N·m for the paper optimum (its transition is at ~570 N·m at 'fast'); and from the grid alone, the force at twice the speed is
    $2^{2n/(n+1)}$ times the force (energy method, $F \\propto v^{2n/(n+1)}$) at every load."""
    scene, sweep = impact_grid
    impact = sweep.impact
    assert impact.force.shape == (7, 2)
    np.testing.assert_allclose(np.asarray(sweep.torques_Nm), GRID[0], rtol=1e-15)
    np.testing.assert_allclose(np.asarray(sweep.speeds_rpm), GRID[1], rtol=1e-15)
    np.testing.assert_array_equal(np.asarray(impact.regime == ImpactRegime.edge),
                                  np.repeat(np.asarray(GRID[0])[:, None] >= 600.0, 2, axis=1))
    for i, t in enumerate(GRID[0]):
        for j, n in enumerate(GRID[1]):
            at = eqx.tree_at(lambda s: s.operating, scene, OperatingPoint(torque_Nm=t, speed_rpm=n))
            single = simulate(at).impact
            # The velocity holds the loaded TE's rate, a central difference at h ~ 1e-6 rad
            # (decision 0015): the two programs round the loaded TE apart by ~1e-17 rad, so
            # the rate by ~1e-7 of itself and v_n, F_s and the approach by up to ~1e-8.
            for field, rtol in (("force", 1e-7), ("velocity", 1e-7), ("pinion_angle", 1e-9), ("approach", 1e-7)):
                np.testing.assert_allclose(float(getattr(impact, field)[i, j]), float(getattr(single, field)),
                                           rtol=rtol, err_msg=f"{field} at {t} N·m, {n} rpm")
            np.testing.assert_allclose(np.asarray(impact.pinion_point[i, j]), np.asarray(single.pinion_point), rtol=1e-9)
        exponent = float(impact.stiffness.exponent[i, 0])
        assert float(impact.force[i, 1] / impact.force[i, 0]) == pytest.approx(2.0 ** (2 * exponent / (exponent + 1)), rel=1e-9)


@pytest.fixture(scope="module")
def design_grid(impact_grid):
    scene, _ = impact_grid
    designs = [eqx.tree_at(lambda s: s.modification.root_relief, scene, f * scene.modification.root_relief)
               for f in ROOT_RELIEF_FACTORS]
    return designs, design_sweep(designs, torques_Nm=GRID[0], speeds_rpm=GRID[1])


def test_design_sweep_rows_equal_each_designs_own_sweeps(impact_grid, design_grid):
    """Three designs (the paper optimum and twice and six times its root relief) in one
    call: each row equals `impact_sweep` of that design alone (1e-9), the speed-free sweep
    (the Harris map's input) gives the same LTE, and the deepest root relief (the pinion's
    root meets the gear's tip at mesh-in) keeps flank-on-flank contact at 1600 N·m, where
    the paper optimum strikes with the gear's tip edge."""
    _, sweep = impact_grid
    designs, grid = design_grid
    harris = design_sweep(designs, torques_Nm=GRID[0])
    assert grid.impact.force.shape == (3, 7, 2) and harris.impact is None
    for k, design in enumerate(designs):
        single = sweep if k == 0 else impact_sweep(design, torques_Nm=GRID[0], speeds_rpm=GRID[1])
        np.testing.assert_allclose(np.asarray(grid.impact.force[k]), np.asarray(single.impact.force), rtol=1e-9)
        np.testing.assert_array_equal(np.asarray(grid.impact.regime == ImpactRegime.edge)[k],
                                      np.asarray(single.impact.regime == ImpactRegime.edge))
        np.testing.assert_allclose(np.asarray(grid.ltca.lte_peak_to_peak_line[k]),
                                   np.asarray(single.ltca.lte_peak_to_peak_line), rtol=1e-9)
    np.testing.assert_allclose(np.asarray(harris.ltca.lte_peak_to_peak_line),
                               np.asarray(grid.ltca.lte_peak_to_peak_line), rtol=1e-9)
    edge = np.asarray(grid.impact.regime == ImpactRegime.edge)
    assert edge[0, -1].all() and not edge[2, -1].any()


def test_regime_map_boundary_agrees_with_the_batched_regime_transition(design_grid):
    """The regime map of `design_sweep` (regime per design and torque) against the batched
    bisection of `regime_transition` (all designs in one call): every grid torque below a
    design's bracket is surface contact, every one above it edge contact; the bracket is
    within its tolerance (1e-3 of its upper end); the regime does not depend on the speed;
    a design without a switch between the bounds (6× root relief) gets NaN; and the
    transition load rises with the root relief."""
    designs, grid = design_grid
    edge = np.asarray(grid.impact.regime == ImpactRegime.edge)
    np.testing.assert_array_equal(edge[..., 0], edge[..., 1])
    below, above = regime_transition(designs, low_Nm=400.0, high_Nm=1600.0, tolerance=1e-3)  # N·mm
    assert below.shape == above.shape == (3,)
    torques = np.asarray(GRID[0]) * 1e3
    for k in range(2):
        assert 4.0e5 <= below[k] < above[k] <= 1.6e6 and above[k] - below[k] <= 1e-3 * above[k]
        outside = (torques <= below[k]) | (torques >= above[k])
        np.testing.assert_array_equal(edge[k, outside, 0], torques[outside] >= above[k], err_msg=f"design {k}")
    assert above[0] < below[1]
    assert np.isnan(below[2]) and np.isnan(above[2]) and not edge[2].any()


def test_force_map_draws_cells_at_the_computed_points_only():
    import matplotlib  # the dev extra installs it

    matplotlib.use("Agg")
    from gearjax.io import plot

    ax = plot.impact_force_map([200.0, 600.0], [2000.0, 4000.0], [[1.0, 2.0], [3.0, 4.0]],
                               [["surface", "edge"], ["surface", "surface"]])
    assert ax.get_xlim() == (200.0, 600.0) and ax.get_ylim() == (2000.0, 4000.0)
    (mesh,) = ax.collections
    corners = mesh.get_coordinates().reshape(-1, 2)
    assert corners[:, 0].min() == 200.0 and corners[:, 0].max() == 600.0
    assert corners[:, 1].min() == 2000.0 and corners[:, 1].max() == 4000.0
    np.testing.assert_array_equal(np.asarray(mesh.get_array()).reshape(2, 2), [[1.0, 3.0], [2.0, 4.0]])
    matplotlib.pyplot.close(ax.figure)


def test_cli_sweep_writes_the_grid_as_json_npz_and_plots(impact_grid, tmp_path, capsys):
    """`gearjax sweep` of the same scene and grid (given as a range and as a list): the
    documented keys, [torque][speed] nesting, values equal to the API's, the arrays in
    sweep.npz and the two figures."""
    _, sweep = impact_grid
    path = tmp_path / "scene.toml"
    path.write_text(FAST_SCENE)
    out = tmp_path / "run"
    assert main(["sweep", str(path), "--torque-Nm", "400:1600:7", "--speed-rpm", "2500,5000",
                 "--out", str(out), "--json", "--plot"]) == 0
    printed = json.loads(capsys.readouterr().out)["sweep"]
    written = json.loads((out / "sweep.json").read_text())["sweep"]
    assert printed["torque_Nm"] == written["torque_Nm"] == GRID[0]
    assert written["speed_rpm"] == pytest.approx(GRID[1], rel=1e-15)
    np.testing.assert_allclose(written["impact_force_N"], np.asarray(sweep.impact.force), rtol=1e-12)
    assert written["impact_regime"] == [["surface", "surface"]] + [["edge", "edge"]] * 6
    assert len(written["lte_peak_to_peak_um"]) == 7 and all(v > 0 for v in written["lte_peak_to_peak_um"])
    arrays = np.load(out / "sweep.npz")
    np.testing.assert_array_equal(arrays["impact_force_N"], np.asarray(written["impact_force_N"]))
    for name in ("sweep_force_map.png", "sweep_harris.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_sweep_killed_between_chunks_resumes_to_the_uninterrupted_result(impact_grid, tmp_path, capsys):
    """`--chunk 3` over the 7 torques in a subprocess, SIGKILLed while chunk 2's line is half
    written (chunk 1 on disk): the directory is refused without `--resume` and for another
    grid (exit 2, one line naming the difference); `--resume` runs chunks 2 and 3, and the
    result equals the one-call sweep of the whole grid to rounding (1e-10: chunks of 3 are
    another batch shape than 7 at once, another compiled program, so not bit-equal; measured
    up to 1.1e-12 relative, on the first chunk, computed in the killed process)."""
    _, sweep = impact_grid
    path = tmp_path / "scene.toml"
    path.write_text(FAST_SCENE)
    out = tmp_path / "killed"
    grid = ["--torque-Nm", "400:1600:7", "--speed-rpm", "2500,5000"]
    script = textwrap.dedent(
        f"""
        import os, signal
        import jax
        jax.config.update("jax_enable_x64", True)
        jax.config.update("jax_numpy_dtype_promotion", "strict")
        from gearjax.io import rundir
        from gearjax.cli import main

        saved = rundir.RunDirectory.save

        def save(self, state, record):
            if record["step"] == 2:  # die with the line of chunk 2 half written
                with open(self.history_path, "a") as f:
                    f.write('{{"step": 2, "rows": {{"torq')
                os.kill(os.getpid(), signal.SIGKILL)
            saved(self, state, record)

        rundir.RunDirectory.save = save
        main(["sweep", {str(path)!r}, *{grid!r}, "--chunk", "3", "--out", {str(out)!r}, "--quiet"])
        """
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert proc.returncode == -signal.SIGKILL, proc.stderr[-2000:]
    lines = (out / "history.jsonl").read_text().splitlines()
    assert len(lines) == 2 and json.loads(lines[0])["rows"]["torque_Nm"] == GRID[0][:3]
    assert not (out / "sweep.json").exists()
    capsys.readouterr()
    assert main(["sweep", str(path), *grid, "--chunk", "3", "--out", str(out)]) == 2
    assert "already holds a run" in capsys.readouterr().err
    assert main(["sweep", str(path), "--torque-Nm", "400:1600:6", "--speed-rpm", "2500,5000", "--chunk", "3",
                 "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "differs in torque_Nm" in err[0], err
    assert main(["sweep", str(path), *grid, "--chunk", "3", "--out", str(out), "--resume", "--json", "--quiet"]) == 0
    printed = json.loads(capsys.readouterr().out)["sweep"]
    written = json.loads((out / "sweep.json").read_text())["sweep"]
    assert [json.loads(x)["step"] for x in (out / "history.jsonl").read_text().splitlines()] == [1, 2, 3]
    assert written["chunks"] == 3 and written["chunk_length"] == 3 and written["torque_Nm"] == GRID[0]
    # chunks of 3 loads against one program of 7: the strike's force at the cross-program
    # tolerance of the first-contact search's rates (decision 0015; 8.4e-10 seen)
    np.testing.assert_allclose(written["impact_force_N"], np.asarray(sweep.impact.force), rtol=1e-7)
    np.testing.assert_allclose(printed["impact_force_N"], written["impact_force_N"], rtol=0)
    np.testing.assert_allclose(written["lte_peak_to_peak_um"], np.asarray(sweep.ltca.lte_peak_to_peak_line) * 1e3,
                               rtol=1e-10)
    assert written["impact_regime"] == [["surface", "surface"]] + [["edge", "edge"]] * 6


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
        ("--torque-Nm", "-5,abc", "--torque-Nm: values must be finite numbers >= 0; got -5"),  # not an option
        ("--speed-rpm", "-1000:5000:3", "--speed-rpm: values must be finite numbers >= 0; got -1000"),
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
def no_compute(forbid):
    """Fail if a sweep gets as far as computing: the checks must come first."""
    forbid(gearjax.sweep.loads, "_load_sweep", "_impact_sweep")
    forbid(gearjax.sweep.transition, "_transition")


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
