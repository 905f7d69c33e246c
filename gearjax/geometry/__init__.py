"""Tooth families (one module each) and flank modifications."""

from ._base import AbstractFlankPair as AbstractFlankPair, AbstractGearPair as AbstractGearPair, SceneFileSpec as SceneFileSpec
from .curvilinear import CurvilinearGearPair as CurvilinearGearPair
from .double_arc import DoubleArcGearPair as DoubleArcGearPair
from .double_arc_zone import DoubleArcZone as DoubleArcZone
from .double_arc_rack import GBT12759Rack as GBT12759Rack
from .involute import InvoluteGearPair as InvoluteGearPair
from .involute_section import AbstractInvolutePair as AbstractInvolutePair

#: The families a scene file can name (`AbstractGearPair.scene_file`), in the order its
#: messages list them: a new family is added here, in its own module and in its tests.
FAMILIES = (InvoluteGearPair, CurvilinearGearPair, DoubleArcGearPair)
