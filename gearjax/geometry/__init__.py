"""Tooth families (one module each) and flank modifications."""

from ._base import AbstractGearPair as AbstractGearPair
from .involute import InvoluteGearPair as InvoluteGearPair
from .curvilinear import CurvilinearGearPair as CurvilinearGearPair
