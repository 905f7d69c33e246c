"""The finer accuracy that the tools check a published figure against."""

import gearjax as gj


def finer(accuracy: gj.Accuracy, face_slices: int, positions_per_pitch: int | None = None) -> gj.Accuracy:
    """`accuracy` with `face_slices` (and optionally `positions_per_pitch`), and 4x its
    contact steps: more slices need more active-set steps (each point that enters or
    leaves the contact is one), and at 161 slices `reference`'s 80 are not enough."""
    return accuracy.replace(face_slices=face_slices, contact_max_steps=4 * accuracy.contact_max_steps,
                            positions_per_pitch=positions_per_pitch or accuracy.positions_per_pitch)
