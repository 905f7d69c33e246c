"""The search methods of `gearjax.optimize`, each a class in one place, and their registry.

A `SearchMethod` says everything the run driver (`gearjax.optimize.run.minimize`), the
certification, the `[optimize]` section and the command line need to know about a method:
its state, one step (one compiled call of the objective's batch program), its best design,
the candidates it hands to certification, when it has finished and whether it converged.
A method is added by writing such a class and decorating it with `register`: `gearjax
optimize --method NAME`, `[optimize] method = "NAME"` and the run directory then know it.

    @register
    class RandomSearch(SearchMethod):
        name = "random"
        ...

The built-in methods are `GeneticSearch` (`"ga"`, `gearjax.optimize.ga`), `CMASearch`
(`"cma_es"`, `gearjax.optimize.cma`), `GradientSearch`
(`"gradient"`, multi-start projected Adam, `gearjax.optimize.gradient`) and `SwitchSearch`
(`"switch"`, a trust-region SQP on the flank branch of the mesh-in regime switch,
`gearjax.optimize.switch`).
"""

from __future__ import annotations

import abc
import dataclasses
from typing import Any, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .batch import batch_objective, batch_value_and_grad
from .cma import CMAConfig, cma_ask, cma_init, cma_tell
from .ga import GAConfig, ga_ask, ga_init, ga_tell
from .gradient import GradientConfig, gradient_init, gradient_step, sample_positions, smoothed
from .objective import Objective
from .space import DesignSpace
from .switch import SwitchConfig, switch_init, switch_update, switch_values

#: the registered methods by name (`register`)
METHODS: dict[str, type[SearchMethod]] = {}


def register(cls: type[SearchMethod]) -> type[SearchMethod]:
    """Class decorator: make `cls` a method of `gearjax.optimize` under `cls.name`."""
    if not (isinstance(cls, type) and issubclass(cls, SearchMethod)):
        raise ValueError(f"register needs a SearchMethod subclass; got {cls!r}")
    if not isinstance(getattr(cls, "name", None), str) or not cls.name:
        raise ValueError(f"{cls.__name__}.name must be a non-empty string")
    if cls.name in METHODS and METHODS[cls.name] is not cls:
        raise ValueError(f"a method named {cls.name!r} is registered already ({METHODS[cls.name].__name__})")
    METHODS[cls.name] = cls
    return cls


@dataclasses.dataclass(frozen=True)
class SearchMethod(abc.ABC):
    """A search method with its settings (`config`).

    Class attributes: `name` (registry key, stored in `run.json`), `step_name` (what one
    step is called in progress lines), `program` (the run's one big compilation, named in
    progress lines) and `uses_gradients` (its evaluations compute the gradient too).

    The state is a pytree of arrays (saved in `state.npz` after every step, so a run
    resumes exactly); unit-cube coordinates are those of the `DesignSpace`.
    """

    config: Any

    name: ClassVar[str]
    step_name: ClassVar[str] = "iteration"
    program: ClassVar[str] = "the objective's batch program"
    uses_gradients: ClassVar[bool] = False

    @classmethod
    @abc.abstractmethod
    def from_settings(cls, settings) -> SearchMethod:
        """The method as an `[optimize]` section (`OptimizeSettings`) sets it up."""

    @property
    @abc.abstractmethod
    def steps(self) -> int:
        """The cap on steps (generations, iterations)."""

    @property
    @abc.abstractmethod
    def batch(self) -> int:
        """Designs evaluated per step (the objective's batch shape)."""

    @abc.abstractmethod
    def init(self, key, starts, dtype):
        """The first state from a random key and the starts (unit cube, (m, 6), or None)."""

    @abc.abstractmethod
    def step(self, objective: Objective, space: DesignSpace, state):
        """One step: `(state, designs (mm), values)` of the designs it evaluated."""

    @abc.abstractmethod
    def best(self, state) -> tuple[Any, Any]:
        """The best value so far and its design in the unit cube."""

    @abc.abstractmethod
    def candidates(self, state) -> tuple[np.ndarray, np.ndarray]:
        """Designs (unit cube) and their values that certification may choose from."""

    def initial_objective(self, objective: Objective, space: DesignSpace, design) -> float:
        """$J$ of the scene's own design through the batch program the run compiles anyway
        (a batch of copies of it: a few evaluations instead of another compilation)."""
        tiled = jnp.broadcast_to(jnp.asarray(design, objective.torques.dtype), (self.batch, 6))
        if self.uses_gradients:
            return float(batch_value_and_grad(objective, space, space.to_unit(tiled))[0][0])
        return float(batch_objective(objective, tiled)[0])

    def finished(self, state) -> bool:
        """The search stops before its cap (default: never)."""
        del state
        return False

    def converged(self, state, history: list[float]) -> bool:
        """The search met its own criterion (default: the best value did not change over the
        last quarter of at least four steps)."""
        del state
        tail = history[-max(2, len(history) // 4):]
        return len(history) >= 4 and tail[0] == tail[-1]


# ------------------------------------------------------------------- compiled small steps
# The optimisers' own steps are small programs of their own (`batch` holds the objective's).
_ga_ask = eqx.filter_jit(ga_ask)
_ga_tell = eqx.filter_jit(ga_tell)
_cma_ask = eqx.filter_jit(cma_ask)
_cma_tell = eqx.filter_jit(cma_tell)
_gradient_step = eqx.filter_jit(lambda state, values, grads, config: gradient_step(state, *smoothed(values, grads), config))
_sample_positions = eqx.filter_jit(sample_positions)
_switch_update = eqx.filter_jit(switch_update)


def _in_dtype(state, dtype):
    return jax.tree_util.tree_map(lambda x: x.astype(dtype) if jnp.issubdtype(x.dtype, jnp.floating) else x, state)


@register
@dataclasses.dataclass(frozen=True)
class GeneticSearch(SearchMethod):
    """The genetic algorithm (`gearjax.optimize.ga`): a generation per step, the whole
    population in one call; `generations` steps."""

    config: GAConfig = dataclasses.field(default_factory=GAConfig)
    generations: int = 30

    name: ClassVar[str] = "ga"
    step_name: ClassVar[str] = "generation"
    program: ClassVar[str] = "the GA's batch program"

    @classmethod
    def from_settings(cls, settings) -> GeneticSearch:
        return cls(settings.ga_config(), settings.generations or 30)

    @property
    def steps(self) -> int:
        return self.generations

    @property
    def batch(self) -> int:
        return self.config.population

    def init(self, key, starts, dtype):
        return _in_dtype(ga_init(key, self.config, 6, starts), dtype)

    def ask(self, state):
        """The generation's candidates in the unit cube, and the state that drew them."""
        return _ga_ask(state, self.config)

    def tell(self, state, unit, values):
        """The state updated with the candidates' objective values."""
        return _ga_tell(state, unit, values, self.config)

    def step(self, objective, space, state):
        unit, state = self.ask(state)
        designs = space.to_design(unit)
        values = batch_objective(objective, designs)
        return self.tell(state, unit, values), designs, values

    def best(self, state):
        return state.best_fitness, state.best

    def candidates(self, state):
        units = np.concatenate([np.asarray(state.best)[None], np.asarray(state.population)])
        values = np.concatenate([np.asarray(state.best_fitness)[None], np.asarray(state.fitness)])
        return units, values


@register
@dataclasses.dataclass(frozen=True)
class CMASearch(GeneticSearch):
    """CMA-ES (`gearjax.optimize.cma`): a generation per step, its `config.population`
    candidates in one call; `generations` steps. Its candidates for certification are the
    best design found and the last generation."""

    config: CMAConfig = dataclasses.field(default_factory=CMAConfig)
    generations: int = 120

    name: ClassVar[str] = "cma_es"
    program: ClassVar[str] = "CMA-ES's batch program"

    @classmethod
    def from_settings(cls, settings) -> CMASearch:
        return cls(settings.cma_config(), settings.generations or 120)

    def init(self, key, starts, dtype):
        return _in_dtype(cma_init(key, self.config, 6, starts), dtype)

    def ask(self, state):
        return _cma_ask(state, self.config)

    def tell(self, state, unit, values):
        return _cma_tell(state, unit, values, self.config)


class _MultiStart(SearchMethod):
    """A method whose state holds each start's best point and value (`best`, `best_value`);
    the starts' best points are its candidates."""

    def best(self, state):
        i = int(np.argmin(np.asarray(state.best_value)))
        return state.best_value[i], state.best[i]

    def candidates(self, state):
        return np.asarray(state.best), np.asarray(state.best_value)


@register
@dataclasses.dataclass(frozen=True)
class GradientSearch(_MultiStart):
    """Multi-start projected Adam (`gearjax.optimize.gradient`; with `config.smoothing`, on
    the Gaussian-smoothed objective): all starts and their samples in one call per
    iteration; `config.iterations` caps the iterations."""

    config: GradientConfig = dataclasses.field(default_factory=GradientConfig)

    name: ClassVar[str] = "gradient"
    program: ClassVar[str] = "the value-and-gradient program"
    uses_gradients: ClassVar[bool] = True

    @classmethod
    def from_settings(cls, settings) -> GradientSearch:
        return cls(settings.gradient_config())

    @property
    def steps(self) -> int:
        return self.config.iterations

    @property
    def batch(self) -> int:
        return self.config.starts * self.config.samples

    def init(self, key, starts, dtype):
        return _in_dtype(gradient_init(key, self.config, 6, starts), dtype)

    def step(self, objective, space, state):
        points = _sample_positions(state, self.config)  # (starts, samples, 6)
        unit = points.reshape(-1, points.shape[-1])
        values, grads = batch_value_and_grad(objective, space, unit)
        state = _gradient_step(state, values.reshape(points.shape[:2]), grads.reshape(points.shape), self.config)
        return state, space.to_design(unit), values


    def finished(self, state) -> bool:
        return not bool(np.any(np.asarray(state.active)))

    def converged(self, state, history) -> bool:
        """Every start stopped by its criterion before the cap."""
        return self.finished(state)


@register
@dataclasses.dataclass(frozen=True)
class SwitchSearch(_MultiStart):
    """The switching-aware SQP (`gearjax.optimize.switch`): min $J_\\text{flank}$ subject to
    every load's switching function $s \\ge$ `config.margin`, from `config.starts` slots that
    start again once converged; each iteration one call of the flank branch's value and
    Jacobian (`switch_values`). For the impact force or velocity as the objective."""

    config: SwitchConfig = dataclasses.field(default_factory=SwitchConfig)

    name: ClassVar[str] = "switch"
    program: ClassVar[str] = "the flank branch's value-and-Jacobian program"
    uses_gradients: ClassVar[bool] = True

    @classmethod
    def from_settings(cls, settings) -> SwitchSearch:
        if settings.objective not in ("force", "velocity"):
            raise ValueError(f"[optimize] method = \"switch\" minimises the impact (objective \"force\" or "
                             f"\"velocity\"); got objective = {settings.objective!r}")
        return cls(settings.switch_config())

    @property
    def steps(self) -> int:
        return self.config.iterations

    @property
    def batch(self) -> int:
        return self.config.starts

    def init(self, key, starts, dtype):
        # the constraints' count is the objective's loads x samples: fixed at the first step
        return switch_init(key, self.config, 0, starts, dtype)

    def step(self, objective, space, state):
        if objective.quantity not in ("force", "velocity"):
            raise ValueError(f"the switch method minimises the impact force or velocity; the objective's quantity "
                             f"is {objective.quantity!r}")
        constraints = int(objective.torques.shape[0]) * objective.samples
        if state.c.shape[-1] != constraints:  # the first step: one switching function per load and sample
            state = eqx.tree_at(lambda s: (s.c, s.a, s.multipliers), state,
                                (jnp.zeros(state.c.shape[:1] + (constraints,), state.c.dtype),
                                 jnp.zeros(state.a.shape[:1] + (constraints, 6), state.a.dtype),
                                 jnp.zeros(state.c.shape[:1] + (constraints,), state.c.dtype)))
        units = state.trial
        values = switch_values(objective, space, units)
        J, _, s, _ = values
        state = _switch_update(state, values, self.config)
        # where J_flank is the objective itself (the flank branch's contact can stop at the
        # gear tip, s = 0, where the edge strikes first: only s >= margin counts)
        on_flank = np.all(np.asarray(s) >= self.config.margin - self.config.feasibility, axis=-1)
        return state, space.to_design(units), np.where(on_flank, np.asarray(J), np.nan)

    def initial_objective(self, objective, space, design) -> float:
        """$J$ of the scene's own design: $J_\\text{flank}$ where it lies on the flank side
        (s >= margin) at every load, else the objective's own batch program (one more
        compilation)."""
        unit = jnp.broadcast_to(space.to_unit(jnp.asarray(design, objective.torques.dtype)), (self.batch, 6))
        J, _, s, _ = switch_values(objective, space, unit)
        if bool(np.all(np.asarray(s[0]) >= self.config.margin - self.config.feasibility)):
            return float(J[0])
        return float(batch_objective(objective, jnp.broadcast_to(jnp.asarray(design, objective.torques.dtype),
                                                                 (self.batch, 6)))[0])

