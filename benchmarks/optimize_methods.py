"""Optimisation methods compared on the certified mesh-in impact objective.

    python benchmarks/optimize_methods.py [--objectives force_1000 spectrum] [--seeds 5]
        [--budget 1200] [--methods ga gradient gradient_restarts gradient_smoothed ga_gradient
        cma_es differential_evolution switch ga_switch cma_es_gradf cma_es_constrained cobyqa slsqp
        gearjax_cma_es]
        [--accuracy default] [--certify reference] [--plot]

Seed 001's pair at 5 000 rpm with seed 001's design space; two objectives: `force_1000`
(F_s at 1 000 N·m) and `spectrum` (mean F_s over 400/1 000/1 600 N·m). Every method starts
from scratch (the paper's optimum lies outside the bounds), searches the unit cube at the
search accuracy through the same compiled `Objective.batch` program, and gets the same
budget of objective evaluations (one evaluation: one design over all the objective's
loads). A value-and-gradient call counts as `gradient_cost` evaluations, the ratio of
its measured time to a forward call of the same batch, measured in this run.

Methods:
* `ga`: gearjax's GA (`ga_init`/`ga_ask`/`ga_tell`), population 40.
* `gradient`: gearjax's multi-start projected Adam (`gradient_init`/`gradient_step`),
  10 Latin-hypercube starts; it stops when every start has stopped.
* `gradient_restarts`: `gradient`, restarted from new Latin-hypercube starts whenever every
  start has stopped, until the budget is spent (its first starts are `gradient`'s).
* `gradient_smoothed`: gearjax's projected Adam on the Gaussian-smoothed objective
  (`GradientConfig.smoothing` 0.1, annealed to 0; 2 starts, each with 2 antithetic pairs:
  10 designs per call), restarted like `gradient_restarts` until the budget is spent.
* `ga_gradient`: the GA (population 20) for half the budget, then the 10 best distinct
  members of its population polished by projected Adam (learning rate 0.02).
* `cma_es`: CMA-ES, the reference implementation (`cma`), population 10, sigma0 0.3,
  box-bounded; non-finite values are given to it as 1e6 N.
* `gearjax_cma_es`: gearjax's CMA-ES (`cma_init`/`cma_ask`/`cma_tell`, `gearjax optimize
  --method cma_es`), population 10, sigma0 0.3, pycma's boundary transformation, restarted
  once the distribution collapses; non-finite values count as +inf.
* `differential_evolution`: SciPy's, population 30 (popsize 5), `vectorized`,
  `updating="deferred"`, no polish; non-finite values as 1e6 N.
* `cma_es_gradf`: `cma_es` with pycma's gradient injection (`ask(gradf=...)`): each
  generation one of its 10 candidates is a step along the exact gradient at the mean, which
  costs one value-and-gradient evaluation (`gradient_cost`) on top of the 10.
* `cma_es_constrained`: `cma_es` on pycma's augmented-Lagrangian wrapper
  (`cma.ConstrainedFitnessAL`) of the switching method's problem: min F_flank subject to
  every load's switching function s >= 0.05 mm, forward values only (one evaluation per
  design); a design enters the log as `switch`'s do (flank side at every load).
* `cobyqa`: SciPy's COBYQA (derivative-free, quadratic models) on the raw force, one design
  per call, from a random start in [0.2, 0.8]^6, started again from a new one whenever it
  stops, until the budget is spent; non-finite values as 1e6 N.
* `slsqp`: SciPy's SLSQP on the raw force with its exact gradient (one value-and-gradient
  evaluation per call), restarted like `cobyqa`; non-finite values as 1e6 N with a zero
  gradient.
* `switch`: gearjax's switching-aware SQP (`gearjax.optimize.switch`: min F_flank subject
  to every load's switching function s >= 0.05 mm), 6 start slots that start again once
  converged or stalled; one call of the flank branch's value and Jacobian
  (`switch_values`) per iteration, counted as `switch_cost` evaluations per design (its
  measured time over a forward call of the same designs); a design enters the run's log
  only where it lies on the flank side at every load, s >= 0.05 mm - 1e-4 mm, as the
  method's own best (there J_flank is the objective).
* `ga_switch`: the GA (population 20) for half the budget as a global phase, then
  `switch` from the 6 best distinct members of its population for the rest.

Certification: the running best design of each run at the checkpoints (a fixed grid of
evaluation counts, CHECKPOINTS, and the run's end) is evaluated again at the
certification accuracy. A run's certified best is the lowest certified value among them;
`evaluations_to_1pct` is the first checkpoint at which that running certified best is
within 1 % of the lowest certified value any run found for the objective (its resolution
is the grid's).

Long runs lose nothing: every finished run is written at once to
`benchmarks/results/optimize_methods_runs.json` (its log of improvements), every
certified design to the same file, and a rerun skips what is there. The summary in the
issue's form, of every certified run in that file (whichever objectives and methods this
call ran), goes to `benchmarks/results/optimize_methods.json`, the figure (median
certified running best against evaluations) to `docs/figures/optimize_methods.png`.
"""

from __future__ import annotations

import argparse
import json
import time

import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from _common import RESULTS, machine, median_time  # noqa: E402

import gearjax as gj  # noqa: E402
from gearjax import optimize as go  # noqa: E402
from gearjax.optimize.batch import batch_objective, batch_objective_in_chunks, batch_value_and_grad  # noqa: E402
from gearjax.optimize.certification import certification_accuracy, with_accuracy  # noqa: E402
from gearjax.optimize.switch import switch_init, switch_update, switch_values  # noqa: E402
from gearjax.papers.seed001 import paper_optimum, seed_pair  # noqa: E402

OBJECTIVES = {"force_1000": [1000.0], "spectrum": [400.0, 1000.0, 1600.0]}
METHODS = ("ga", "gradient", "gradient_restarts", "gradient_smoothed", "ga_gradient", "cma_es", "differential_evolution",
           "switch", "ga_switch", "cma_es_gradf", "cma_es_constrained", "cobyqa", "slsqp", "gearjax_cma_es")
#: the black-box and SciPy methods the figure draws dashed
YARDSTICKS = ("cma_es", "differential_evolution", "cma_es_gradf", "cma_es_constrained", "cobyqa", "slsqp")
CHECKPOINTS = (25, 50, 75, 100, 150, 200, 300, 400, 600, 800, 1000, 1200, 1600, 2400)
GRADIENT_METHODS = ("gradient", "gradient_restarts", "gradient_smoothed", "ga_gradient", "cma_es_gradf", "slsqp")
CHUNK = STARTS = 10  # designs per program call; gradient starts
PENALTY = 1e6
RUNS_FILE = RESULTS / "optimize_methods_runs.json"
#: the switch method's designs on the flank side: s >= margin - feasibility (mm), as the
#: method's own best (`SwitchConfig`)
ON_FLANK_MM = go.SwitchConfig().margin - go.SwitchConfig().feasibility


def objective_for(name: str, accuracy: str) -> go.Objective:
    scene = gj.Scene(seed_pair(), paper_optimum(), effects=("impact",), accuracy=accuracy,
                     operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0))
    return go.Objective.create(scene, torques_Nm=OBJECTIVES[name])


class Counter:
    """Counts evaluations and logs every improvement of the running best (evaluations at
    it, value, unit-cube design) of one run."""

    def __init__(self, objective, space, budget, gradient_cost, switch_cost=1.0):
        self.objective, self.space, self.budget, self.gradient_cost = objective, space, budget, gradient_cost
        self.switch_cost = switch_cost
        self.evaluations, self.best, self.log = 0.0, np.inf, []

    @property
    def left(self) -> float:
        return self.budget - self.evaluations

    def _note(self, units, values, cost):
        for i, value in enumerate(values):
            if np.isfinite(value) and value < self.best:
                self.best = float(value)
                self.log.append([self.evaluations + cost * (i + 1), self.best, [float(u) for u in units[i]]])
        self.evaluations += cost * len(values)

    def values(self, units) -> np.ndarray:
        """The objective at unit-cube points (n, 6), padded to CHUNK rows per program call."""
        units = np.clip(np.atleast_2d(np.asarray(units, float)), 0.0, 1.0)
        values = batch_objective_in_chunks(self.objective, self.space.to_design(jnp.asarray(units)), CHUNK)
        self._note(units, values, 1.0)
        return values

    def switch_values(self, units):
        """`switch_values` at unit-cube points; the flank branch's objective is noted where
        every switching function is >= ON_FLANK_MM (there it is the objective)."""
        values = switch_values(self.objective, self.space, jnp.asarray(units))
        J, _, s, _ = (np.asarray(v) for v in values)
        self._note(np.asarray(units), np.where(np.all(s >= ON_FLANK_MM, axis=-1), J, np.inf), self.switch_cost)
        return values

    def value_and_grad(self, units):
        values, grads = batch_value_and_grad(self.objective, self.space, jnp.asarray(units))
        values = np.asarray(values)
        self._note(np.asarray(units), values, self.gradient_cost)
        return values, grads

    def value(self, unit) -> float:
        """The objective at one unit-cube point, one design per program call (the serial
        methods), clipped to the cube."""
        unit = np.clip(np.asarray(unit, float), 0.0, 1.0)[None]
        value = batch_objective_in_chunks(self.objective, self.space.to_design(jnp.asarray(unit)), 1)
        self._note(unit, value, 1.0)
        return float(value[0])

    def value_and_gradient(self, unit) -> tuple[float, np.ndarray]:
        """The objective and its unit-coordinate gradient at one point (`gradient_cost`),
        in the STARTS-row program (the point repeated), clipped to the cube."""
        unit = np.clip(np.asarray(unit, float), 0.0, 1.0)
        values, grads = batch_value_and_grad(self.objective, self.space, jnp.asarray(np.tile(unit, (STARTS, 1))))
        self._note(unit[None], np.asarray(values)[:1], self.gradient_cost)
        return float(values[0]), np.asarray(grads[0])

    def flank_values(self, units):
        """F_flank and every load's switching function (mm) at unit-cube points, forward
        only, one evaluation each; noted as `switch_values` notes them."""
        units = np.clip(np.atleast_2d(np.asarray(units, float)), 0.0, 1.0)
        evaluation = _flank_jit(self.objective, self.space.to_design(jnp.asarray(units)))
        J, s = np.asarray(evaluation[0]), np.asarray(evaluation[1]).reshape(len(units), -1)
        self._note(units, np.where(np.all(s >= ON_FLANK_MM, axis=-1), J, np.inf), 1.0)
        return J, s


@eqx.filter_jit
def _flank_jit(objective, designs):
    def one(design):
        evaluation = objective.evaluate(design, flank_branch=True)
        return evaluation.objective, evaluation.switch

    return jax.lax.map(one, designs, batch_size=objective.map_batch_size)


def run_ga(counter: Counter, seed: int, population: int = 40, fraction: float = 1.0) -> go.GAState:
    config = go.GAConfig(population=population)
    ask = eqx.filter_jit(lambda s: go.ga_ask(s, config))
    tell = eqx.filter_jit(lambda s, c, f: go.ga_tell(s, c, f, config))
    state = go.ga_init(jax.random.PRNGKey(seed), config, 6)
    while counter.left - (1.0 - fraction) * counter.budget >= population:
        candidates, state = ask(state)
        values = counter.values(candidates)
        state = tell(state, candidates, jnp.asarray(values))
    return state


#: one projected Adam step on the (smoothed) objective; the samples to evaluate
_step = eqx.filter_jit(lambda state, values, grads, config: go.gradient_step(state, *go.smoothed(values, grads), config))
_sample = eqx.filter_jit(go.sample_positions)


def descend(counter: Counter, seed: int, config: go.GradientConfig, initial=None) -> None:
    """gearjax's projected Adam (`gradient_init`, `sample_positions`, `smoothed`,
    `gradient_step`, as `gearjax optimize` runs it): every sample of every start in one
    value-and-gradient call per iteration, until every start has stopped, the iterations
    are done or the budget cannot pay another call."""
    rows = config.starts * config.samples
    state = go.gradient_init(jax.random.PRNGKey(seed), config, 6, initial)
    for _ in range(config.iterations):
        if not bool(jnp.any(state.active)) or counter.left < rows * counter.gradient_cost:
            break
        points = _sample(state, config)
        values, grads = counter.value_and_grad(points.reshape(-1, 6))
        state = _step(state, jnp.asarray(values).reshape(points.shape[:2]), grads.reshape(points.shape), config)


def iterations_left(counter: Counter, rows: int) -> int:
    """Iterations of `rows` value-and-gradient rows that the budget left pays for (≥ 1)."""
    return max(1, int(counter.left // (rows * counter.gradient_cost)))


def run_gradient(counter: Counter, seed: int, initial=None, learning_rate: float = 0.05) -> None:
    config = go.GradientConfig(starts=STARTS, iterations=iterations_left(counter, STARTS), learning_rate=learning_rate)
    descend(counter, seed, config, initial)


def run_gradient_restarts(counter: Counter, seed: int) -> None:
    """`run_gradient`, started again from new Latin-hypercube starts whenever every start
    has stopped, until the budget is spent."""
    restart = 0
    while counter.left >= STARTS * counter.gradient_cost:
        run_gradient(counter, seed if restart == 0 else seed + 2000 + restart)
        restart += 1


def run_gradient_smoothed(counter: Counter, seed: int, smoothing: float = 0.1, pairs: int = 2) -> None:
    """Projected Adam on the Gaussian-smoothed objective, STARTS designs per call
    (STARTS // (1 + 2 pairs) starts), restarted from new starts until the budget is spent."""
    if STARTS % (1 + 2 * pairs):
        raise ValueError(f"gradient_smoothed: 1 + 2 pairs must divide the {STARTS} designs per call; got pairs={pairs}")
    restart = 0
    while counter.left >= STARTS * counter.gradient_cost:
        config = go.GradientConfig(starts=STARTS // (1 + 2 * pairs), iterations=iterations_left(counter, STARTS),
                                   smoothing=smoothing, smoothing_pairs=pairs)
        descend(counter, seed + 3000 * restart, config)
        restart += 1


def run_ga_gradient(counter: Counter, seed: int) -> None:
    state = run_ga(counter, seed, population=20, fraction=0.5)
    fitness = np.asarray(state.fitness)
    order = [int(i) for i in np.argsort(fitness) if np.isfinite(fitness[i])]
    population = np.asarray(state.population)
    distinct = []
    for i in order:
        if all(np.max(np.abs(population[i] - population[j])) > 1e-6 for j in distinct):
            distinct.append(i)
    run_gradient(counter, seed + 1000, initial=population[distinct[:STARTS]] if distinct else None, learning_rate=0.02)


def run_cma(counter: Counter, seed: int) -> None:
    es = _cma(seed)
    while counter.left >= CHUNK:
        x = es.ask()
        values = counter.values(np.asarray(x))
        es.tell(x, [float(v) if np.isfinite(v) else PENALTY for v in values])


def run_gearjax_cma(counter: Counter, seed: int) -> None:
    config = go.CMAConfig(population=CHUNK)
    ask = eqx.filter_jit(lambda s: go.cma_ask(s, config))
    tell = eqx.filter_jit(lambda s, c, f: go.cma_tell(s, c, f, config))
    state = go.cma_init(jax.random.PRNGKey(seed), config, 6)
    while counter.left >= CHUNK:
        candidates, state = ask(state)
        state = tell(state, candidates, jnp.asarray(counter.values(candidates)))


def run_de(counter: Counter, seed: int) -> None:
    from scipy.optimize import differential_evolution

    size = 5 * 6

    def f(x):  # x: (6, S)
        values = counter.values(np.asarray(x).T)
        return np.where(np.isfinite(values), values, PENALTY)

    differential_evolution(f, [(0.0, 1.0)] * 6, popsize=5, maxiter=max(0, int(counter.left // size) - 1), tol=0.0,
                           atol=0.0, seed=seed, vectorized=True, updating="deferred", polish=False,
                           init="latinhypercube")


_switch_update = eqx.filter_jit(switch_update)


def run_switch(counter: Counter, seed: int, starts: int = 6, initial=None) -> None:
    """gearjax's switching-aware SQP (`switch_init`, `switch_values`, `switch_update`, as
    `gearjax optimize --method switch` runs it) until the budget cannot pay another call;
    `initial`: the first slots' starts (unit cube)."""
    config = go.SwitchConfig(starts=starts, iterations=10**6)
    constraints = int(counter.objective.torques.shape[0]) * counter.objective.samples
    state = switch_init(jax.random.PRNGKey(seed), config, constraints, initial, jnp.float64)
    while counter.left >= starts * counter.switch_cost:
        state = _switch_update(state, counter.switch_values(state.trial), config)


def run_ga_switch(counter: Counter, seed: int) -> None:
    """The GA (population 20) for half the budget as the global phase, then the switching-
    aware SQP from its 6 best distinct members for the rest."""
    state = run_ga(counter, seed, population=20, fraction=0.5)
    fitness, population = np.asarray(state.fitness), np.asarray(state.population)
    distinct = []
    for i in [int(i) for i in np.argsort(fitness) if np.isfinite(fitness[i])]:
        if all(np.max(np.abs(population[i] - population[j])) > 1e-6 for j in distinct):
            distinct.append(i)
    run_switch(counter, seed + 1000, initial=population[distinct[:6]] if distinct else None)


def _cma(seed: int):
    import cma

    x0 = np.random.default_rng(seed).uniform(0.2, 0.8, 6)
    return cma.CMAEvolutionStrategy(x0, 0.3, {"bounds": [0.0, 1.0], "popsize": CHUNK, "seed": seed + 1, "verbose": -9,
                                                "verb_log": 0})


def run_cma_gradf(counter: Counter, seed: int) -> None:
    """`run_cma` with pycma's gradient injection: one candidate per generation steps along
    the exact gradient at the mean (`ask(gradf=...)` calls it once per generation)."""
    es = _cma(seed)
    cost = CHUNK + counter.gradient_cost

    def gradient(x):
        value, grad = counter.value_and_gradient(x)
        return grad if np.isfinite(value) and np.all(np.isfinite(grad)) else np.zeros(6)

    while counter.left >= cost:
        x = es.ask(gradf=gradient)
        values = counter.values(np.asarray(x))
        es.tell(x, [float(v) if np.isfinite(v) else PENALTY for v in values])


def run_cma_constrained(counter: Counter, seed: int) -> None:
    """CMA-ES on pycma's augmented-Lagrangian wrapper of min F_flank subject to s >= the
    switching method's margin at every load; each generation's values in one call."""
    import cma
    import cma.constraints_handler
    import cma.logger

    cma.constraints_handler._Logger = cma.logger.LoggerDummy  # its loggers write files to outcmaes/
    es, margin = _cma(seed), go.SwitchConfig().margin
    cache = {}
    fitness = cma.ConstrainedFitnessAL(lambda x: cache[tuple(x)][0], lambda x: cache[tuple(x)][1])
    while counter.left >= CHUNK:
        x = es.ask()
        J, s = counter.flank_values(np.asarray(x))
        for xi, Ji, si in zip(x, J, s):
            finite = np.isfinite(Ji) and np.all(np.isfinite(si))
            cache[tuple(xi)] = (float(Ji) if finite else PENALTY, list(margin - si) if finite else [PENALTY] * len(si))
        es.tell(x, [fitness(xi) for xi in x])
        fitness.update(es)
        cache.clear()


class BudgetSpent(Exception):
    """Raised by a serial method's function when the budget cannot pay another call."""


def _restarted(counter: Counter, seed: int, minimize_from, cost: float) -> None:
    """`minimize_from(x0)` from random starts in [0.2, 0.8]^6 until the budget cannot pay
    another `cost` (the function raises `BudgetSpent` inside a run)."""
    rng = np.random.default_rng(seed)
    while counter.left >= cost:
        try:
            minimize_from(rng.uniform(0.2, 0.8, 6))
        except BudgetSpent:
            return


def run_cobyqa(counter: Counter, seed: int) -> None:
    from scipy.optimize import Bounds, minimize

    def f(x):
        if counter.left < 1.0:
            raise BudgetSpent
        value = counter.value(x)
        return value if np.isfinite(value) else PENALTY

    _restarted(counter, seed, lambda x0: minimize(f, x0, method="COBYQA", bounds=Bounds(0.0, 1.0),
                                                  options={"maxfev": max(1, int(counter.left))}), 1.0)


def run_slsqp(counter: Counter, seed: int) -> None:
    from scipy.optimize import minimize

    def f(x):
        if counter.left < counter.gradient_cost:
            raise BudgetSpent
        value, grad = counter.value_and_gradient(x)
        return (value, grad) if np.isfinite(value) and np.all(np.isfinite(grad)) else (PENALTY, np.zeros(6))

    _restarted(counter, seed, lambda x0: minimize(f, x0, jac=True, method="SLSQP", bounds=[(0.0, 1.0)] * 6,
                                                  options={"maxiter": 1000}), counter.gradient_cost)


RUNNERS = {"ga": run_ga, "gradient": run_gradient, "gradient_restarts": run_gradient_restarts,
           "gradient_smoothed": run_gradient_smoothed,
           "ga_gradient": run_ga_gradient, "cma_es": run_cma,
           "differential_evolution": run_de, "switch": run_switch, "ga_switch": run_ga_switch,
           "cma_es_gradf": run_cma_gradf, "cma_es_constrained": run_cma_constrained, "cobyqa": run_cobyqa,
           "slsqp": run_slsqp, "gearjax_cma_es": run_gearjax_cma}


def gradient_cost(objective, space, repeats: int = 3) -> dict:
    """Time of a value-and-gradient call of STARTS designs over a forward call of the same
    designs (compiled apart, medians)."""
    units = jax.random.uniform(jax.random.PRNGKey(7), (STARTS, 6), jnp.float64)
    designs = space.to_design(units)

    forward = median_time(lambda: batch_objective(objective, designs), repeats)
    both = median_time(lambda: batch_value_and_grad(objective, space, units), repeats)
    return {"forward_s": forward, "value_and_grad_s": both, "ratio": both / forward}


def switch_cost(objective, space, repeats: int = 3) -> dict:
    """Time of a `switch_values` call (flank branch's value and Jacobian) of STARTS designs
    over a forward call of the same designs (compiled apart, medians)."""
    units = jax.random.uniform(jax.random.PRNGKey(7), (STARTS, 6), jnp.float64)
    designs = space.to_design(units)
    forward = median_time(lambda: batch_objective(objective, designs), repeats)
    both = median_time(lambda: switch_values(objective, space, units), repeats)
    return {"forward_s": forward, "switch_values_s": both, "ratio": both / forward}


def load_runs() -> dict:
    return json.loads(RUNS_FILE.read_text()) if RUNS_FILE.exists() else {"runs": {}, "certified": {}}


def save_runs(data: dict) -> None:
    tmp = RUNS_FILE.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    tmp.replace(RUNS_FILE)


def checkpoint_designs(run: dict) -> list:
    """[(checkpoint, unit design of the running best there)] of a run's log."""
    log, out = run["log"], []
    for c in [c for c in CHECKPOINTS if c < run["evaluations"]] + [run["evaluations"]]:
        before = [entry for entry in log if entry[0] <= c + 1e-9]
        if before:
            out.append((c, before[-1][2]))
    return out


def key_of(objective_name: str, unit) -> str:
    return objective_name + ":" + ",".join(f"{u:.12f}" for u in unit)


def certify_runs(data: dict, name: str, objective, space, accuracy: str, chunk: int = 6) -> None:
    """Certify every checkpoint design of the objective's runs not yet certified, `chunk`
    designs per program call, saving after each call."""
    target = with_accuracy(objective, certification_accuracy(accuracy))
    todo = []
    for run_key, run in data["runs"].items():
        if run_key.startswith(name + "/"):
            for _, unit in checkpoint_designs(run):
                key = key_of(name, unit)
                if key not in data["certified"] and key not in {k for k, _ in todo}:
                    todo.append((key, unit))
    print(f"{name}: certifying {len(todo)} designs at {accuracy}", flush=True)
    evaluate_into(data, data["certified"], target, space, todo, chunk)


def evaluate_into(data: dict, store: dict, objective, space, todo: list, chunk: int) -> None:
    """store[key] = the objective at each (key, unit design) of `todo` (None where a stage
    failed), `chunk` designs per program call, the runs file saved after each call."""
    for start in range(0, len(todo), chunk):
        part = todo[start:start + chunk]
        values = batch_objective_in_chunks(objective, space.to_design(jnp.asarray([u for _, u in part])), chunk)
        for (key, _), value in zip(part, values):
            store[key] = float(value) if np.isfinite(value) else None
        save_runs(data)


def best_designs(data: dict, name: str) -> dict:
    """{run key: unit design of the run's certified best}."""
    out = {}
    for run_key, run in data["runs"].items():
        if run_key.startswith(name + "/"):
            scored = [(data["certified"].get(key_of(name, u)), u) for _, u in checkpoint_designs(run)]
            scored = [(v, u) for v, u in scored if v is not None]
            if scored:
                out[run_key] = min(scored, key=lambda vu: vu[0])[1]
    return out


def check_finer(data: dict, name: str, objective, space, spec: str, chunk: int = 6) -> None:
    """Evaluate every run's certified best again at a finer accuracy (`Accuracy.from_spec`,
    e.g. "reference@128x161"), stored under `data["finer"][spec]`."""
    target = with_accuracy(objective, gj.Accuracy.from_spec(spec))
    finer = data.setdefault("finer", {}).setdefault(spec, {})
    todo = [(key_of(name, u), u) for u in best_designs(data, name).values()]
    todo = list({k: u for k, u in todo if k not in finer}.items())
    print(f"{name}: {len(todo)} certified bests at {spec}", flush=True)
    evaluate_into(data, finer, target, space, todo, chunk)


def certified_trajectory(data: dict, name: str, run: dict) -> list:
    """[(checkpoint, lowest certified value of the running bests up to it)]."""
    out, best = [], np.inf
    for c, unit in checkpoint_designs(run):
        value = data["certified"].get(key_of(name, unit))
        if value is not None:
            best = min(best, value)
        out.append((c, best if np.isfinite(best) else None))
    return out


def summary(data: dict, names, methods) -> tuple[dict, dict]:
    """({objective: {method: [one entry per seed]}}, {objective: lowest certified value of
    any run})."""
    objectives, best = {}, {}
    for name in names:
        runs = {k: r for k, r in data["runs"].items() if k.startswith(name + "/")}
        trajectories = {k: certified_trajectory(data, name, r) for k, r in runs.items()}
        finals = [t[-1][1] for t in trajectories.values() if t and t[-1][1] is not None]
        if not finals:
            continue
        best_any = best[name] = min(finals)
        objectives[name] = {}
        for method in methods:
            entries = []
            for k, run in sorted(runs.items()):
                if k.split("/")[1] != method:
                    continue
                t = trajectories[k]
                within = [c for c, v in t if v is not None and v <= 1.01 * best_any]
                entries.append({"seed": run["seed"], "certified_best_N": t[-1][1] if t else None,
                                "search_best_N": run["log"][-1][1] if run["log"] else None,
                                "evaluations": round(run["evaluations"], 1),
                                "evaluations_to_1pct": (int(within[0]) if float(within[0]).is_integer()
                                                        else round(within[0], 1)) if within else None,
                                "wall_s": run["wall_s"], "trajectory": t})
            if entries:
                objectives[name][method] = entries
    return objectives, best


def plot(objectives: dict, best: dict, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(objectives), figsize=(6 * len(objectives), 4.2), squeeze=False)
    for ax, (name, methods) in zip(axes[0], objectives.items()):
        for method, entries in methods.items():
            grid = sorted({c for e in entries for c, _ in e["trajectory"]})
            medians = []
            for c in grid:
                values = [min([v for cc, v in e["trajectory"] if cc <= c and v is not None] or [np.inf]) for e in entries]
                medians.append(np.median(values))
            yardstick = method in YARDSTICKS
            ax.step(grid, medians, where="post", ls="--" if yardstick else "-",
                    label=f"{method}{' (yardstick)' if yardstick else ''}, {len(entries)} seeds")
        ax.axhline(1.01 * best[name], color="k", lw=0.6, ls=":", label="best certified + 1 %")
        ax.set(xscale="log", xlabel="objective evaluations", ylabel="median certified running best F_s (N)",
               title=f"{name}: {', '.join(f'{t:g}' for t in OBJECTIVES[name])} N·m, certified at reference")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def add_finer(data: dict, objectives: dict, spec: str) -> dict:
    """Each entry's certified best at the finer accuracy (`finer_N`); returns per objective
    the largest relative difference (F_finer - F) / F_finer."""
    finer, checks = data["finer"][spec], {}
    for name, methods in objectives.items():
        bests = best_designs(data, name)
        diffs = []
        for method, entries in methods.items():
            for entry in entries:
                unit = bests.get(f"{name}/{method}/{entry['seed']}")
                entry["finer_N"] = None if unit is None else finer.get(key_of(name, unit))
                if entry["finer_N"] is not None and entry["certified_best_N"] is not None:
                    diffs.append((entry["finer_N"] - entry["certified_best_N"]) / entry["finer_N"])
        checks[name] = {"accuracy": spec, "designs": len(bests), "checked": len(diffs),
                        "largest_relative_difference": max(diffs, key=abs) if diffs else None}
        print(f"{name}: certified bests at {spec}: {checks[name]}", flush=True)
    return checks


def markdown(objectives: dict, best: dict) -> str:
    """The results as the docs' table: per objective and method, the median and range of
    the certified best over the seeds, the seeds within 1 % of the best certified value,
    and the median evaluations to get there (over the seeds that did)."""
    def n(x):
        return f"{x:,.0f}".replace(",", " ")

    lines = ["| objective | method | median certified best (N) | range (N) | seeds within 1 % | "
             "median evaluations to 1 % | evaluations used | median at the finer check (N) |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, methods in objectives.items():
        for method, entries in methods.items():
            finals = [e["certified_best_N"] for e in entries if e["certified_best_N"] is not None]
            if not finals:  # runs not certified yet
                continue
            hits = [e["evaluations_to_1pct"] for e in entries if e["evaluations_to_1pct"] is not None]
            used = [e["evaluations"] for e in entries]
            finer = [e.get("finer_N") for e in entries]
            finer = n(np.median(finer)) if all(f is not None for f in finer) else "—"
            to_1pct = f"{np.median(hits):.0f} (n = {len(hits)})" if hits else "—"
            lines.append(f"| {name} | {method} | {n(np.median(finals))} | {n(min(finals))}–{n(max(finals))} | "
                         f"{len(hits)} of {len(entries)} | {to_1pct} | {np.median(used):.0f} | {finer} |")
        lines.append(f"| {name} | best of all runs | {n(best[name])} | | | | | |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--objectives", nargs="+", default=list(OBJECTIVES), choices=list(OBJECTIVES))
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=list(METHODS))
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--budget", type=int, default=1200)
    parser.add_argument("--accuracy", default="default")
    parser.add_argument("--certify", default="reference")
    parser.add_argument("--no-certify", action="store_true", help="run the searches only")
    parser.add_argument("--finer", metavar="SPEC", help="also evaluate each run's certified best at this accuracy "
                        "(e.g. reference@128x161) and report the largest difference")
    parser.add_argument("--plot", action="store_true", help="write docs/figures/optimize_methods.png")
    args = parser.parse_args()
    if args.seeds < 1 or args.budget < 2 * CHUNK * 4:
        raise SystemExit("optimize_methods: --seeds must be >= 1 and --budget >= 80")
    data = load_runs()
    settings = {"budget": args.budget, "search_accuracy": args.accuracy, "certify": args.certify}
    stored = data.setdefault("settings", settings)
    if stored != settings:
        raise SystemExit(f"optimize_methods: {RUNS_FILE.name} holds runs with {stored}; rerun with those settings "
                         "or move the file away")
    for name in args.objectives:
        objective = objective_for(name, args.accuracy)
        space = go.DesignSpace.for_scene(objective.scene)
        cost = data.setdefault("gradient_cost", {}).get(name)
        if cost is None and any(m in GRADIENT_METHODS for m in args.methods):
            cost = data["gradient_cost"][name] = gradient_cost(objective, space)
            save_runs(data)
            print(f"{name}: value and gradient cost {cost['ratio']:.2f} forward calls", flush=True)
        switch = data.setdefault("switch_cost", {}).get(name)
        if switch is None and "switch" in args.methods:
            switch = data["switch_cost"][name] = switch_cost(objective, space)
            save_runs(data)
            print(f"{name}: flank branch's value and Jacobian cost {switch['ratio']:.2f} forward calls", flush=True)
        for seed in range(args.seeds):
            for method in args.methods:
                key = f"{name}/{method}/{seed}"
                if key in data["runs"]:
                    continue
                counter = Counter(objective, space, args.budget, cost["ratio"] if cost else 1.0,
                                  switch["ratio"] if switch else 1.0)
                t0 = time.perf_counter()
                RUNNERS[method](counter, seed)
                wall = time.perf_counter() - t0
                data["runs"][key] = {"seed": seed, "method": method, "budget": args.budget,
                                     "accuracy": args.accuracy, "evaluations": counter.evaluations,
                                     "wall_s": wall, "log": counter.log}
                save_runs(data)
                print(f"{key:40s} best {counter.best:9.1f} N after {counter.evaluations:7.1f} evaluations, {wall:6.1f} s",
                      flush=True)
        if not args.no_certify:
            certify_runs(data, name, objective, space, args.certify)
        if args.finer:
            check_finer(data, name, objective, space, args.finer)
    # The summary holds every certified run of the file, whichever subset this call ran.
    objectives, best = summary(data, list(OBJECTIVES), list(METHODS))
    finer = args.finer or next(iter(data.get("finer", {})), None)
    checks = add_finer(data, objectives, finer) if finer else {}
    checkpoints = [c for c in CHECKPOINTS if c < args.budget] + [args.budget]
    out = {"machine": machine(),
           "settings": {**settings, "checkpoints": checkpoints, "gradient_cost": data.get("gradient_cost", {}),
                        "switch_cost": data.get("switch_cost", {})},
           "best_certified_N": best, "finer_check": checks, "objectives": objectives}
    (RESULTS / "optimize_methods.json").write_text(json.dumps(out, indent=1, allow_nan=False))
    print(markdown(objectives, best))
    if args.plot:
        from pathlib import Path

        plot(objectives, best, Path(__file__).resolve().parents[1] / "docs" / "figures" / "optimize_methods.png")


if __name__ == "__main__":
    main()
