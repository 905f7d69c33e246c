"""gearjax.optimize: objective, GA, gradient descent, run directories, sensitivities, CLI.

One objective structure for the whole file (seed 001 pair, `fast` accuracy, 1000 N·m,
5000 rpm), so its two compiled programs (the batch of 12 values; values and gradients of
2 designs) are compiled once and shared by every test.
"""

import dataclasses
import json
import signal
import subprocess
import sys
import textwrap

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import gearjax as gj
from gearjax import optimize as go
from gearjax.optimize.batch import (
    batch_evaluation as _batch_evaluation,
    batch_objective as _batch_objective,
    batch_quantities,
    batch_value_and_grad as _batch_value_and_grad,
)
from gearjax.papers.seed001 import paper_optimum

POPULATION = 12
STARTS = 2
GENERATIONS = 12
#: the certification accuracy of the GA runs: `fast` with finer face slices, one program
CERTIFY = gj.Accuracy.preset("fast").replace(face_slices=13)


@pytest.fixture(scope="module")
def scene(seed_pair):
    return gj.Scene(
        seed_pair, paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
        effects=("impact",), accuracy="fast",
    )


@pytest.fixture(scope="module")
def objective(scene):
    return go.Objective.create(scene)


@pytest.fixture(scope="module")
def space(scene):
    # the paper's optimum (y4 = 4.3 mm) needs a wider tip-relief-length bound than its own 4.0 mm
    return go.DesignSpace.for_scene(scene, tip_relief_length=(0.5, 4.5))


@pytest.fixture(scope="module")
def designs(space):
    """Paper optimum, a long deep relief (an earlier gradient optimum of seed 001, which
    engages flank on flank at 400-1600 N·m), and 10 random designs (mm)."""
    rng = np.random.default_rng(3)
    out = np.array(space.to_design(rng.uniform(size=(POPULATION, 6))))
    out[0] = np.asarray(paper_optimum().as_vector())
    out[1] = [0.0666, 0.0439, 1.4037, 2.4398, 0.0258, 8.8405]
    return out


@pytest.fixture(scope="module")
def batch_values(objective, designs):
    return np.asarray(_batch_objective(objective, designs))


@pytest.fixture(scope="module")
def ga_run(objective, space, tmp_path_factory):
    run_dir = tmp_path_factory.mktemp("ga")
    result = go.genetic(objective, space, config=go.GAConfig(population=POPULATION), generations=GENERATIONS,
                        seed=0, run_dir=run_dir, certify=CERTIFY)
    return result, run_dir


def _simulate(objective, design):
    return gj.simulate(objective.scene_for(design))


def test_objective_is_simulate_impact_force_and_batch_is_a_loop(objective, scene, designs, batch_values):
    # Design 1's strike point is a smooth maximum along the face, placed at a parabola's
    # vertex (`tca.face_peak`) to ~1e-9 mm by the rounding of its slope, which differs
    # between the single and the vmapped program; v_n moves ~60 mm/s per mm along the face
    # there, so the two agree to ~1e-9 on F_s.
    for i in (0, 1, 5):
        force = float(_simulate(objective, designs[i]).impact.force)
        assert batch_values[i] == pytest.approx(force, rel=1e-8)
    # Every design scores (random design 3's first-contact search is a hard one: its flank
    # contact lies inside a deep relief). A design whose stages fail scores +inf and leaves the others alone:
    # y6 = b in place of design 3, out of range inside the program (`invalid_modification`).
    assert np.all(np.isfinite(batch_values))
    broken = designs.copy()
    broken[3, 5] = float(scene.pair.face_width)
    assert gj.enum_name(gj.simulate(objective.scene_for(broken[3]), throw=False).impact.result) == "invalid_modification"
    values = np.asarray(_batch_objective(objective, broken))
    assert values[3] == np.inf
    np.testing.assert_allclose(np.delete(values, 3), np.delete(batch_values, 3), rtol=1e-12)
    # rows are independent: the same designs in another order give the same values
    order = np.arange(POPULATION)[::-1]
    assert np.asarray(_batch_objective(objective, designs[order])) == pytest.approx(batch_values[order], rel=1e-12)


@pytest.fixture(scope="module")
def regimes(objective, designs):
    return [_simulate(objective, designs[i]).impact.regime_name for i in (0, 1)]


def test_gradient_matches_central_differences_in_both_regimes(objective, space, designs, regimes):
    # the paper's optimum strikes with the tip edge at 1000 N·m; the deep relief engages flank on flank
    assert regimes == ["edge", "surface"]
    units = np.asarray(space.to_unit(designs[:2]))
    values, grads = (np.asarray(a) for a in _batch_value_and_grad(objective, space, units))
    h = 1e-5
    for k in range(2):
        probe = np.repeat(units[k][None], POPULATION, axis=0)
        for i in range(6):
            probe[2 * i, i] += h
            probe[2 * i + 1, i] -= h
        f = np.asarray(_batch_objective(objective, space.to_design(probe)))
        central = (f[0::2] - f[1::2]) / (2 * h)
        scale = np.max(np.abs(central))
        assert values[k] == pytest.approx(float(_batch_objective(objective, np.repeat(designs[k][None], POPULATION, 0))[0]), rel=1e-8)
        np.testing.assert_allclose(grads[k], central, rtol=1e-4, atol=1e-4 * scale)


def test_the_flank_branch_is_the_objective_where_the_flanks_strike_first(objective, designs, batch_values):
    """`Objective.evaluate(..., flank_branch=True)` (what the switch method minimises): where
    its switching function s is > 0 the flanks strike first and J of the flank branch is
    J itself; where the ordinary evaluation strikes with the tip edge, s <= 0 (negative,
    or zero where the flank branch's contact stops at the gear tip). With `actual`, the same
    program gives the ordinary evaluation's force, velocity and regime besides (what the
    Pareto front's archive holds)."""
    import jax

    flank = jax.jit(lambda ds: jax.lax.map(lambda d: objective.evaluate(d, flank_branch=True, actual=True), ds))(
        jnp.asarray(designs))
    ordinary = _batch_evaluation(objective, designs)  # the batch program of `batch_values`
    switch, edge = np.asarray(flank.switch)[:, 0, 0], np.asarray(ordinary.edge)[:, 0, 0]
    ok = np.isfinite(batch_values) & np.isfinite(np.asarray(flank.objective))
    zero = 1e-6  # mm
    flanks = ok & (switch > zero)
    assert np.all(np.isfinite(switch[ok])) and 0 < np.sum(flanks) and np.sum(edge[ok]) > 0
    assert not np.any(edge[flanks]) and np.all(switch[ok & edge] <= zero)
    # two programs' first-contact searches, each stopped at its root tolerance
    np.testing.assert_allclose(np.asarray(flank.objective)[flanks], batch_values[flanks], rtol=1e-6)
    assert ordinary.switch is None and ordinary.actual_force is None
    actual = flank.actual()
    for name in ("force", "velocity"):  # the same stages in two programs, each stopped at its root tolerance
        np.testing.assert_allclose(np.asarray(getattr(actual, name))[ok], np.asarray(getattr(ordinary, name))[ok],
                                   rtol=1e-6)
    np.testing.assert_array_equal(np.asarray(actual.edge), np.asarray(ordinary.edge))


def test_ga_best_never_worsens_and_improves_on_the_first_population(ga_run, space):
    result, run_dir = ga_run
    history = np.asarray(result.history)
    assert np.all(np.diff(history) <= 0.0)
    assert history[-1] < history[0]
    assert result.evaluations == POPULATION * GENERATIONS
    records = [json.loads(line) for line in (run_dir / "history.jsonl").read_text().splitlines()]
    assert len(records) == GENERATIONS
    evaluated = np.array([r["designs_mm"] for r in records])
    assert evaluated.shape == (GENERATIONS, POPULATION, 6)
    assert space.contains(evaluated)
    # the best of the first record is the best of its evaluated values
    assert records[0]["best_objective"] == pytest.approx(min(records[0]["objective"]), rel=0, abs=0)
    # the search's best is the best value evaluated; the result is the best certified
    # candidate, which need not be the search's best (see the certification tests below)
    assert history[-1] == pytest.approx(min(min(r["objective"]) for r in records), rel=0, abs=0)


def test_ga_is_reproducible_and_a_killed_run_resumes_to_the_same_result(ga_run, objective, space, tmp_path):
    result, run_dir = ga_run
    killed = tmp_path / "killed"
    script = textwrap.dedent(
        f"""
        import os, signal
        import jax
        jax.config.update("jax_enable_x64", True)
        import gearjax as gj
        from gearjax import optimize as go
        from gearjax.optimize import run as run_module
        from gearjax.papers.seed001 import paper_optimum, seed_pair

        saved = run_module.RunDirectory.save

        def save(self, state, record):
            if record["step"] == 5:
                # die between the history line and the state of step 5: the worst moment
                with open(self.history_path, "a") as f:
                    f.write('{{"step": 5, "partial')
                os.kill(os.getpid(), signal.SIGKILL)
            saved(self, state, record)

        run_module.RunDirectory.save = save
        scene = gj.Scene(seed_pair(), paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
                         effects=("impact",), accuracy="fast")
        objective = go.Objective.create(scene)
        space = go.DesignSpace.for_scene(scene, tip_relief_length=(0.5, 4.5))
        go.genetic(objective, space, config=go.GAConfig(population={POPULATION}), generations={GENERATIONS},
                   seed=0, run_dir={str(killed)!r})
        """
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=900)
    assert proc.returncode == -signal.SIGKILL, proc.stderr[-2000:]
    lines = (killed / "history.jsonl").read_text().splitlines()
    assert len(lines) == 5 and lines[-1].startswith('{"step": 5, "partial')
    with pytest.raises(ValueError, match="resume"):
        go.genetic(objective, space, config=go.GAConfig(population=POPULATION), generations=GENERATIONS,
                   seed=0, run_dir=killed)
    resumed = go.genetic(objective, space, config=go.GAConfig(population=POPULATION), generations=GENERATIONS,
                         seed=0, run_dir=killed, resume=True, certify=CERTIFY)
    assert resumed.history == result.history
    np.testing.assert_array_equal(resumed.best_design, result.best_design)
    full = [json.loads(x) for x in (run_dir / "history.jsonl").read_text().splitlines()]
    again = [json.loads(x) for x in (killed / "history.jsonl").read_text().splitlines()]
    assert [r["designs_mm"] for r in again] == [r["designs_mm"] for r in full]
    assert [r["objective"] for r in again] == [r["objective"] for r in full]
    assert [r["random_key"] for r in again] == [r["random_key"] for r in full]
    # a resumed run must be the same run
    with pytest.raises(ValueError, match="differs in seed"):
        go.genetic(objective, space, config=go.GAConfig(population=POPULATION), generations=GENERATIONS,
                   seed=1, run_dir=killed, resume=True)


def test_gradient_descent_lowers_the_objective_from_a_poor_start(objective, space):
    poor = np.asarray(space.lower)  # the least relief the bounds allow: hard edge contact
    result = go.gradient_descent(objective, space, config=go.GradientConfig(starts=STARTS, iterations=12),
                                 seed=0, initial=np.stack([poor, poor + 0.25 * np.asarray(space.width)]),
                                 certify="fast")  # the search's accuracy: certified values are its own
    start = result.history[0]
    assert np.isfinite(start)
    # 3 025 -> 2 520 N by iteration 6, where both starts stall (30 iterations give the
    # same); with the first contact taken at the slices it had gone below 0.8 of the start
    assert result.best_objective < 0.9 * start
    assert np.all(np.diff(result.history) <= 0.0)
    assert space.contains(result.best_design)
    assert result.gradient_evaluations == result.evaluations == STARTS * result.steps
    assert result.certification.accuracy == "fast" and result.certified_objective == result.best_objective


def test_the_result_is_the_best_certified_candidate(ga_run, objective):
    """The GA's result is chosen among its best design and the 5 best distinct members of
    the final population by the objective at the certification accuracy, which is
    `simulate`'s impact force at that accuracy; the run directory keeps the certification."""
    result, run_dir = ga_run
    cert = result.certification
    # the search's 6 candidates, best first, then the initial design unless it is one of them
    assert cert.accuracy == "custom" and cert.designs.shape[0] in (6, 7) and cert.designs.shape[1] == 6
    assert len({tuple(d) for d in cert.designs}) == cert.designs.shape[0]
    assert cert.objective[0] == result.history[-1] and np.all(np.diff(cert.objective[:6]) >= 0.0)
    assert any(np.allclose(d, result.initial_design, rtol=0, atol=1e-12) for d in cert.designs)
    assert not np.allclose(cert.certified, cert.objective, rtol=1e-6)  # another accuracy, other values
    best = int(np.argmin(cert.certified))
    np.testing.assert_array_equal(result.best_design, cert.designs[best])
    assert result.best_objective == cert.objective[best] and result.certified_objective == cert.certified[best]
    scene = objective.scene_for(cert.designs[best])
    force = float(gj.simulate(dataclasses.replace(scene, accuracy=CERTIFY)).impact.force)
    assert force == pytest.approx(result.certified_objective, rel=1e-8)  # see the first test
    stored = json.loads((run_dir / "certification.json").read_text())
    assert stored["certified"] == cert.certified.tolist()


def test_the_search_starts_from_the_scene_and_never_ends_worse(ga_run, objective, space):
    """The scene's design (the paper optimum, inside this file's bounds) is the first
    population's first member, is certified with the candidates, and the result is
    certified no worse than it."""
    result, run_dir = ga_run
    first = json.loads((run_dir / "history.jsonl").read_text().splitlines()[0])
    np.testing.assert_allclose(first["designs_mm"][0], result.initial_design, rtol=0, atol=1e-12)
    assert first["objective"][0] == pytest.approx(result.initial_objective, rel=1e-12)
    cert = result.certification
    own = next(i for i, d in enumerate(cert.designs) if np.allclose(d, result.initial_design, rtol=0, atol=1e-12))
    assert result.certified_objective <= cert.certified[own]
    assert result.best_source == ("initial" if np.allclose(result.best_design, result.initial_design, atol=1e-12)
                                  else "search")


def test_a_search_that_finds_nothing_better_returns_the_initial_design(ga_run, objective, space):
    """A GA of one generation whose population is the least relief the bounds allow (hard
    edge contact) cannot beat a scene whose design is the file's GA result: the result is
    the scene's design, certified, and says so."""
    best = ga_run[0]
    good = eqx.tree_at(lambda o: o.scene.modification, objective, gj.FlankModification.from_vector(best.best_design))
    poor = np.repeat(np.asarray(space.lower)[None], POPULATION, axis=0)
    result = go.genetic(good, space, config=go.GAConfig(population=POPULATION), generations=1, seed=0,
                        initial=poor, certify=CERTIFY)
    assert result.history[0] > result.initial_objective  # the search's best is worse than the start
    assert result.best_source == "initial"
    np.testing.assert_array_equal(result.best_design, best.best_design)
    assert result.certified_objective == pytest.approx(best.certified_objective, rel=1e-10)


def test_a_scene_without_a_modification_starts_from_the_unmodified_pair(scene, space, objective):
    """An unmodified pair is optimised over the design space; its initial objective is the
    unmodified pair's force (zero relief amounts: the same flanks)."""
    plain = go.Objective.create(dataclasses.replace(scene, modification=None))
    unmodified = np.asarray(gj.FlankModification().as_vector())
    np.testing.assert_array_equal(np.asarray(plain.scene.modification.as_vector()), unmodified)
    result = go.genetic(plain, space, config=go.GAConfig(population=POPULATION), generations=1, seed=0,
                        certify=None)
    np.testing.assert_array_equal(result.initial_design, unmodified)
    assert result.initial_objective == pytest.approx(float(_simulate(objective, unmodified).impact.force), rel=1e-8)
    assert result.best_objective <= result.initial_objective
    assert not space.contains(unmodified)  # below the amounts' lower bounds: not in the population


def test_certification_settings_are_checked_before_the_search(objective, space):
    with pytest.raises(ValueError, match="certify must be"):
        go.genetic(objective, space, generations=1, certify="exact")
    with pytest.raises(ValueError, match="certify_top"):
        go.gradient_descent(objective, space, certify_top=0)


def test_sensitivities_agree_with_the_energy_method_the_descent_gradient_and_differences(objective, space, designs,
                                                                                          regimes):
    """`sensitivities` (∂J with respect to the design, the loads, the speed and the errors)
    on both sides of the surface/edge switch: the paper's optimum strikes with the gear's
    tip edge, the deep relief flank on flank (`regimes`). The two designs go in one
    call: the gradient descent's program of 2 starts, compiled once for both tests."""
    assert regimes == ["edge", "surface"]
    _, grads = _batch_value_and_grad(objective, space, np.asarray(space.to_unit(designs[:2])))
    # central differences in the torque, the two designs side by side in one batch
    rows = np.repeat(designs[:2], POPULATION // 2, axis=0)
    h = 1e-4 * float(objective.torques[0])  # N·mm

    def at_torque(torque):
        return np.asarray(_batch_objective(eqx.tree_at(lambda o: o.torques, objective, jnp.array([torque])), rows))

    t = float(objective.torques[0])
    central = (at_torque(t + h) - at_torque(t - h))[:: POPULATION // 2] / (2 * h) * 1e3  # per N·m
    both = go.sensitivities(objective, designs[:2], space)
    assert isinstance(both, list) and len(both) == 2
    for k, s in enumerate(both):
        impact = _simulate(objective, designs[k]).impact
        assert s["objective"] == pytest.approx(float(impact.force), rel=1e-8)  # see the first test
        n = float(impact.stiffness.exponent)
        # F_s = ((n+1)/2 m v^2)^(n/(n+1)) K^(1/(n+1)) with v proportional to the speed
        assert s["speed"]["log_derivative"] == pytest.approx(2 * n / (n + 1), rel=1e-6)
        per_width = np.array([e["per_bound_width"] for e in s["parameters"].values()])
        # The same program at designs that differ by the unit-cube round trip (1e-16): on
        # the deep relief (k = 1) the gradients differed by 1.7e-5 and 5.3e-5 relative in
        # two runs since the strike point moves continuously along the face, so its
        # derivative is sensitive to a rounding-level change of the design there (open).
        np.testing.assert_allclose(per_width, np.asarray(grads[k]), rtol=3e-4)
        # the scene file's units: per µm of an amount (y1, y2, y5), per mm of a length
        gradient = np.array([e["gradient"] for e in s["parameters"].values()])
        np.testing.assert_allclose(gradient * [1e3, 1e3, 1, 1, 1e3, 1], per_width / np.asarray(space.width), rtol=1e-12)
        assert s["loads"][0]["gradient_per_Nm"] == pytest.approx(central[k], rel=1e-3)
        assert set(s["errors"]) == {"base_pitch_deviation_um", "pitch_deviation_um", "misalignment_um"}
        assert all(np.isfinite(v) for v in s["errors"].values())
    assert "speed" in go.sensitivity_table(both[0])
    for bad in (designs[0][:5], designs[:0], np.full(6, np.nan)):
        with pytest.raises(ValueError, match="design"):
            go.sensitivities(objective, bad, space)


def test_every_quantity_is_simulates_and_aggregates_from_one_evaluation(objective, scene, designs, batch_values):
    """The batch program returns the whole `Evaluation`: J, and the loaded TE peak-to-peak
    (µm), the largest pressure and the mean mesh stiffness (maximised: J holds its
    negative) of `simulate` at the same design, each the objective of an `Objective` of
    that quantity."""
    evaluation = _batch_evaluation(objective, designs)
    np.testing.assert_array_equal(np.asarray(evaluation.objective), batch_values)
    ltca = _simulate(objective, designs[0]).ltca
    expected = {"lte": 1e3 * float(ltca.lte_peak_to_peak_line), "pressure": float(jnp.max(ltca.pressure)),
                "stiffness": -float(ltca.mean_mesh_stiffness), "force": float(batch_values[0])}
    for name, value in expected.items():
        other = go.Objective.create(scene, quantity=name)
        assert float(other.aggregated(evaluation)[0]) == pytest.approx(value, rel=1e-8), name
        assert float(objective.aggregated(evaluation, name)[0]) == pytest.approx(value, rel=1e-8), name
    assert 0.5 < expected["lte"] < 20.0 and 500.0 < expected["pressure"] < 3000.0 and expected["stiffness"] < -5.0
    # the same program, in chunks of its batch: natural-sense aggregates, +inf on a failed design
    broken = designs[:3].copy()
    broken[2, 5] = float(scene.pair.face_width)
    q = batch_quantities(objective, broken, (("lte", "mean"), ("stiffness", "max")), rows=POPULATION)
    assert q[0] == pytest.approx([expected["lte"], -expected["stiffness"]], rel=1e-12)
    assert np.all(np.isfinite(q[:2])) and np.all(q[2] == np.inf) and q.shape == (3, 2)


def test_a_duty_cycle_weights_its_loads_by_time_share_or_takes_the_worst_one(scene):
    """Aggregation over three loads of a hand-made evaluation (two error samples): the
    time-weighted mean of the samples' means, the worst case, and +inf if an entry failed."""
    force = jnp.array([[1000.0, 1200.0], [1500.0, 1500.0], [2000.0, 2400.0]])
    zeros = jnp.zeros_like(force)
    evaluation = go.Evaluation(jnp.zeros(()), force, force, zeros, zeros, zeros, zeros, zeros, jnp.asarray(0))
    shares = go.Objective.create(scene, torques_Nm=[400.0, 1000.0, 1600.0], weights=[2.0, 1.0, 1.0])
    assert float(shares.value(evaluation)) == pytest.approx(0.5 * 1100.0 + 0.25 * 1500.0 + 0.25 * 2200.0, rel=1e-14)
    worst = go.Objective.create(scene, torques_Nm=[400.0, 1000.0, 1600.0], aggregate="max")
    assert float(worst.value(evaluation)) == 2200.0
    failed = eqx.tree_at(lambda e: e.failed, evaluation, jnp.asarray(1))
    assert float(shares.value(failed)) == np.inf


def test_each_load_runs_at_its_own_speed(objective, scene, designs):
    """A duty cycle's speed per load reaches the impact: the file's objective structure at
    2500 rpm (its batch program) against `simulate` at that speed."""
    slow = go.Objective.create(scene, speeds_rpm=[2500.0])
    np.testing.assert_allclose(np.asarray(slow.speeds), [2500.0 * np.pi / 30.0], rtol=1e-15)
    forces = np.asarray(_batch_objective(slow, designs))
    scene_slow = objective.scene_for(designs[0], speed=2500.0 * np.pi / 30.0)
    assert forces[0] == pytest.approx(float(gj.simulate(scene_slow).impact.force), rel=1e-8)
    assert forces[0] < float(_batch_objective(objective, designs)[0])  # a slower strike is a softer one
    three = go.Objective.create(scene, torques_Nm=[400.0, 1000.0, 1600.0], speeds_rpm=[3000.0])
    np.testing.assert_array_equal(np.asarray(three.speeds), np.full(3, 3000.0 * np.pi / 30.0))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(tip_relief=(0.05, 0.01)), "lower < upper"),
        (dict(crowning=(0.0, float("nan"))), "finite"),
        (dict(tip_relief_length=(0.5, 40.0)), "active flank"),
        (dict(unmodified_length=(0.0, 42.0)), "face width"),
        (dict(root_relief_length=(0.0, 2.0)), "lower bound of root_relief_length"),
        (dict(bogus=(0.0, 1.0)), "unknown design parameter"),
    ],
)
def test_bad_bounds_are_rejected(scene, kwargs, match):
    with pytest.raises(ValueError, match=match):
        go.DesignSpace.for_scene(scene, **kwargs)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(torques_Nm=[]), "non-empty"),
        (dict(torques_Nm=[400.0, -1.0]), "torques_Nm"),
        (dict(torques_Nm=[400.0, 1000.0], weights=[1.0]), "one weight per load"),
        (dict(torques_Nm=[400.0, 1000.0], weights=[0.0, 0.0]), "positive"),
        (dict(quantity="energy"), "quantity"),
        (dict(aggregate="median"), "aggregate"),
        (dict(torques_Nm=[400.0, 1000.0], speeds_rpm=[1000.0, 2000.0, 3000.0]), r"speeds_rpm must hold one .* per load \(2\)"),
        (dict(speeds_rpm=[-5.0]), "speeds_rpm"),
        (dict(speeds=[100.0], speeds_rpm=[1000.0]), "give the speeds once"),
    ],
)
def test_bad_objective_input_is_rejected(scene, kwargs, match):
    with pytest.raises(ValueError, match=match):
        go.Objective.create(scene, **kwargs)


def test_scene_without_torque_and_small_population_are_rejected(seed_pair):
    with pytest.raises(ValueError, match="torque"):
        go.Objective.create(gj.Scene(seed_pair, paper_optimum()))
    with pytest.raises(ValueError, match="population"):
        go.GAConfig(population=1)


def _scene_file(tmp_path, optimize: str) -> str:
    from gearjax.io.scene_file import DEFAULT_SCENE_TOML

    text = DEFAULT_SCENE_TOML.replace('accuracy = "default"', 'accuracy = "fast"') + "\n[optimize]\n" + optimize
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize(
    "optimize, field",
    [
        ("method = 'annealing'\n", "[optimize] method:"),
        ("objective = 'noise'\n", "[optimize] objective:"),
        ("loads_Nm = []\n", "[optimize] loads_Nm:"),
        ("loads_Nm = [-400.0]\n", "[optimize] loads_Nm:"),
        ("loads_Nm = [400.0, 1000.0]\nload_weights = [1.0]\n", "weight"),
        ("loads_Nm = [400.0, 1000.0]\nspeeds_rpm = [1000.0, 2000.0, 3000.0]\n", "[optimize] speeds_rpm"),
        ("population = 1\n", "[optimize] population:"),
        ("tip_relief_um = [50.0, 10.0]\n", "tip_relief"),
        ("colour = 'red'\n", "[optimize] colour:"),
        ("certify = 'exact'\n", "[optimize] certify:"),
        ("method = 'switch'\nobjective = 'lte'\n", "[optimize] method = \"switch\""),
        ("method = 'switch'\nswitch_margin_mm = -0.1\n", "[optimize] switch_margin_mm:"),
    ],
)
def test_cli_rejects_a_bad_optimize_section(tmp_path, capsys, optimize, field):
    from gearjax.cli import main

    code = main(["optimize", _scene_file(tmp_path, optimize), "--out", str(tmp_path / "run"), "--no-cache"])
    err = capsys.readouterr().err
    assert code == 2
    assert field in err and err.count("\n") == 1


def test_cli_optimize_writes_json_history_and_a_runnable_best_scene(tmp_path, capsys, space, batch_values):
    from gearjax.cli import main
    from gearjax.io.scene_file import load_scene

    path = _scene_file(tmp_path, f"method = 'ga'\npopulation = {POPULATION}\ngenerations = 2\n"
                                 'tip_relief_length = [0.5, 4.5]\ncertify = "fast"\n')
    out = tmp_path / "run"
    code = main(["optimize", path, "--out", str(out), "--json", "--quiet", "--no-cache"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    o = json.loads(captured.out)["optimize"]
    assert o["method"] == "ga" and o["evaluations"] == 2 * POPULATION and len(o["history"]) == 2
    assert o["best_objective_N"] <= o["history"][0] and o["best_objective_N"] == o["history"][-1]
    # certified at the search's own accuracy: the certified value is the search's
    assert o["certification_accuracy"] == "fast" and o["certified_objective_N"] == o["best_objective_N"]
    # the search's 6 candidates and the initial design (in the first population), unless it is one of them
    assert len(o["certified_candidates"]) in (6, 7) and o["best_source"] == "search"
    # the default scene's modification is the paper optimum: the library's objective of it
    assert o["initial_objective_N"] == pytest.approx(batch_values[0], rel=1e-6)
    assert set(o["best_modification"]) == {"root_relief_um", "tip_relief_um", "root_relief_length",
                                           "tip_relief_length", "crowning_um", "unmodified_length"}
    assert "generation 2/2" in captured.err
    best, data = load_scene(o["best_scene"])
    np.testing.assert_allclose(np.asarray(best.modification.as_vector()),
                               [o["best_modification"][k] * (1e-3 if k.endswith("_um") else 1.0) for k in o["best_modification"]],
                               rtol=1e-5)
    assert data["optimize"]["population"] == POPULATION
    assert space.contains(np.asarray(best.modification.as_vector()), tol=1e-6)
    # the same command again refuses to overwrite, and --resume of a finished run changes nothing
    assert main(["optimize", path, "--out", str(out), "--no-cache"]) == 2
    assert main(["optimize", path, "--out", str(out), "--resume", "--json", "--quiet", "--no-cache"]) == 0
    assert json.loads(capsys.readouterr().out)["optimize"]["history"] == o["history"]


def test_ga_and_adam_find_the_minimum_of_a_quadratic_bowl():
    """The optimisers alone, on $f(x) = |x - c|^2$ in the unit cube (c inside, one coordinate
    beyond the box: the minimum there lies on the bound)."""
    import jax

    centre = jnp.array([0.3, 0.7, 0.5, 0.1, 0.9, 1.4])
    target = jnp.clip(centre, 0.0, 1.0)

    def f(x):
        return jnp.sum(jnp.square(x - centre), axis=-1)

    config = go.GAConfig(population=24)
    state = go.ga_init(jax.random.PRNGKey(0), config, 6)
    best = []
    for _ in range(40):
        x, state = go.ga_ask(state, config)
        assert bool(jnp.all((x >= 0.0) & (x <= 1.0)))
        state = go.ga_tell(state, x, f(x), config)
        best.append(float(state.best_fitness))
    assert np.all(np.diff(best) <= 0.0)
    np.testing.assert_allclose(state.best, target, atol=0.05)

    # no stall stop: Adam's momentum overshoots a bowl for a while before it settles
    cfg = go.GradientConfig(starts=3, iterations=200, learning_rate=0.05, ftol=0.0, patience=200, xtol=1e-9)
    gstate = go.gradient_init(jax.random.PRNGKey(1), cfg, 6)
    for _ in range(cfg.iterations):
        values, grads = jax.vmap(jax.value_and_grad(f))(gstate.position)
        gstate = go.gradient_step(gstate, values, grads, cfg)
    np.testing.assert_allclose(gstate.best, np.broadcast_to(target, (3, 6)), atol=1e-2)


def test_smoothing_samples_a_starts_point_and_antithetic_pairs_common_to_every_start():
    import jax

    cfg = go.GradientConfig(starts=3, iterations=10, smoothing=0.1, smoothing_pairs=2)
    assert cfg.samples == 5 and go.GradientConfig(starts=3).samples == 1
    state = go.gradient_init(jax.random.PRNGKey(0), cfg, 6, initial=np.full((3, 6), 0.5))
    points = np.asarray(go.sample_positions(state, cfg))
    assert points.shape == (3, 5, 6)
    np.testing.assert_array_equal(points[:, 0], 0.5)  # the start's own point first
    offsets = points - 0.5
    np.testing.assert_allclose(offsets[:, 1:3], -offsets[:, 3:5], atol=1e-15)  # antithetic
    np.testing.assert_array_equal(offsets[0], offsets[2])  # common random numbers
    assert 0.02 < np.std(offsets[0, 1:]) < 0.3  # sigma = 0.1 at the first iteration
    def at(iteration):
        return np.asarray(go.sample_positions(eqx.tree_at(lambda s: s.iteration, state, jnp.asarray(iteration, jnp.int32)), cfg))

    last = at(9) - 0.5  # the last iteration: sigma = sigma_0 / iterations, fresh samples
    assert 0.002 < np.std(last[0, 1:]) < 0.03 and not np.allclose(last[0, 1:3], offsets[0, 1:3] / 10)
    np.testing.assert_array_equal(at(10), 0.5)  # 0 at `iterations`
    corner = eqx.tree_at(lambda s: s.position, state, jnp.zeros((3, 6)))
    assert float(np.min(go.sample_positions(corner, cfg))) == 0.0  # clipped to the box
    assert float(np.max(go.sample_positions(corner, cfg))) > 0.0


def test_the_smoothed_gradient_is_the_mean_over_the_finite_samples():
    values = jnp.array([[1.0, 2.0, jnp.inf], [jnp.inf, 3.0, 4.0], [jnp.inf, jnp.inf, jnp.inf]])
    grads = jnp.stack([jnp.ones((3, 6)), 3 * jnp.ones((3, 6)), jnp.zeros((3, 6))])
    grads = grads.at[0, 1].set(3.0).at[0, 2].set(100.0).at[1, 1].set(jnp.nan)
    value, grad = go.smoothed(values, grads)
    np.testing.assert_array_equal(value, [1.0, jnp.inf, jnp.inf])  # the start's own point
    np.testing.assert_allclose(grad[0], 2.0)  # mean of 1 and 3; the infinite sample left out
    np.testing.assert_allclose(grad[1], 3.0)  # the NaN gradient left out
    assert bool(jnp.all(jnp.isnan(grad[2])))


def test_smoothing_reaches_the_bowl_under_wiggles_where_plain_descent_stalls():
    """A bowl with wiggles 12 per unit (depth 0.02 per parameter), 10 seeds of 4 starts:
    projected Adam stops in a wiggle's basin nearly always; on the smoothed objective
    (sigma 0.1, annealed) most starts reach the bowl's minimum (25 of 40 here, 1 of 40
    without smoothing)."""
    import jax

    centre = jnp.array([0.3, 0.7, 0.45, 0.6, 0.35, 0.55])

    def f(x):
        return jnp.sum(jnp.square(x - centre), -1) + 0.01 * jnp.sum(1 - jnp.cos(24 * jnp.pi * (x - centre)), -1)

    def reached(cfg):
        value_and_grad = jax.vmap(jax.vmap(jax.value_and_grad(f)))
        step = jax.jit(lambda s: go.gradient_step(s, *go.smoothed(*value_and_grad(go.sample_positions(s, cfg))), cfg))
        count = 0
        for seed in range(1, 11):
            state = go.gradient_init(jax.random.PRNGKey(seed), cfg, 6)
            for _ in range(cfg.iterations):
                state = step(state)
            count += int(np.sum(np.max(np.abs(np.asarray(state.best) - np.asarray(centre)), axis=1) < 0.01))
        return count

    plain = reached(go.GradientConfig(starts=4, iterations=150, ftol=0.0, patience=200, xtol=1e-9))
    smooth = reached(go.GradientConfig(starts=4, iterations=150, xtol=1e-9, smoothing=0.1))
    assert plain <= 4 and smooth >= 20, (plain, smooth)


def test_smoothed_descent_evaluates_every_sample_and_resumes_from_its_run_directory(objective, space, monkeypatch,
                                                                                     tmp_path):
    """`gradient_descent` with smoothing, its objective replaced by a bowl in the unit cube
    (the run's plumbing, not the gear objective's program): each iteration evaluates the
    starts' samples as one batch, the best only improves, and a finished run directory
    resumed gives the same result (its state, the random key included, loaded)."""
    import gearjax.optimize.methods as methods_module

    batches = []

    def bowl(objective, space, units):
        units = jnp.asarray(units)
        batches.append(units.shape)
        return jnp.sum(jnp.square(units - 0.3), axis=-1), 2.0 * (units - 0.3)

    monkeypatch.setattr(methods_module, "batch_value_and_grad", bowl)
    cfg = go.GradientConfig(starts=2, iterations=6, smoothing=0.1, smoothing_pairs=1)
    first = go.gradient_descent(objective, space, config=cfg, seed=3, certify=None, run_dir=tmp_path / "run")
    per_design = int(objective.torques.shape[0]) * objective.samples
    assert set(batches) == {(6, 6)} and first.steps == 6
    assert first.evaluations == first.gradient_evaluations == 6 * 6 * per_design
    assert np.all(np.diff(first.history) <= 0.0) and first.best_objective < first.history[0]
    again = go.gradient_descent(objective, space, config=cfg, seed=3, certify=None, run_dir=tmp_path / "run",
                                resume=True)
    np.testing.assert_array_equal(again.best_design, first.best_design)
    assert again.history == first.history


def test_a_registered_method_runs_through_minimize_the_settings_and_the_run_directory(objective, space, designs,
                                                                                     batch_values, tmp_path):
    """A method is a class and a `register`: random search over the unit cube, one batch of
    the file's 12 designs per step (so the objective's compiled batch program is shared),
    runs through `minimize`, is named by `[optimize] method` and in `run.json`, and a name
    cannot be taken twice."""
    import jax

    @dataclasses.dataclass(frozen=True)
    class RandomSearch(go.SearchMethod):
        config: go.GAConfig = dataclasses.field(default_factory=lambda: go.GAConfig(population=POPULATION))
        name = "random_test"

        @classmethod
        def from_settings(cls, settings):
            return cls(go.GAConfig(population=settings.population))

        steps = property(lambda self: 2)
        batch = property(lambda self: self.config.population)

        def init(self, key, starts, dtype):
            return {"key": key, "best": jnp.full(6, 0.5, dtype), "best_value": jnp.asarray(jnp.inf, dtype)}

        def step(self, objective, space, state):
            key, draw = jax.random.split(state["key"])
            units = jax.random.uniform(draw, (self.batch, 6), objective.torques.dtype)
            values = _batch_objective(objective, space.to_design(units))
            i = jnp.argmin(values)
            better = values[i] < state["best_value"]
            best = jnp.where(better, units[i], state["best"])
            return ({"key": key, "best": best, "best_value": jnp.minimum(values[i], state["best_value"])},
                    space.to_design(units), values)

        def best(self, state):
            return state["best_value"], state["best"]

        def candidates(self, state):
            return np.asarray(state["best"])[None], np.asarray(state["best_value"])[None]

    go.register(RandomSearch)
    try:
        with pytest.raises(ValueError, match="registered already"):
            go.register(type("Other", (RandomSearch,), {"name": "random_test"}))
        settings = go.OptimizeSettings.from_dict({"method": "random_test", "population": POPULATION})
        method = settings.search_method()
        assert isinstance(method, RandomSearch) and method.batch == POPULATION
        result = go.minimize(objective, space, method, seed=1, certify=None, run_dir=tmp_path / "run")
    finally:
        go.METHODS.pop("random_test")
    assert result.method == "random_test" and result.steps == 2 and result.gradient_evaluations == 0
    assert result.evaluations == 2 * POPULATION
    records = [json.loads(line) for line in (tmp_path / "run" / "history.jsonl").read_text().splitlines()]
    assert result.best_objective == min(min(r["objective"]) for r in records)
    assert json.loads((tmp_path / "run" / "run.json").read_text())["method"] == "random_test"
    # the batch program is the file's: the scene's own design scores as in the batch fixture
    assert result.initial_objective == pytest.approx(batch_values[0], rel=1e-12)
    with pytest.raises(go.SettingsError, match="method"):
        go.OptimizeSettings.from_dict({"method": "random_test"})


def test_cma_es_runs_through_the_settings_and_minimize_with_the_batch_program_of_the_file(objective, space,
                                                                                        batch_values, tmp_path):
    """`[optimize] method = "cma_es"` sets up `CMASearch` (population and generations from
    the section, its own defaults otherwise); a run of 12 candidates per generation shares
    the file's compiled batch program, asks only designs within the bounds, and its best is
    the best value it evaluated."""
    assert go.OptimizeSettings.from_dict({"method": "cma_es"}).search_method() == go.CMASearch(go.CMAConfig(10), 120)
    with pytest.raises(go.SettingsError, match=r"\[optimize\] population"):
        go.OptimizeSettings.from_dict({"method": "cma_es", "population": 3}).search_method()
    settings = go.OptimizeSettings.from_dict({"method": "cma_es", "population": POPULATION, "generations": 3})
    method = settings.search_method()
    result = go.minimize(objective, space, method, seed=2, certify=None, run_dir=tmp_path / "run")
    assert result.method == "cma_es" and result.steps == 3 and result.evaluations == 3 * POPULATION
    records = [json.loads(line) for line in (tmp_path / "run" / "history.jsonl").read_text().splitlines()]
    evaluated = np.array([r["designs_mm"] for r in records])
    assert evaluated.shape == (3, POPULATION, 6) and space.contains(evaluated)
    assert result.best_objective == min(min(r["objective"]) for r in records)
    assert np.all(np.diff(result.history) <= 0.0)
    assert result.initial_objective == pytest.approx(batch_values[0], rel=1e-12)


def test_resuming_a_run_of_another_version_names_the_setting_it_lacks(tmp_path):
    from gearjax.io.rundir import RunDirectory, RunDirectoryError

    RunDirectory(tmp_path, {"method": "gradient", "config": {"starts": 8}}, resume=False)
    with pytest.raises(RunDirectoryError, match=r"differs in config\.smoothing \(absent from the saved run"):
        RunDirectory(tmp_path, {"method": "gradient", "config": {"starts": 8, "smoothing": 0.0}}, resume=True)
    with pytest.raises(RunDirectoryError, match=r"differs in config\.starts$"):
        RunDirectory(tmp_path, {"method": "gradient", "config": {"starts": 4}}, resume=True)


def test_a_start_that_never_had_a_finite_value_moves_to_the_centre():
    import jax

    cfg = go.GradientConfig(starts=2, iterations=5)
    state = go.gradient_init(jax.random.PRNGKey(0), cfg, 6, initial=np.array([[0.0] * 6, [1.0] * 6]))
    values = jnp.array([jnp.inf, 1.0])
    grads = jnp.stack([jnp.full(6, jnp.nan), jnp.ones(6)])
    new = go.gradient_step(state, values, grads, cfg)
    np.testing.assert_allclose(new.position[0], 0.25)  # halfway from the corner to the centre
    assert new.best_value[1] == 1.0 and bool(jnp.all(new.position[1] < 1.0))  # a finite start steps downhill


@pytest.mark.slow
def test_notebook_06_runs_in_this_process_with_its_programs(objective, space, ga_run, monkeypatch):
    """Notebook 06 (GA and gradient descent on this file's objective) runs here rather than
    in a kernel (`_notebooks.py`): its gradient program is the one this file compiles for
    2 starts, which a kernel would trace and, missing the cache (another key), compile again.
    Its two runs certify at this file's `CERTIFY` rather than at `reference`: the same
    program at other static shapes, whose compile and two runs took about 270 s under the
    test flags, more than half of the test; `ga_run` has compiled it (certification itself
    is tested above)."""
    import functools

    from _notebooks import execute_in_process

    monkeypatch.setattr(go, "genetic", functools.partial(go.genetic, certify=CERTIFY))
    monkeypatch.setattr(go, "gradient_descent", functools.partial(go.gradient_descent, certify=CERTIFY))
    ns = execute_in_process("06_optimisation.ipynb")
    # the notebook's problem is this file's: one structure, so one compiled program
    assert bool(eqx.tree_equal(ns["objective"], objective))
    np.testing.assert_array_equal(np.asarray(ns["space"].lower), np.asarray(space.lower))
    np.testing.assert_array_equal(np.asarray(ns["space"].upper), np.asarray(space.upper))
    ga, gd = ns["ga"], ns["gd"]
    assert gd.method == "gradient" and ga.method == "ga"
    for r in (ga, gd):
        assert np.isfinite(r.best_objective) and r.best_objective <= r.initial_objective
