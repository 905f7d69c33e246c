"""Modification optimisation: seed 001's six parameters tuned for a small mesh-in impact.

The pipeline: a `DesignSpace` (bounds, unit-cube coordinates) → an `Objective` (a pure
function of the design vector over a load spectrum and error samples) → an optimiser
(`minimize` with a registered `SearchMethod` of `gearjax.optimize.methods`: `genetic`, the
GA of `gearjax.optimize.ga`; `CMASearch`, CMA-ES of `gearjax.optimize.cma`; `gradient_descent`, multi-start projected Adam; `SwitchSearch`,
an SQP on the flank branch of the mesh-in regime switch) that writes
every step to a run directory and resumes exactly → a certification of
its best designs at a finer accuracy (`certify`), which picks the result. `pareto_front`
trades several quantities (impact force, loaded TE, contact pressure, ...) over the duty
cycle: many scalarisations solved together by the same SQP, the front certified.
"""

from .certification import Certification as Certification
from .certification import certify as certify
from .cma import CMAConfig as CMAConfig
from .cma import CMAState as CMAState
from .cma import cma_ask as cma_ask
from .cma import cma_init as cma_init
from .cma import cma_tell as cma_tell
from .ga import GAConfig as GAConfig
from .ga import GAState as GAState
from .ga import ga_ask as ga_ask
from .ga import ga_init as ga_init
from .ga import ga_tell as ga_tell
from .gradient import (
    GradientConfig as GradientConfig,
)
from .gradient import (
    GradientState as GradientState,
)
from .gradient import (
    gradient_init as gradient_init,
)
from .gradient import (
    gradient_step as gradient_step,
)
from .gradient import (
    latin_hypercube as latin_hypercube,
)
from .gradient import (
    sample_positions as sample_positions,
)
from .gradient import (
    smoothed as smoothed,
)
from .objective import (
    Evaluation as Evaluation,
)
from .objective import (
    Objective as Objective,
)
from .objective import (
    Penalty as Penalty,
)
from .objective import (
    sample_errors as sample_errors,
)
from .methods import METHODS as METHODS
from .methods import CMASearch as CMASearch
from .methods import GeneticSearch as GeneticSearch
from .methods import GradientSearch as GradientSearch
from .methods import SearchMethod as SearchMethod
from .methods import SwitchSearch as SwitchSearch
from .methods import register as register
from .pareto import ParetoConfig as ParetoConfig
from .pareto import ParetoState as ParetoState
from .pareto_run import ParetoResult as ParetoResult
from .pareto_run import pareto_front as pareto_front
from .run import OptimizationResult as OptimizationResult
from .run import genetic as genetic
from .run import gradient_descent as gradient_descent
from .run import minimize as minimize
from .sensitivity import sensitivities as sensitivities
from .sensitivity import sensitivity_table as sensitivity_table
from .settings import OptimizeSettings as OptimizeSettings
from .settings import SettingsError as SettingsError
from .switch import SwitchConfig as SwitchConfig
from .switch import SwitchState as SwitchState
from .space import (
    PARAMETERS as PARAMETERS,
)
from .space import (
    DesignSpace as DesignSpace,
)
from .space import (
    design_dict as design_dict,
)
from .space import (
    modification_from_design as modification_from_design,
)
