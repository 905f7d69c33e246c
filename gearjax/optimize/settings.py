"""The `[optimize]` section of a scene file: what `gearjax optimize` runs.

Every key is optional (defaults in brackets); units are those of the scene file:

    [optimize]
    method = "cma_es"             # a registered method: "cma_es" | "gradient" | "ga" | "switch" ["cma_es"]
    objective = "force"           # "force" (F_s, N) | "velocity" (|v_n|, mm/s) | "lte" (loaded
                                  #   TE peak-to-peak, um) | "pressure" (MPa) | "stiffness"
                                  #   (mean mesh stiffness, N/(mm um), maximised) ["force"]
    loads_Nm = [400, 1000, 1600]  # duty cycle: loads [the scene's torque]
    speeds_rpm = [3000, 5000, 5000] #   the pinion speed at each, or one for all [the scene's]
    load_weights = [1, 2, 1]      #   time shares, one per load, sum > 0 [equal]
    aggregate = "mean"            # "mean" (time-weighted) | "max" (worst case) over the loads ["mean"]
    error_samples = 8             # sampled mesh errors, 0 = the scene's own errors [0]
    misalignment_um = 10.0        # tolerance: f_ma ~ U(-t, t) [0]
    base_pitch_deviation_um = 5.0 # tolerance: f_pb ~ U(-t, t) [0]
    max_pressure_MPa = 1500.0     # penalty limit on the largest Hertz pressure [none]
    pressure_penalty = 1000.0     # its weight, in the objective's unit [1000]
    max_lte_um = 2.0              # penalty limit on the loaded TE peak-to-peak [none]
    lte_penalty = 1000.0          # its weight [1000]
    accuracy = "default"          # accuracy preset of the search [the scene's]
    certify = "reference"         # preset at which the best designs are evaluated again
                                  #   and the best is chosen, or "none" ["reference"]
    certify_top = 5               # candidates certified besides the best found [5]
    population = 40               # GA [40], CMA-ES [10]
    generations = 30              # GA [30], CMA-ES [120]
    starts = 10                   # gradient [10], switch: start slots [6]
    iterations = 100              # gradient [100], switch: SQP iterations [30], --pareto [40]
    learning_rate = 0.05          # gradient, unit-cube coordinates [0.05]
    smoothing = 0.0               # gradient: Gaussian smoothing sigma_0, unit cube, 0-0.5 [0]
    smoothing_pairs = 2           # gradient: antithetic samples per start when smoothing [2]
    switch_margin_mm = 0.05       # switch, --pareto: roll length kept off the regime switch [0.05]
    pareto_quantities = ["force", "lte", "pressure:max"]  # --pareto: traded quantities,
                                  #   "name" or "name:aggregate" [this list]
    pareto_divisions = 5          # --pareto: weight lattice divisions (21 scalarisations) [5]
    seed = 0                      # [0]
    root_relief_um = [5, 75]      # bounds, one key per parameter (the [modification]
    tip_relief_um = [5, 75]       #   keys), [lower, upper]; seed 001's by default:
    root_relief_length = [0.5, 4] #   amounts 0.001-0.015 m_n, lengths 0.1-0.8 m_n,
    tip_relief_length = [0.5, 4]  #   unmodified_length 0-0.5 b
    crowning_um = [5, 75]
    unmodified_length = [0, 21]
"""

from __future__ import annotations

import dataclasses
from typing import Any

from ..accuracy import PRESETS, Accuracy
from ..io.declared_keys import INF, SceneKey, check_keys
from ..scene import Scene
from .certification import scene_with_accuracy
from .cma import CMAConfig
from .ga import GAConfig
from .gradient import GradientConfig
from .switch import SwitchConfig
from .pareto import ParetoConfig
from .objective import AGGREGATES, QUANTITIES, Objective, Penalty, sample_errors
from .methods import METHODS
from .space import _MODULE_BOUNDS, PARAMETERS, SCENE_KEYS, DesignSpace

_KEYS = {
    "method", "objective", "loads_Nm", "speeds_rpm", "load_weights", "aggregate", "error_samples", "misalignment_um",
    "base_pitch_deviation_um", "max_pressure_MPa", "pressure_penalty", "max_lte_um", "lte_penalty",
    "accuracy", "population", "generations", "starts", "iterations", "learning_rate", "smoothing",
    "smoothing_pairs", "switch_margin_mm", "pareto_quantities", "pareto_divisions", "seed", "certify", "certify_top",
} | {key for key, _ in SCENE_KEYS}


class SettingsError(ValueError):
    """A bad `[optimize]` section; the message names the field as `[optimize] key`."""


def _fail(key: str, message: str) -> SettingsError:
    return SettingsError(f"[optimize] {key}: {message}")


def _number(key: str, value: Any, low: float | None = None, integer: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or (integer and not isinstance(value, int)):
        raise _fail(key, f"must be {'an integer' if integer else 'a number'}; got {value!r}")
    if value != value or value in (float("inf"), float("-inf")):
        raise _fail(key, f"must be finite; got {value!r}")
    if low is not None and value < low:
        raise _fail(key, f"must be >= {low:g}; got {value!r}")
    return value


def _choice(key: str, value: Any, choices: tuple) -> str:
    if value not in choices:
        raise _fail(key, f"must be one of {', '.join(map(repr, choices))}; got {value!r}")
    return value


@dataclasses.dataclass(frozen=True)
class OptimizeSettings:
    """The parsed `[optimize]` section (scene-file units)."""

    method: str = "cma_es"
    objective: str = "force"
    loads_Nm: tuple[float, ...] | None = None
    speeds_rpm: tuple[float, ...] | None = None
    load_weights: tuple[float, ...] | None = None
    aggregate: str = "mean"
    error_samples: int = 0
    misalignment_um: float = 0.0
    base_pitch_deviation_um: float = 0.0
    max_pressure_MPa: float | None = None
    pressure_penalty: float = 1000.0
    max_lte_um: float | None = None
    lte_penalty: float = 1000.0
    accuracy: str | None = None  # None: the scene's own
    certify: str | None = "reference"  # None: no certification
    certify_top: int = 5
    population: int | None = None  # None: the method's own default
    generations: int | None = None
    starts: int | None = None  # None: the method's own default
    iterations: int | None = None
    learning_rate: float = 0.05
    smoothing: float = 0.0
    smoothing_pairs: int = 2
    switch_margin_mm: float = 0.05
    pareto_quantities: tuple[str, ...] = ("force", "lte", "pressure:max")
    pareto_divisions: int = 5
    seed: int = 0
    bounds: dict = dataclasses.field(default_factory=dict)  # parameter -> (lo, hi) in mm

    @classmethod
    def from_dict(cls, table: dict) -> OptimizeSettings:
        if not isinstance(table, dict):
            raise SettingsError("[optimize] must be a TOML table")
        for key in table:
            if key not in _KEYS:
                raise _fail(key, f"unknown field; allowed: {', '.join(sorted(_KEYS))}")
        try:
            check_keys("optimize", scene_keys(), table)
        except ValueError as err:
            raise SettingsError(str(err)) from None
        out: dict[str, Any] = {}
        if "method" in table:
            out["method"] = _choice("method", table["method"], tuple(sorted(METHODS)))
        if "objective" in table:
            out["objective"] = _choice("objective", table["objective"], tuple(QUANTITIES))
        if "aggregate" in table:
            out["aggregate"] = _choice("aggregate", table["aggregate"], AGGREGATES)
        if "accuracy" in table:
            out["accuracy"] = _choice("accuracy", table["accuracy"], ("fast", "default", "reference"))
        for key in ("loads_Nm", "speeds_rpm", "load_weights"):
            if key in table:
                value = table[key]
                if not isinstance(value, list) or not value:
                    raise _fail(key, f"must be a non-empty list of numbers; got {value!r}")
                out[key] = tuple(float(_number(key, v, 0.0)) for v in value)
        if "loads_Nm" in out and any(v <= 0.0 for v in out["loads_Nm"]):
            raise _fail("loads_Nm", f"must be torques > 0 N·m; got {list(out['loads_Nm'])}")
        if "certify" in table:
            choice = _choice("certify", table["certify"], ("fast", "default", "reference", "none"))
            out["certify"] = None if choice == "none" else choice
        for key, low in (("error_samples", 0), ("population", 2), ("generations", 1), ("starts", 1),
                         ("iterations", 1), ("smoothing_pairs", 1), ("seed", 0), ("certify_top", 1),
                         ("pareto_divisions", 1)):
            if key in table:
                out[key] = int(_number(key, table[key], low, integer=True))
        for key in ("misalignment_um", "base_pitch_deviation_um", "max_pressure_MPa", "pressure_penalty",
                    "max_lte_um", "lte_penalty", "learning_rate", "smoothing", "switch_margin_mm"):
            if key in table:
                out[key] = float(_number(key, table[key], 0.0))
        if "pareto_quantities" in table:
            value = table["pareto_quantities"]
            if not isinstance(value, list) or len(value) < 2:
                raise _fail("pareto_quantities", f"must be a list of at least two quantities; got {value!r}")
            try:
                ParetoConfig(quantities=tuple(value))
            except ValueError as err:
                raise _fail("pareto_quantities", str(err)) from None
            out["pareto_quantities"] = tuple(value)
        bounds = {}
        for (key, factor), name in zip(SCENE_KEYS, PARAMETERS):
            if key in table:
                value = table[key]
                if not isinstance(value, list) or len(value) != 2:
                    raise _fail(key, f"must be [lower, upper]; got {value!r}")
                lo, hi = (float(_number(key, v)) / factor for v in value)
                bounds[name] = (lo, hi)
        out["bounds"] = bounds
        return cls(**out)

    def build(self, scene: Scene) -> tuple[Objective, DesignSpace]:
        """The objective (at this section's accuracy) and the design space of `scene`."""
        if scene.operating.torque is None or "impact" not in scene.effects:
            raise SettingsError(
                "[optimize] the scene needs a torque ([operating] torque_Nm) and effects = [\"impact\"] ([analysis])"
            )
        try:
            space = DesignSpace.for_scene(scene, **self.bounds)
        except ValueError as err:
            raise SettingsError(f"[optimize] {err}") from None
        if self.accuracy is not None:
            scene = scene_with_accuracy(scene, Accuracy.preset(self.accuracy))
        errors = None
        if self.error_samples > 0:
            errors = sample_errors(
                self.error_samples,
                misalignment=self.misalignment_um * 1e-3,
                base_pitch_deviation=self.base_pitch_deviation_um * 1e-3,
                seed=self.seed,
            )
        pressure = None if self.max_pressure_MPa is None else Penalty(self.max_pressure_MPa, self.pressure_penalty)
        lte = None if self.max_lte_um is None else Penalty(self.max_lte_um * 1e-3, self.lte_penalty)
        try:
            objective = Objective.create(
                scene,
                torques_Nm=self.loads_Nm,
                speeds_rpm=self.speeds_rpm,
                weights=self.load_weights,
                quantity=self.objective,
                aggregate=self.aggregate,
                errors=errors,
                pressure_penalty=pressure,
                lte_penalty=lte,
            )
        except ValueError as err:
            raise SettingsError(f"[optimize] {err}") from None
        return objective, space

    def search_method(self):
        """The `SearchMethod` this section names, set up from its keys."""
        return METHODS[self.method].from_settings(self)

    def ga_config(self) -> GAConfig:
        population = self.population or 40
        return GAConfig(population=population, elite=max(1, min(2, population - 1)))

    def cma_config(self) -> CMAConfig:
        population = self.population or 10
        if population < 4:
            raise _fail("population", f"CMA-ES needs >= 4 candidates per generation; got {population}")
        return CMAConfig(population=population)

    def gradient_config(self) -> GradientConfig:
        starts, iterations = self.starts or 10, self.iterations or 100
        return GradientConfig(starts=starts, iterations=iterations, learning_rate=self.learning_rate,
                              smoothing=self.smoothing, smoothing_pairs=self.smoothing_pairs)

    def switch_config(self) -> SwitchConfig:
        return SwitchConfig(starts=self.starts or 6, iterations=self.iterations or 30, margin=self.switch_margin_mm)

    def pareto_config(self) -> ParetoConfig:
        """The front search's settings (`gearjax optimize --pareto`)."""
        try:
            return ParetoConfig(quantities=self.pareto_quantities, divisions=self.pareto_divisions,
                                iterations=self.iterations or 40, margin=self.switch_margin_mm)
        except ValueError as err:
            raise SettingsError(f"[optimize] {err}") from None


def scene_keys() -> tuple[SceneKey, ...]:
    """The `[optimize]` section's keys with unit, default, allowed values and meaning, in
    the order of the scene-file reference (`gearjax.io.scene_keys.reference`)."""
    d = {f.name: f.default for f in dataclasses.fields(OptimizeSettings)}
    count = lambda key, low, meaning: SceneKey(key, "", d[key], meaning, (low, INF, True, True), integer=True)  # noqa: E731
    weight = lambda key, unit, meaning: SceneKey(key, unit, d[key], meaning, (0.0, INF, True, True))  # noqa: E731
    keys = [
        SceneKey("method", "", d["method"], "search method (`gearjax.optimize.methods`)", choices=tuple(sorted(METHODS))),
        SceneKey("objective", "", d["objective"], "quantity minimised: " + "; ".join(
            f"`{name}`, {q.what} ({q.unit})" for name, q in QUANTITIES.items()), choices=tuple(QUANTITIES)),
        SceneKey("loads_Nm", "N·m", None, "pinion torques of the load spectrum", (0.0, INF, False, True),
                 absent="the scene's torque", allowed="a non-empty list"),
        SceneKey("speeds_rpm", "rpm", None, "pinion speed at each load of the spectrum", (0.0, INF, True, True),
                 absent="the scene's speed", allowed="one per load, or one for all"),
        SceneKey("load_weights", "", None, "time shares (weights) of the loads", (0.0, INF, True, True), absent="equal",
                 allowed="one per load, with a positive sum"),
        SceneKey("aggregate", "", d["aggregate"], "over the loads: time-weighted mean or worst case (maximum)",
                 choices=AGGREGATES),
        count("error_samples", 0, "sampled mesh errors per design (0: the scene's own errors)"),
        weight("misalignment_um", "µm", "tolerance of f_ma: samples drawn from U(−t, t)"),
        weight("base_pitch_deviation_um", "µm", "tolerance of f_pb"),
        SceneKey("max_pressure_MPa", "MPa", None, "limit of the largest Hertz pressure (penalised beyond)",
                 (0.0, INF, False, True), absent="no limit"),
        weight("pressure_penalty", "", "weight of the pressure penalty, in the objective's unit"),
        SceneKey("max_lte_um", "µm", None, "limit of the loaded TE peak-to-peak (penalised beyond)", (0.0, INF, False, True),
                 absent="no limit"),
        weight("lte_penalty", "", "weight of the loaded-TE penalty, in the objective's unit"),
        SceneKey("accuracy", "", None, "accuracy preset of the search", choices=tuple(PRESETS),
                 absent="the scene's (`[analysis] accuracy`)"),
        SceneKey("certify", "", d["certify"], "preset at which the best candidates are evaluated again "
                 "(`none`: no certification)", choices=tuple(PRESETS) + ("none",)),
        count("certify_top", 1, "candidates certified"),
        SceneKey("population", "", None, "GA, CMA-ES: candidates per generation (CMA-ES: >= 4)", (2, INF, True, True),
                 absent="GA 40, CMA-ES 10", integer=True),
        SceneKey("generations", "", None, "GA, CMA-ES: generations", (1, INF, True, True),
                 absent="GA 30, CMA-ES 120", integer=True),
        SceneKey("starts", "", None, "gradient, switch: Latin-hypercube starts (start slots)", (1, INF, True, True),
                 absent="gradient 10, switch 6", integer=True),
        SceneKey("iterations", "", None, "gradient: Adam iterations per start; switch, --pareto: SQP iterations",
                 (1, INF, True, True), absent="gradient 100, switch 30, --pareto 40", integer=True),
        SceneKey("learning_rate", "", d["learning_rate"], "gradient: Adam's learning rate, in the unit cube of the bounds",
                 (0.0, 1.0, False, True)),
        SceneKey("smoothing", "", d["smoothing"], "gradient: σ₀ of the Gaussian smoothing of the objective, in "
                 "the unit cube of the bounds, annealed to 0 (0: none)", (0.0, 0.5, True, True)),
        count("smoothing_pairs", 1, "gradient: antithetic sample pairs per start and iteration when smoothing"),
        SceneKey("switch_margin_mm", "mm", d["switch_margin_mm"], "switch: roll length kept between the flanks' "
                 "first contact and the gear tip (s >= margin)", (0.0, 1.0, True, True)),
        SceneKey("pareto_quantities", "", list(d["pareto_quantities"]), "--pareto: the traded quantities, "
                 "`\"name\"` or `\"name:aggregate\"` (names of `objective`; aggregate `mean` or `max` over the loads, "
                 "default `aggregate`)", allowed="a list of at least two, each name once"),
        SceneKey("pareto_divisions", "", d["pareto_divisions"], "--pareto: divisions H of the weight lattice "
                 "(C(H + Q − 1, Q − 1) scalarisations; 21 for three quantities and H = 5)", (1, 12, True, True),
                 integer=True),
        count("seed", 0, "random seed of the search and of the error samples"),
    ]
    scales = ("m_n",) * 5 + ("b",)
    for i, ((key, _), (low, high), scale) in enumerate(zip(SCENE_KEYS, _MODULE_BOUNDS, scales)):
        keys.append(SceneKey(key, "µm" if key.endswith("_um") else "mm", None,
                             f"bounds `[lower, upper]` of y{i + 1} (`[modification] {key}`)",
                             absent=f"seed 001's: [{low:g}, {high:g}] {scale}",
                             allowed="lower < upper; within the active flank and face width"))
    return tuple(keys)
