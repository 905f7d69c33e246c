"""Certification: an optimiser's best designs evaluated again at a finer accuracy.

An optimiser finds the designs where its objective is lowest, and with it the designs
where the objective's discretisation errs most in its favour. So `genetic` and
`gradient_descent` end by evaluating their best candidates (the best design found and the
`top` best distinct designs of the final population, or the starts' best points) at a
certification accuracy (default the `reference` preset) and choose the best by that
value. Where the certification accuracy is the search's own, the certified values are the
search's values (nothing is evaluated again).

The candidates are evaluated in one batch of `top + 1` designs (padded by repetition), so
one compiled program serves every certification of an objective structure.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._validate import check_int
from ..accuracy import PRESETS, Accuracy
from .objective import Objective

#: best candidates certified besides the best design found
CERTIFY_TOP = 5


def accuracy_name(accuracy: Accuracy) -> str:
    """The preset's name, or "custom"."""
    return next((name for name, preset in PRESETS.items() if preset == accuracy), "custom")


def certification_accuracy(certify) -> Accuracy | None:
    """`certify` as an `Accuracy`: a preset name, an `Accuracy`, or None (no
    certification). Raises `ValueError` naming the argument otherwise."""
    if certify is None or isinstance(certify, Accuracy):
        return certify
    if isinstance(certify, str) and certify in PRESETS:
        return PRESETS[certify]
    raise ValueError(f"certify must be an accuracy preset ({', '.join(PRESETS)}), an Accuracy or None; got {certify!r}")


@dataclasses.dataclass(frozen=True)
class Certification:
    """Candidates of a search evaluated at the certification accuracy (host values).

    Attributes:
        accuracy: the certification accuracy (preset name, or "custom").
        designs: the candidates $(y_1, \\dots, y_6)$ (mm), shape (m, 6), best search value first.
        objective: their objective at the search's accuracy (N or mm/s), shape (m,).
        certified: their objective at the certification accuracy, shape (m,).
    """

    accuracy: str
    designs: np.ndarray
    objective: np.ndarray
    certified: np.ndarray

    @property
    def best(self) -> int:
        """Index of the lowest certified value (a non-finite value never wins)."""
        return int(np.argmin(np.where(np.isfinite(self.certified), self.certified, np.inf)))

    def to_dict(self) -> dict:
        return {
            "accuracy": self.accuracy,
            "designs_mm": self.designs.tolist(),
            "objective": self.objective.tolist(),
            "certified": self.certified.tolist(),
        }

    @classmethod
    def from_dict(cls, data: dict) -> Certification:
        return cls(data["accuracy"], np.asarray(data["designs_mm"], float), np.asarray(data["objective"], float),
                   np.asarray(data["certified"], float))


def scene_with_accuracy(scene, accuracy: Accuracy):
    """The scene with another (static) accuracy."""
    return scene if scene.accuracy == accuracy else dataclasses.replace(scene, accuracy=accuracy)


def with_accuracy(objective: Objective, accuracy: Accuracy) -> Objective:
    """The objective with its scene at another (static) accuracy."""
    if objective.scene.accuracy == accuracy:
        return objective
    return eqx.tree_at(lambda o: o.scene, objective, scene_with_accuracy(objective.scene, accuracy))


def certify(objective: Objective, designs, values=None, *, accuracy="reference", top: int = CERTIFY_TOP) -> Certification:
    """Evaluate `designs` (mm, shape (m, 6), m <= top + 1) at the certification `accuracy`
    (a preset name or an `Accuracy`).

    Args:
        objective: the search's objective.
        designs: the candidates (mm).
        values: their objective at the search's accuracy, or None to evaluate it.
        accuracy: the certification accuracy.
        top: the batch is `top + 1` designs (padded), one program per objective structure.
    """
    from .batch import batch_objective_in_chunks

    check_int("certify_top", top, 1)
    target = certification_accuracy(accuracy)
    if target is None:
        raise ValueError("accuracy: certification needs an accuracy (a preset name or an Accuracy)")
    designs = np.atleast_2d(np.asarray(designs, dtype=float))
    if designs.shape[-1] != 6 or not 1 <= designs.shape[0] <= top + 1:
        raise ValueError(f"designs must have shape (m, 6) with 1 <= m <= {top + 1}; got {designs.shape}")

    def evaluate(obj):
        return batch_objective_in_chunks(obj, designs, top + 1)

    values = evaluate(objective) if values is None else np.asarray(values, dtype=float)
    same = objective.scene.accuracy == target
    certified = values.copy() if same else evaluate(with_accuracy(objective, target))
    return Certification(accuracy_name(target), designs, values, certified)


def candidates(units, values, space, top: int) -> tuple[np.ndarray, np.ndarray]:
    """The designs to certify (mm) and their search values, best first: of a method's
    candidates (`SearchMethod.candidates`: unit-cube designs and their values, e.g. the best
    design found and the GA's final population, or the starts' best points), the `top` + 1
    best distinct ones."""
    units, values = np.asarray(units), np.asarray(values)
    order = np.argsort(np.where(np.isfinite(values), values, np.inf), kind="stable")
    chosen: list[int] = []
    for i in order:
        if not any(np.array_equal(units[i], units[j]) for j in chosen):
            chosen.append(int(i))
        if len(chosen) == top + 1:
            break
    return np.asarray(space.to_design(jnp.asarray(units[chosen]))), values[chosen]
