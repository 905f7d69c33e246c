"""`pareto_front`: the front search's run (a run directory that resumes exactly) and the
certification of the front.

The run directory holds `run.json` (what the run is), `history.jsonl` (per iteration the
designs evaluated (mm), their quantities and whether each lies on the flank side),
`state.npz` (the `ParetoState` after the last finished iteration) and `front.json` (the
front's designs with their quantities at the certification accuracy). The archive is every
design evaluated, with the impact of the regime that strikes first (a tip-edge strike with
its own force); the front is its non-dominated set, of which at most
`ParetoConfig.front_size` spread-out designs are evaluated again at the certification
accuracy, and the certified front is the non-dominated set of those.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time

import equinox as eqx
import jax
import numpy as np

from ..io.progress import Progress, compiling
from ..io.rundir import atomic_write
from .batch import batch_quantities
from .certification import accuracy_name, certification_accuracy, with_accuracy
from .front import distinct, nondominated, spread
from .objective import QUANTITIES, Objective
from .pareto import ParetoConfig, pareto_init, pareto_update, pareto_values, with_constraints
from .run import _description, _resume, _starts, _unit
from .space import DesignSpace

_update = eqx.filter_jit(pareto_update)


@dataclasses.dataclass(frozen=True)
class ParetoResult:
    """Outcome of `pareto_front` (host values; quantities in their units and natural sense:
    the stiffness positive).

    Attributes:
        quantities: the traded quantities as "name:aggregate".
        units: their units.
        designs: the certified designs (mm), shape (n, 6): the spread-out front of the
            search's archive.
        values: their quantities at the search's accuracy, shape (n, Q).
        certified: at the certification accuracy (None without certification).
        on_front: which of them are non-dominated by the certified values (by the search's
            without certification).
        archive_designs, archive_values: every design evaluated (with finite quantities)
            and its quantities (the search's accuracy).
        evaluations: evaluations, counted per design, load and error sample (each also
            computed the Jacobian).
        steps: iterations run; wall_time_s: the run's wall time (s), compilation included.
        accuracy, certification_accuracy: preset names ("custom" otherwise; None without).
        run_dir: the run directory, or None.
    """

    quantities: tuple[str, ...]
    units: tuple[str, ...]
    designs: np.ndarray
    values: np.ndarray
    certified: np.ndarray | None
    on_front: np.ndarray
    archive_designs: np.ndarray
    archive_values: np.ndarray
    evaluations: int
    steps: int
    wall_time_s: float
    accuracy: str
    certification_accuracy: str | None
    run_dir: str | None

    @property
    def front(self) -> tuple[np.ndarray, np.ndarray]:
        """The front's designs (mm) and their certified quantities (the search's without)."""
        values = self.values if self.certified is None else self.certified
        return self.designs[self.on_front], values[self.on_front]


def pareto_front(
    objective: Objective,
    space: DesignSpace,
    config: ParetoConfig | None = None,
    *,
    seed: int = 0,
    run_dir: str | os.PathLike | None = None,
    resume: bool = False,
    progress: str | None = None,
    certify: str | None = "reference",
) -> ParetoResult:
    """The Pareto front of `config.quantities` over the objective's duty cycle
    (`gearjax.optimize.pareto`), one compiled call per iteration, certified at `certify`.

    Args:
        objective: the `Objective` (its loads, speeds, time shares, errors and accuracy;
            its own quantity and penalties are not used).
        space: the `DesignSpace`.
        config: the `ParetoConfig` (default: force, loaded TE and worst-case pressure).
        seed, run_dir, resume, progress: as `minimize`'s.
        certify: accuracy preset (or `Accuracy`) at which the front is evaluated again, or None.
    """
    config = ParetoConfig() if config is None else config
    if not isinstance(config, ParetoConfig):
        raise ValueError(f"config must be a ParetoConfig; got {type(config).__name__}")
    if not isinstance(objective, Objective):
        raise ValueError("objective must be a gearjax.optimize.Objective (Objective.create(scene, ...))")
    target = certification_accuracy(certify)
    space.check_fits(objective.scene)
    quantities = config.parsed(objective.aggregate)
    names = tuple(f"{n}:{a}" for n, a in quantities)
    description = _description("pareto", config.iterations, config, objective, space, seed)
    description["quantities"] = list(names)
    init = pareto_init(jax.random.PRNGKey(seed), config, _unit(space, _starts(objective, space, None)),
                       objective.torques.dtype)
    init = with_constraints(init, int(objective.torques.shape[0]) * objective.samples)
    start = time.perf_counter()
    directory, state, records = _resume(run_dir, resume, init, description)
    before = records[-1]["elapsed_s"] if records else 0.0
    elapsed = lambda: before + time.perf_counter() - start  # noqa: E731
    state = _iterate(objective, space, config, quantities, state, records, directory, progress, elapsed)
    sense = np.asarray([QUANTITIES[n].sense for n, _ in quantities])
    designs, values = _archive(records)
    chosen = _front_designs(designs, values * sense, config.front_size)
    certified = None
    if target is not None and target == objective.scene.accuracy:
        certified = values[chosen].copy()  # the search's own accuracy: nothing to evaluate again
    elif target is not None and len(chosen):
        certified = _certified(directory, objective, designs[chosen], quantities, target, config.front_size, progress)
    ranked = (values[chosen] if certified is None else certified) * sense
    return ParetoResult(
        quantities=names, units=tuple(QUANTITIES[n].unit for n, _ in quantities), designs=designs[chosen],
        values=values[chosen], certified=certified, on_front=nondominated(ranked) if len(chosen) else np.zeros(0, bool),
        archive_designs=designs, archive_values=values,
        evaluations=len(records) * config.slots * int(objective.torques.shape[0]) * objective.samples,
        steps=len(records), wall_time_s=elapsed(), accuracy=accuracy_name(objective.scene.accuracy),
        certification_accuracy=None if target is None else accuracy_name(target),
        run_dir=None if directory is None else str(directory.path))


def _iterate(objective, space, config, quantities, state, records, directory, progress, elapsed):
    """The iterations after those in `records`, each saved to the run directory."""
    bar = Progress(progress, config.iterations, len(records), "iteration")
    sense = np.asarray([QUANTITIES[n].sense for n, _ in quantities])
    try:
        for step in range(len(records) + 1, config.iterations + 1):
            units = state.sqp.trial
            with compiling("the front's value-and-Jacobian program", mode=progress if step == 1 else None):
                values = pareto_values(objective, space, units, quantities)
            state = _update(state, values, config)
            q, s = np.asarray(values[4]), np.asarray(values[2])
            flank = np.all(s >= 0.0, axis=1)
            record = {"step": step, "designs_mm": np.asarray(space.to_design(units)).tolist(),
                      "quantities": (q * sense).tolist(), "flank": flank.tolist(),
                      "evaluations": step * config.slots * int(objective.torques.shape[0]) * objective.samples,
                      "elapsed_s": elapsed(), "random_key": np.asarray(state.sqp.key).tolist()}
            records.append(record)
            if directory is not None:
                directory.save(state, record)
            bar.update(step, record["elapsed_s"], flank=f"{int(np.sum(flank))} of {len(flank)} on the flank side")
    finally:
        bar.close()
    return state


def _archive(records) -> tuple[np.ndarray, np.ndarray]:
    """Every design evaluated (mm) with finite quantities, and its quantities (natural
    sense), from the run's records."""
    if not records:
        return np.zeros((0, 6)), np.zeros((0, 0))
    designs = np.concatenate([np.asarray(r["designs_mm"], float) for r in records])
    values = np.concatenate([np.asarray(r["quantities"], float) for r in records])
    finite = np.all(np.isfinite(values), axis=1)
    return designs[finite], values[finite]


def _front_designs(designs, minimised, count: int) -> np.ndarray:
    """Indices of the archive's distinct non-dominated designs, at most `count` spread out."""
    if len(designs) == 0:
        return np.zeros(0, int)
    keep = np.flatnonzero(nondominated(minimised))
    keep = keep[distinct(designs[keep])]
    return keep[spread(minimised[keep], count)]


def _certified(directory, objective, designs, quantities, accuracy, rows, progress) -> np.ndarray:
    """The designs' quantities (natural sense) at the certification accuracy, `rows` designs
    per call; reused from the run directory's `front.json` for the same designs and accuracy."""
    path = None if directory is None else directory.path / "front.json"
    name = accuracy_name(accuracy)
    if path is not None and path.exists():
        stored = json.loads(path.read_text())
        if stored["accuracy"] == name != "custom" and np.array_equal(np.asarray(stored["designs_mm"]), designs):
            return np.asarray(stored["certified"], float)
    with compiling("the certification program", mode=progress):
        certified = batch_quantities(with_accuracy(objective, accuracy), designs, quantities, rows)
    if path is not None:
        atomic_write(path, json.dumps({"accuracy": name, "quantities": [f"{n}:{a}" for n, a in quantities],
                                       "designs_mm": designs.tolist(), "certified": certified.tolist()},
                                      indent=1).encode())
    return certified

