"""Unloaded tooth contact analysis (TCA) on the tooth-family interface."""

from ._slice import ContactKind as ContactKind
from .analysis import (
    TCAResult as TCAResult,
    face_slices as face_slices,
    pair_window as pair_window,
    positions as positions,
    tooth_contact_analysis as tooth_contact_analysis,
)
