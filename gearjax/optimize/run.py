"""Optimisation runs: one compiled call per generation/iteration, a run directory that
loses nothing, exact resumption, progress display.

A run directory holds

* `run.json`: what the run is (method, settings, bounds, objective, seed), written once;
  a resumed run must match it;
* `history.jsonl`: one line per generation/iteration, appended and flushed to disk
  (`fsync`) as soon as it is done: step, the evaluated designs (mm) and their objective
  values, the best value and design so far, cumulative evaluations, elapsed time and the
  random state;
* `state.npz`: the full optimiser state after the last finished step (random key,
  population and fitness, or Adam's state), replaced atomically (`os.replace`);
* `certification.json`: the best candidates evaluated at the certification accuracy
  (`gearjax.optimize.certification`), written once the search is done and reused on resume.

Resuming loads `state.npz`, drops history lines past its step (a step whose state was not
yet saved), and continues. The state holds everything the next step depends on and every
step is one deterministic compiled program, so a resumed run ends with exactly the
designs, values and history of an uninterrupted one.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time

import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import ArrayLike
from .._validate import check_int
from ..accuracy import Accuracy
from ..io.progress import Progress, compiling
from ..io.rundir import RunDirectory, atomic_write
from .certification import CERTIFY_TOP, Certification, accuracy_name, candidates, certification_accuracy, certify
from .ga import GAConfig
from .gradient import GradientConfig
from .methods import GeneticSearch, GradientSearch, SearchMethod
from .objective import Objective
from .space import DesignSpace


@dataclasses.dataclass(frozen=True)
class OptimizationResult:
    """Outcome of `minimize` (`genetic`, `gradient_descent`; host values, engine units).

    Attributes:
        method: the method's registered name (`gearjax.optimize.methods`).
        best_design: $(y_1, \\dots, y_6)$ (mm) of the best design: the lowest certified
            value among the certified candidates, or the search's best without certification.
        best_objective: its objective value at the search's accuracy (N or mm/s).
        certified_objective: its objective at the certification accuracy (None without).
        certification: the `Certification` of the candidates, the initial design last
            unless it is one of them (None without).
        best_source: "search" or "initial": the result is never worse than the scene's
            own design; where the search found nothing better (certified, or at the search's
            accuracy without certification), the best design is the initial one.
        initial_objective: the objective of the scene's own modification (the unmodified
            pair's for a scene without one), at the search's accuracy.
        initial_design: that modification (mm); it starts the search (first member of the
            population, first start) where it lies within the bounds.
        history: best value after each generation/iteration.
        evaluations: objective evaluations, counted per design and load (and error sample).
        gradient_evaluations: of those, evaluations that also computed the gradient.
        steps: generations or iterations run.
        wall_time_s: wall time of the whole run (s), compilation included; a resumed run
            adds the time of the runs before.
        converged: gradient: every start stopped by its criterion before the cap; GA: the
            best value did not change over the last quarter of the generations.
        run_dir: the run directory, or None.
    """

    method: str
    best_design: np.ndarray
    best_objective: float
    initial_objective: float
    initial_design: np.ndarray
    history: list[float]
    evaluations: int
    gradient_evaluations: int
    steps: int
    wall_time_s: float
    converged: bool
    run_dir: str | None
    certified_objective: float | None = None
    certification: Certification | None = None
    best_source: str = "search"


# ---------------------------------------------------------------------------- drivers
def _description(name: str, steps: int, config, objective: Objective, space: DesignSpace, seed) -> dict:
    """What a run directory's `run.json` holds of a search (method `name`, its `steps` and
    `config`), its objective and space: a resumed run must match it."""
    o = objective
    return {
        "method": name,
        "seed": int(seed),
        "steps": int(steps),
        "config": {f.name: getattr(config, f.name) for f in dataclasses.fields(config)},
        "lower_mm": np.asarray(space.lower).tolist(),
        "upper_mm": np.asarray(space.upper).tolist(),
        "objective": {
            "quantity": o.quantity,
            "aggregate": o.aggregate,
            "torques_Nmm": np.asarray(o.torques).tolist(),
            "speeds_rad_s": np.asarray(o.speeds).tolist(),
            "weights": np.asarray(o.weights).tolist(),
            "error_samples": o.samples,
            "errors_mm": {k: np.asarray(getattr(o.errors, k)).tolist() for k in ("base_pitch_deviation", "pitch_deviation", "misalignment")},
            "penalties": [None if p is None else [p.limit, p.weight] for p in (o.pressure_penalty, o.lte_penalty)],
            "accuracy": repr(o.scene.accuracy),
        },
    }


def minimize(
    objective: Objective,
    space: DesignSpace,
    method: SearchMethod,
    *,
    seed: int = 0,
    run_dir: str | os.PathLike | None = None,
    resume: bool = False,
    progress: str | None = None,
    initial: ArrayLike | None = None,
    certify: str | Accuracy | None = "reference",
    certify_top: int = CERTIFY_TOP,
) -> OptimizationResult:
    """Minimise the objective with a search method (`gearjax.optimize.methods`: a
    registered `SearchMethod` with its settings), one compiled call of the objective's
    batch program per step, every step written to `run_dir`; then certify.

    Args:
        objective: the `Objective`.
        space: the `DesignSpace` (bounds in mm).
        method: the method, e.g. `GeneticSearch(GAConfig(), generations=30)` or
            `GradientSearch(GradientConfig())`.
        seed: random seed; the same seed gives the same run bit for bit.
        run_dir: directory for the run's files (see the module docstring), or None.
        resume: continue the run in `run_dir`.
        progress: "auto" (a tqdm bar on a terminal, else plain lines), "bar", "lines" or
            None (quiet).
        initial: designs (mm, shape (m, 6)) that start the search (first members of the
            GA's population, first starts), clipped to the bounds; by default the scene's
            own design where it lies within the bounds, the rest random.
        certify: accuracy at which the best candidates are evaluated again once the search
            is done (a preset name or an `Accuracy`; `gearjax.optimize.certification`), or None.
        certify_top: candidates certified besides the best design found (the method's
            `candidates`) and the initial design.

    The result is the best of the certified candidates and the scene's own design: never
    worse than the start (`OptimizationResult.best_source` says which).
    """
    if not isinstance(method, SearchMethod):
        raise ValueError(f"method must be a SearchMethod (gearjax.optimize.methods); got {type(method).__name__}")
    certify_accuracy = _checked(objective, method.steps, certify_top, certify)
    space.check_fits(objective.scene)
    init_state = method.init(jax.random.PRNGKey(seed), _unit(space, _starts(objective, space, initial)),
                             objective.torques.dtype)
    start = time.perf_counter()
    description = _description(method.name, method.steps, method.config, objective, space, seed)
    directory, state, records = _resume(run_dir, resume, init_state, description)
    previous_time = records[-1]["elapsed_s"] if records else 0.0
    initial_design = np.asarray(objective.scene.modification.as_vector())
    with compiling(f"{method.program} for this objective", mode=progress):  # the run's one big compilation
        initial = (records[0]["initial_objective"] if records
                   else method.initial_objective(objective, space, initial_design))
    state = _steps(method, objective, space, state, records, directory, progress, initial,
                   lambda: previous_time + time.perf_counter() - start)
    best, best_design = _best(method, state, space)
    certification = None
    if certify_accuracy is not None:
        designs, values = _with_initial(*candidates(*method.candidates(state), space, certify_top), initial_design,
                                        initial)
        # one batch shape for every run: the search's candidates and the initial design
        certification = _certification(directory, objective, designs, values, certify_accuracy, certify_top + 1,
                                       progress)
        i = certification.best
        best_design, best = certification.designs[i], float(certification.objective[i])
    elif np.isfinite(initial) and not initial >= best:  # the search found nothing lower
        best_design, best = initial_design, float(initial)
    source = "initial" if _same_design(best_design, initial_design) else "search"
    history = [r["best_objective"] for r in records]
    evaluations = len(records) * method.batch * int(objective.torques.shape[0]) * objective.samples
    return OptimizationResult(
        method=method.name,
        best_design=best_design,
        best_objective=best,
        initial_objective=float(initial),
        initial_design=initial_design,
        history=history,
        evaluations=evaluations,
        gradient_evaluations=evaluations if method.uses_gradients else 0,
        steps=len(records),
        wall_time_s=previous_time + time.perf_counter() - start,
        converged=method.converged(state, history),
        run_dir=None if directory is None else str(directory.path),
        certified_objective=None if certification is None else float(certification.certified[certification.best]),
        certification=certification,
        best_source=source,
    )


def _steps(method: SearchMethod, objective, space, state, records: list, directory, progress, initial, elapsed):
    """Run the method's steps after those in `records` (appended to it and saved to the
    run directory one by one) until its cap or until it has finished; the last state."""
    samples = int(objective.torques.shape[0]) * objective.samples
    bar = Progress(progress, method.steps, len(records), method.step_name)
    try:
        for step in range(len(records) + 1, method.steps + 1):
            state, designs, values = method.step(objective, space, state)
            best, best_design = _best(method, state, space)
            record = _record(step, state, designs, values, best, best_design, step * method.batch * samples,
                             elapsed(), initial)
            records.append(record)
            if directory is not None:
                directory.save(state, record)
            bar.update(step, record["elapsed_s"], best=f"{best:.6g}")
            if method.finished(state):
                break
    finally:
        bar.close()
    return state


def _checked(objective, steps, certify_top, certify_accuracy):
    """The run's inputs checked before any work; returns the certification `Accuracy`."""
    check_int("steps (generations or iterations)", steps, 1)
    check_int("certify_top", certify_top, 1)
    if not isinstance(objective, Objective):
        raise ValueError("objective must be a gearjax.optimize.Objective (Objective.create(scene, ...))")
    return certification_accuracy(certify_accuracy)


def _resume(run_dir, resume, init_state, description):
    """The run directory (None without one), and the state and step records to continue from
    (`init_state` and none for a new run)."""
    if run_dir is None:
        return None, init_state, []
    directory = RunDirectory(run_dir, description, resume)
    loaded = directory.load(init_state) if resume else None
    state, records = loaded if loaded is not None else (init_state, [])
    return directory, state, records


def _record(step, state, designs, values, best, best_design, evaluations, elapsed, initial) -> dict:
    """One step's record, as the run directory stores it (designs in mm)."""
    return {
        "step": step,
        "designs_mm": np.asarray(designs).tolist(),
        "objective": [float(v) for v in np.asarray(values)],
        "best_objective": best,
        "best_design_mm": best_design.tolist(),
        "evaluations": evaluations,
        "elapsed_s": elapsed,
        "initial_objective": initial,
        "random_key": np.asarray(getattr(state, "key", jnp.zeros(2, jnp.uint32))).tolist(),
    }


#: designs closer than this in every parameter (mm) are the same design (a design passed
#: through the unit cube and back differs from itself by rounding)
SAME_DESIGN_MM = 1e-12


def _same_design(a, b) -> bool:
    return bool(np.allclose(a, b, rtol=0.0, atol=SAME_DESIGN_MM))


def _with_initial(designs, values, initial_design, initial_value):
    """The search's candidates (mm, best first) and the initial design last, unless it is
    one of them already."""
    if any(_same_design(d, initial_design) for d in designs):
        return designs, values
    return (np.concatenate([designs, np.asarray(initial_design, float)[None]]),
            np.concatenate([values, [initial_value]]))


def _certification(directory, objective, designs, values, accuracy, top, progress) -> Certification:
    """`certify` the candidates, or the run directory's certification of the same
    candidates at the same accuracy (a resumed run that had finished)."""
    path = None if directory is None else directory.path / "certification.json"
    if path is not None and path.exists():
        stored = Certification.from_dict(json.loads(path.read_text()))
        name = accuracy_name(accuracy)  # a custom accuracy is certified again
        if stored.accuracy == name != "custom" and np.array_equal(stored.designs, designs):
            return stored
    with compiling("the certification program", mode=progress):
        result = certify(objective, designs, values, accuracy=accuracy, top=top)
    if path is not None:
        atomic_write(path, json.dumps(result.to_dict(), indent=1).encode())
    return result


def _best(method: SearchMethod, state, space: DesignSpace) -> tuple[float, np.ndarray]:
    """Best value and design (mm) so far."""
    value, unit = method.best(state)
    return float(value), np.asarray(space.to_design(unit))


def _starts(objective: Objective, space: DesignSpace, initial):
    """The designs that start the search: `initial`, or by default the scene's own design
    where it lies within the bounds (else None: a random start)."""
    if initial is not None:
        return initial
    own = np.asarray(objective.scene.modification.as_vector())
    return own[None] if space.contains(own) else None


def _unit(space: DesignSpace, designs):
    """Unit-cube coordinates of designs (mm), or None."""
    if designs is None:
        return None
    designs = np.atleast_2d(np.asarray(designs, dtype=float))
    if designs.shape[-1] != 6 or not np.all(np.isfinite(designs)):
        raise ValueError(f"initial designs must be finite (y1..y6) rows in mm; got shape {designs.shape}")
    return np.asarray(space.to_unit(designs))


def genetic(
    objective: Objective,
    space: DesignSpace,
    *,
    config: GAConfig | None = None,
    generations: int = 30,
    **options,
) -> OptimizationResult:
    """Minimise the objective with the genetic algorithm (`gearjax.optimize.ga`): `minimize`
    with `GeneticSearch(config, generations)` (default seed 001's population 40 over 30
    generations); one compiled call per generation evaluates the whole population. The
    other arguments (`seed`, `run_dir`, `resume`, `progress`, `initial`, `certify`,
    `certify_top`) are `minimize`'s."""
    return minimize(objective, space, GeneticSearch(GAConfig() if config is None else config, generations), **options)


def gradient_descent(
    objective: Objective,
    space: DesignSpace,
    *,
    config: GradientConfig | None = None,
    **options,
) -> OptimizationResult:
    """Minimise the objective by projected Adam from `config.starts` Latin-hypercube starts
    (`gearjax.optimize.gradient`; with `config.smoothing`, on the Gaussian-smoothed
    objective), all starts and their samples in one compiled call per iteration:
    `minimize` with `GradientSearch(config)`; `config.iterations` caps the iterations. The
    other arguments are `minimize`'s."""
    return minimize(objective, space, GradientSearch(GradientConfig() if config is None else config), **options)
