"""Loaded tooth contact analysis: compliance models, the contact solver, LTE and stiffness."""

from .analysis import LTCAResult as LTCAResult, loaded_contact_analysis as loaded_contact_analysis
from .compliance import (
    AbstractCompliance as AbstractCompliance,
    IsoCompliance as IsoCompliance,
    PointCompliance as PointCompliance,
    SliceCompliance as SliceCompliance,
)
from .model import ContactModel as ContactModel
from .iso import IsoStiffness as IsoStiffness, iso_mesh_stiffness as iso_mesh_stiffness
from .solver import ContactProblem as ContactProblem, ContactSolution as ContactSolution, solve_contact as solve_contact
