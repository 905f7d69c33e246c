"""Mesh-in impact: first contact under load, impact velocity, local stiffness and force."""

from .analysis import ImpactRegime as ImpactRegime, ImpactResult as ImpactResult, impact_analysis as impact_analysis
from .branches import ImpactBranches as ImpactBranches, impact_branches as impact_branches
from .energy import (
    base_radius_equivalent_mass as base_radius_equivalent_mass,
    equivalent_mass as equivalent_mass,
    gear_inertia as gear_inertia,
    impact_force as impact_force,
)
from .stiffness import LocalStiffness as LocalStiffness, local_stiffness as local_stiffness
