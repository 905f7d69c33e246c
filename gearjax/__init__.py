"""gearjax: a differentiable gear-contact engine in JAX.

Pipeline: Scene -> geometry -> tca (rigid) -> ltca (elastic) -> impact -> results. Every
stage is a pure function of `equinox.Module` pytrees, so the chain can be `jit`-compiled,
`vmap`-batched and differentiated. gearjax changes no JAX configuration; float64, the
reference precision, needs `jax.config.update("jax_enable_x64", True)` at start-up. On
import it appends one XLA CPU flag to `XLA_FLAGS` (unless already set) that avoids a
runtime deadlock of jaxlib's CPU backend, see `gearjax._runtime`.
"""

from ._runtime import configure_xla_flags as _configure_xla_flags

_configure_xla_flags()

from . import units as units
from .accuracy import Accuracy as Accuracy
from .geometry import (
    AbstractGearPair as AbstractGearPair,
    CurvilinearGearPair as CurvilinearGearPair,
    InvoluteGearPair as InvoluteGearPair,
)
from .geometry.depth import FlankDepth as FlankDepth
from .geometry.errors import MeshErrors as MeshErrors
from .geometry.modification import (
    FlankModification as FlankModification,
)
from .scene import (
    OperatingPoint as OperatingPoint,
    Scene as Scene,
    SimulationResult as SimulationResult,
    simulate as simulate,
    stack_scenes as stack_scenes,
)
from .tca import TCAResult as TCAResult, tooth_contact_analysis as tooth_contact_analysis
from .units import Material as Material

__version__ = "0.1.0"
