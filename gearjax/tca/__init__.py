"""Unloaded tooth contact analysis (TCA) on the tooth-family interface."""

from ._slice_problem import ContactKind as ContactKind
from .analysis import tooth_contact_analysis as tooth_contact_analysis
from .grid import face_slices as face_slices, pair_window as pair_window, positions as positions
from .result import TCAResult as TCAResult, merge_zones as merge_zones
