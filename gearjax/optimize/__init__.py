"""Modification optimisation: seed 001's six parameters tuned for a small mesh-in impact.

The pipeline: a `DesignSpace` (bounds, unit-cube coordinates) → an `Objective` (a pure
function of the design vector over a load spectrum and error samples) → an optimiser
(`genetic`, the GA of `gearjax.optimize.ga`; `gradient_descent`, multi-start projected
Adam) that writes every step to a run directory and resumes exactly.
"""

from .ga import GAConfig as GAConfig, GAState as GAState, ga_ask as ga_ask, ga_init as ga_init, ga_tell as ga_tell
from .gradient import (
    GradientConfig as GradientConfig,
    GradientState as GradientState,
    gradient_init as gradient_init,
    gradient_step as gradient_step,
    latin_hypercube as latin_hypercube,
)
from .objective import (
    Evaluation as Evaluation,
    Objective as Objective,
    Penalty as Penalty,
    sample_errors as sample_errors,
)
from .run import OptimizationResult as OptimizationResult, genetic as genetic, gradient_descent as gradient_descent
from .space import (
    PARAMETERS as PARAMETERS,
    DesignSpace as DesignSpace,
    design_dict as design_dict,
    modification_from_design as modification_from_design,
)
from .sensitivity import sensitivities as sensitivities, sensitivity_table as sensitivity_table
from .settings import OptimizeSettings as OptimizeSettings, SettingsError as SettingsError
