"""gearjax: a differentiable gear-contact engine in JAX.

Pipeline: Scene -> geometry -> tca (rigid) -> ltca (elastic) -> impact -> results. Every
stage is a pure function of `equinox.Module` pytrees, so the chain can be `jit`-compiled,
`vmap`-batched and differentiated. gearjax changes no JAX configuration; float64, the
reference precision, needs `jax.config.update("jax_enable_x64", True)` at start-up. With
jaxlib >= 0.12 importing it changes nothing in the process; older jaxlib versions get
their workarounds (environment variables read when JAX's CPU backend starts), see
`gearjax.runtime.versions`.
"""

from .runtime.versions import configure as _configure_runtime

_configure_runtime()

from . import units as units
from ._solution import (
    RESULTS as RESULTS,
    SimulationError as SimulationError,
    enum_message as enum_message,
    enum_name as enum_name,
)
from .accuracy import Accuracy as Accuracy
from .runtime.cache import enable_compilation_cache as enable_compilation_cache
from .runtime.cache import exclude_from_persistent_cache as exclude_from_persistent_cache
from .geometry import (
    AbstractFlankPair as AbstractFlankPair,
    AbstractGearPair as AbstractGearPair,
    AbstractInvolutePair as AbstractInvolutePair,
    CurvilinearGearPair as CurvilinearGearPair,
    DoubleArcGearPair as DoubleArcGearPair,
    DoubleArcZone as DoubleArcZone,
    GBT12759Rack as GBT12759Rack,
    InvoluteGearPair as InvoluteGearPair,
)
from .designs import simulate_designs as simulate_designs
from .geometry.depth import FlankDepth as FlankDepth
from .geometry.errors import MeshErrors as MeshErrors
from .geometry.modification import FlankModification as FlankModification
from .impact import (
    ImpactBranches as ImpactBranches,
    ImpactRegime as ImpactRegime,
    ImpactResult as ImpactResult,
    LocalStiffness as LocalStiffness,
    impact_analysis as impact_analysis,
    impact_branches as impact_branches,
)
from .ltca import (
    AbstractCompliance as AbstractCompliance,
    IsoCompliance as IsoCompliance,
    LTCAResult as LTCAResult,
    SliceCompliance as SliceCompliance,
    ToothSectionCompliance as ToothSectionCompliance,
    loaded_contact_analysis as loaded_contact_analysis,
)
from .pipeline import (
    SimulationResult as SimulationResult,
    simulate as simulate,
)
from .scene import (
    OperatingPoint as OperatingPoint,
    Scene as Scene,
    stack_scenes as stack_scenes,
)
from .sweep import (
    DesignSweep as DesignSweep,
    ImpactSweep as ImpactSweep,
    design_sweep as design_sweep,
    LoadSweep as LoadSweep,
    impact_sweep as impact_sweep,
    load_sweep as load_sweep,
    regime_transition as regime_transition,
)
from .tca import (
    ContactKind as ContactKind,
    TCAResult as TCAResult,
    tooth_contact_analysis as tooth_contact_analysis,
)
from .units import Material as Material

__version__ = "0.1.0"
