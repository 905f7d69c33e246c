"""Loaded tooth contact analysis: compliance models, the contact solver, LTE and stiffness."""

from .analysis import LTCAResult as LTCAResult, loaded_contact_analysis as loaded_contact_analysis
from .compliance import (
    AbstractCompliance as AbstractCompliance,
    AbstractSliceCompliance as AbstractSliceCompliance,
    IsoCompliance as IsoCompliance,
    PointCompliance as PointCompliance,
    SliceCompliance as SliceCompliance,
)
from .model import ContactModel as ContactModel
from .iso import IsoStiffness as IsoStiffness, iso_mesh_stiffness as iso_mesh_stiffness
from .point_analysis import ToothSectionCompliance as ToothSectionCompliance
from .solver import ContactProblem as ContactProblem, ContactSolution as ContactSolution, solve_contact as solve_contact

#: The compliance models a scene file can name (`AbstractCompliance.scene_file`), the
#: default first: a new model is added here, in its own module and in its tests.
COMPLIANCE_MODELS = (SliceCompliance, IsoCompliance, ToothSectionCompliance)


def default_compliance(pair) -> type[AbstractCompliance]:
    """The compliance model a scene takes for `pair` when none is given: the first of
    `COMPLIANCE_MODELS` that models its family (the first of all for a family none models,
    whose loaded scene the checks then refuse)."""
    return next((model for model in COMPLIANCE_MODELS if isinstance(pair, model.families)), COMPLIANCE_MODELS[0])
