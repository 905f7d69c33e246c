"""The Pareto front: the front utilities against independent definitions, the front search on
an analytic problem, and `gearjax optimize --pareto` end to end (run directory, resumption,
readable errors)."""

import itertools
import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gearjax.optimize.front import distinct, hypervolume, nondominated, spread
from gearjax.optimize.pareto import ParetoConfig, parse_quantity, pareto_init, pareto_update, simplex_lattice, \
    with_constraints


def _dominated_by_definition(F):
    n = len(F)
    return np.array([any(np.all(F[j] <= F[i]) and np.any(F[j] < F[i]) for j in range(n) if j != i) for i in range(n)])


def _union_volume(F, r):
    """Inclusion-exclusion over every subset of the boxes [p, r]."""
    total = 0.0
    for size in range(1, len(F) + 1):
        for subset in itertools.combinations(range(len(F)), size):
            corner = np.max(F[list(subset)], axis=0)
            total += (-1) ** (size + 1) * np.prod(np.maximum(r - corner, 0.0))
    return total


@pytest.mark.parametrize("dim", [2, 3, 4])
def test_hypervolume_is_the_volume_of_the_union_of_boxes(dim):
    rng = np.random.default_rng(dim)
    for _ in range(20):
        F = rng.uniform(0.0, 1.0, (rng.integers(1, 8), dim))
        r = np.full(dim, 1.05)
        assert hypervolume(F, r) == pytest.approx(_union_volume(F, r), rel=1e-12, abs=1e-15)


def test_hypervolume_counts_only_points_inside_the_reference_and_finite():
    r = np.array([1.0, 1.0])
    assert hypervolume([[0.5, 0.5]], r) == pytest.approx(0.25)
    assert hypervolume([[0.5, 0.5], [1.5, 0.0], [np.inf, 0.0]], r) == pytest.approx(0.25)
    with pytest.raises(ValueError, match="reference has 3 entries"):
        hypervolume([[0.5, 0.5]], [1.0, 1.0, 1.0])


def test_nondominated_is_the_definition_and_keeps_one_of_equal_points():
    rng = np.random.default_rng(0)
    F = np.round(rng.uniform(0.0, 1.0, (60, 3)), 1)  # ties and duplicates
    keep = nondominated(F)
    dominated = _dominated_by_definition(F)
    assert not np.any(keep & dominated)
    for i in np.flatnonzero(~dominated):  # every non-dominated value is kept exactly once
        assert np.sum(keep & np.all(F == F[i], axis=1)) == 1
    assert not nondominated([[np.nan, 0.0], [1.0, 1.0]])[0]


def test_spread_starts_at_each_quantitys_lowest_and_is_distinct():
    rng = np.random.default_rng(1)
    F = rng.uniform(0.0, 1.0, (50, 3))
    chosen = spread(F, 10)
    assert len(chosen) == len(set(chosen.tolist())) == 10
    assert set(np.argmin(F, axis=0).tolist()) <= set(chosen[:3].tolist())
    assert np.array_equal(spread(F[:4], 10), np.arange(4))
    designs = np.array([[0.0, 1.0], [0.0, 1.0 + 1e-12], [0.0, 2.0]])
    assert distinct(designs).tolist() == [True, False, True]


def test_lattice_and_quantities():
    weights = np.asarray(simplex_lattice(3, 5))
    assert weights.shape == (math.comb(7, 2), 3) == (ParetoConfig().slots, 3)
    assert np.allclose(weights.sum(axis=1), 1.0) and len({tuple(w) for w in weights.tolist()}) == 21
    assert parse_quantity("pressure:max") == ("pressure", "max")
    assert parse_quantity("lte", "max") == ("lte", "max")


@pytest.mark.parametrize("quantities, match", [
    (("force",), "at least two"),
    (("force", "force:max"), "each quantity once"),
    (("force", "noise"), "must be one of force"),
    (("force", "lte:median"), "aggregate after ':'"),
])
def test_bad_quantities_name_the_field(quantities, match):
    with pytest.raises(ValueError, match=match):
        ParetoConfig(quantities=quantities)
    with pytest.raises(ValueError, match="pareto divisions"):
        ParetoConfig(divisions=0)


def test_every_slot_reaches_the_pareto_set_of_two_bowls():
    """q1 = |x - a|^2, q2 = |x - b|^2 on the unit cube: the Pareto set is the segment [a, b];
    each slot's best lies on it, the extreme weights reach its ends, and the slots' points
    are spread along it."""
    a, b = jnp.full(6, 0.2), jnp.array([0.8, 0.7, 0.6, 0.8, 0.7, 0.6])
    config = ParetoConfig(quantities=("lte", "pressure"), divisions=6, iterations=60)

    def values(x):
        q = jnp.stack([jnp.sum((x - a) ** 2), jnp.sum((x - b) ** 2)])
        return q, jax.jacfwd(lambda y: jnp.stack([jnp.sum((y - a) ** 2), jnp.sum((y - b) ** 2)]))(x)

    @jax.jit
    def step(state):
        q, dq = jax.vmap(values)(state.sqp.trial)
        k = q.shape[0]
        return pareto_update(state, (q, dq, jnp.ones((k, 1)), jnp.zeros((k, 1, 6))), config)

    state = with_constraints(pareto_init(jax.random.PRNGKey(3), config), 1)
    for _ in range(config.iterations):
        state = step(state)
    best = np.asarray(state.sqp.best)
    t = np.clip(((best - np.asarray(a)) @ np.asarray(b - a)) / float((b - a) @ (b - a)), 0.0, 1.0)
    off = np.linalg.norm(best - (np.asarray(a) + t[:, None] * np.asarray(b - a)), axis=1)
    assert np.all(off < 2e-3), off
    weights = np.asarray(state.weights)
    assert t[np.argmax(weights[:, 0])] < 0.01 and t[np.argmax(weights[:, 1])] > 0.99
    assert len(np.unique(np.round(t, 2))) >= 5


def test_only_the_slots_that_weigh_the_force_keep_to_the_flank_side():
    """Both bowls' minima lie at x0 = 0.2, where the switching function s = x0 - 0.5 is
    negative: the slot of weights (1, 0) on (force, lte) stops at the margin s = 0.05, the
    slot of weights (0, 1), whose J_k has no force term, reaches the minimum."""
    a = jnp.full(6, 0.2)
    config = ParetoConfig(quantities=("force", "lte"), divisions=1, iterations=40)

    def values(x):
        f = lambda y: jnp.stack([jnp.sum((y - a) ** 2), 2.0 * jnp.sum((y - a) ** 2)])  # noqa: E731
        return f(x), jax.jacfwd(f)(x), x[:1] - 0.5, jnp.eye(6)[:1]

    @jax.jit
    def step(state):
        return pareto_update(state, jax.vmap(values)(state.sqp.trial), config)

    state = with_constraints(pareto_init(jax.random.PRNGKey(5), config), 1)
    for _ in range(config.iterations):
        state = step(state)
    best, weights = np.asarray(state.sqp.best), np.asarray(state.weights)
    force_slot, lte_slot = int(np.argmax(weights[:, 0])), int(np.argmax(weights[:, 1]))
    assert best[force_slot, 0] == pytest.approx(0.55, abs=1e-3)
    np.testing.assert_allclose(best[lte_slot], np.asarray(a), atol=5e-3)  # not held at x0 >= 0.55


def _scene_file(tmp_path, optimize: str) -> str:
    from gearjax.io.scene_file import DEFAULT_SCENE_TOML

    text = DEFAULT_SCENE_TOML.replace('accuracy = "default"', 'accuracy = "fast"') + "\n[optimize]\n" + optimize
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return str(path)


#: the three quantities over 400/1 000/1 600 N·m, time shares 1:2:1, at `fast`
SMALL = ('loads_Nm = [400, 1000, 1600]\nload_weights = [1, 2, 1]\npareto_divisions = 1\niterations = 2\n'
         'certify = "fast"\n')


@pytest.mark.parametrize("optimize, field", [
    ('pareto_quantities = ["force"]', "pareto_quantities"),
    ('pareto_quantities = ["force", "noise"]', "pareto_quantities"),
    ("pareto_divisions = 0", "pareto_divisions"),
])
def test_cli_pareto_rejects_a_bad_section_in_one_line(tmp_path, capsys, optimize, field):
    from gearjax.cli import main

    code = main(["optimize", "--pareto", _scene_file(tmp_path, optimize), "--out", str(tmp_path / "run"), "--no-cache"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and field in err


def test_cli_pareto_writes_a_front_and_a_killed_run_resumes_to_the_same_front(tmp_path, capsys, monkeypatch):
    """`gearjax optimize --pareto` on three quantities at `fast`: no design evaluated
    dominates a front design; a run stopped
    after its first iteration and resumed ends with the uninterrupted run's history and
    front."""
    from gearjax.cli import main
    from gearjax.optimize import pareto_run

    path = _scene_file(tmp_path, SMALL)
    whole = tmp_path / "whole"
    assert main(["optimize", "--pareto", path, "--out", str(whole), "--json", "--quiet", "--no-cache"]) == 0
    report = json.loads(capsys.readouterr().out)["pareto"]
    assert report["quantities"] == ["force:mean", "lte:mean", "pressure:max"]
    assert report["units"] == ["N", "µm", "MPa"] and report["time_shares"] == [0.25, 0.5, 0.25]
    assert report["steps"] == 2 and report["evaluations"] == 2 * 3 * 3  # 3 scalarisations, 3 loads
    front = np.array([[e["objectives"][q] for q in report["quantities"]] for e in report["front"]])
    assert len(front) >= 1 and all(e["certified"] for e in report["front"])
    history = [json.loads(line) for line in (whole / "history.jsonl").read_text().splitlines()]
    archive = np.array([q for r in history for q in r["quantities"] if np.all(np.isfinite(q))])
    for point in front:  # nothing in the archive dominates a front design
        assert not np.any(np.all(archive <= point, axis=1) & np.any(archive < point, axis=1))
    assert (whole / "front.csv").read_text().count("\n") == len(front) + 1

    calls = {"n": 0}
    update = pareto_run._update

    def stop_after_one(*args):
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt
        return update(*args)

    monkeypatch.setattr(pareto_run, "_update", stop_after_one)
    killed = tmp_path / "killed"
    with pytest.raises(KeyboardInterrupt):
        main(["optimize", "--pareto", path, "--out", str(killed), "--quiet", "--no-cache"])
    monkeypatch.setattr(pareto_run, "_update", update)
    assert len((killed / "history.jsonl").read_text().splitlines()) == 1
    assert main(["optimize", "--pareto", path, "--out", str(killed), "--resume", "--json", "--quiet",
                 "--no-cache"]) == 0
    resumed = json.loads(capsys.readouterr().out)["pareto"]
    again = [json.loads(line) for line in (killed / "history.jsonl").read_text().splitlines()]
    assert [(r["designs_mm"], r["quantities"], r["flank"]) for r in again] == \
        [(r["designs_mm"], r["quantities"], r["flank"]) for r in history]
    assert resumed["front"] == report["front"]


@pytest.mark.slow
def test_notebook_08_runs_in_this_process_and_its_front_is_the_searchs(tmp_path):
    """Notebook 08 (the seed pair's front over a three-load duty cycle) runs here rather
    than in a kernel (`_notebooks.py`), on the CLI test's settings (`SMALL`): the same
    front program. Its front is `pareto_front`'s at those settings, non-dominated in its
    archive, and its 'lowest' rows are the front's minima."""
    from _notebooks import execute_in_process

    from gearjax import optimize as go

    ns = execute_in_process("08_pareto.ipynb")
    result, config, objective = ns["result"], ns["config"], ns["objective"]
    assert config.slots == 3 and config.iterations == 2 and result.certification_accuracy == "fast"
    np.testing.assert_array_equal(np.asarray(objective.torques), [4e5, 1e6, 1.6e6])  # N·mm
    designs, values = result.front
    again = go.pareto_front(objective, ns["space"], config, seed=0, certify="fast")
    np.testing.assert_array_equal(again.front[1], values)
    archive = result.archive_values
    for point in values:
        assert not np.any(np.all(archive <= point, axis=1) & np.any(archive < point, axis=1))
    assert [int(np.argmin(values[:, j])) for j in range(3)] == ns["lowest"]


def test_each_quantity_has_its_own_aggregate_over_the_duty_cycle(seed_pair):
    import gearjax as gj
    from gearjax.optimize import Evaluation, Objective

    scene = gj.Scene(seed_pair, effects=("impact",), accuracy="fast", operating=gj.OperatingPoint(torque_Nm=1000.0))
    objective = Objective.create(scene, torques_Nm=[400.0, 1000.0, 1600.0], weights=[1.0, 2.0, 1.0])
    rng = np.random.default_rng(2)
    x = [jnp.asarray(rng.uniform(1.0, 2.0, (3, 2))) for _ in range(6)]
    e = Evaluation(jnp.zeros(()), x[0], x[0], x[1], jnp.zeros((3, 2), bool), x[2], x[3], x[4], jnp.zeros((), int))
    per_load = np.asarray(x[2]).mean(axis=1)
    assert float(objective.aggregated(e, "pressure", "max")) == pytest.approx(per_load.max(), rel=1e-14)
    assert float(objective.aggregated(e, "pressure", "mean")) == pytest.approx(per_load @ [0.25, 0.5, 0.25], rel=1e-14)
    assert float(objective.aggregated(e, "stiffness", "max")) == pytest.approx(-np.asarray(x[4]).mean(axis=1).min())
