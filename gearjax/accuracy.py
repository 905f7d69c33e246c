"""Discretisation and solver settings, in one static object with named presets.

`Accuracy` is hashable configuration (every field static): changing it recompiles, which
is what makes the compiled program contain exactly the resolution asked for. The presets'
errors against `reference` and their cost in time are measured by `benchmarks/accuracy.py`
(README, "What accuracy costs"): at 1.9-3.4 % of the reference's time `default` is within
0.7 % of it on every quantity of an unmodified spur and a curvilinear pair, and on the seed
001 pair's mean LTE, mesh stiffness and load share (0.03-0.2 %), but not on its LTE
peak-to-peak (8 %; limited by the face slices), maximum pressure (2 %; a face-end peak that
grows as the slices narrow) and impact force (1.6 %; the strike velocity's slice
dependence).
"""

from __future__ import annotations

import dataclasses
import re

import equinox as eqx
import jax.numpy as jnp

from ._validate import check_choice, check_int, check_range

TCA_METHODS = ("surface", "plane_of_action")
DTYPES = ("float64", "float32")


def floored_tolerances(rtol: float, atol: float, dtype) -> tuple[float, float]:
    """`(rtol, atol)` floored near the precision of `dtype`: 16 and 64 machine epsilons.

    One rule for every Newton iteration of the engine (surface TCA, contact solver,
    first-contact search): float32 (machine epsilon 1.2e-7) cannot meet 1e-8, and a solve that
    stops short of its tolerance by rounding alone would be reported unconverged (a TCA
    candidate would drop its contact, making the TE jump). In float64 the floors (3.6e-15,
    1.4e-14) lie below every preset's tolerances.
    """
    eps = float(jnp.finfo(dtype).eps)
    return max(float(rtol), 16 * eps), max(float(atol), 64 * eps)


class Accuracy(eqx.Module):
    """How finely and how tightly the engine resolves the contact.

    Attributes:
        positions_per_pitch: pinion positions per angular pitch $2\\pi/z_1$.
        face_slices: transverse slices across the face width (cell midpoints; the two face
            ends are added as edge candidates).
        newton_rtol, newton_atol: Newton tolerances (relative, absolute; parameters in mm,
            angles in rad).
        newton_max_steps: iteration cap; a solve that does not converge marks its candidate
            invalid and is counted in `TCAResult.unconverged` (never silently replaced by its
            start value). Contacts on the active flanks converge in at most 6 steps for the
            seed pair even with reliefs of slope 0.3; the cap stops off-flank tangencies of
            steep reliefs from holding up the whole batch.
        tca_method: "surface" (general TCA on the real flanks, edge contact included) or
            "plane_of_action" (involute families only: contact on the plane of action with
            the separation equal to the sum of both flanks' depths).
        contact_max_steps: cap on the active-set steps of each position's contact solve
            (`gearjax.ltca.solver`); the seed pair settles in a few steps.
        quadrature_points: Gauss–Legendre points of the tooth compliance integrals.
        impact_max_steps: cap on the evaluations of the first-contact search (safeguarded
            Newton in a bracket one grid step wide at the start; each evaluation is TCA and
            LTCA at one pinion angle with their rates). Newton needs 3-5 on the seed pair;
            the cap covers the bisection fallback (a gap with no usable slope, such as
            unloaded perfect flanks), which needs about $\\log_2$(grid step / atol)
            evaluations: 26 for "default", 34 for "reference".
        impact_fit_points: forces at which the local force-approach curve at the impact
            point is computed for the fit $F = K_s\\delta^n$.
        impact_fit_range: (low, high) of those forces as fractions of the reference load
            (the static normal load, at least 10 N per mm of face width). The low end is
            0.1: below it the contact at a face-end corner is shorter than a few face
            slices, so the approach there depends on the slice width (it grows without
            limit as the slices shrink), while the work done below a tenth of the impact
            force is 1-2 % of the impact energy. With (0.02, 1) the seed pair's edge-regime
            impact force moved by 8-9 % between 21 and 161 slices, with (0.1, 1) by 1.1-1.3 %.
        dtype: "float64" (reference; needs `jax.config.update("jax_enable_x64", True)`)
            or "float32".
    """

    positions_per_pitch: int = eqx.field(static=True, default=32)
    face_slices: int = eqx.field(static=True, default=21)
    newton_rtol: float = eqx.field(static=True, default=1e-10)
    newton_atol: float = eqx.field(static=True, default=1e-10)
    newton_max_steps: int = eqx.field(static=True, default=12)
    tca_method: str = eqx.field(static=True, default="surface")
    contact_max_steps: int = eqx.field(static=True, default=40)
    quadrature_points: int = eqx.field(static=True, default=24)
    impact_max_steps: int = eqx.field(static=True, default=40)
    impact_fit_points: int = eqx.field(static=True, default=6)
    impact_fit_range: tuple[float, float] = eqx.field(static=True, default=(0.1, 1.0))
    dtype: str = eqx.field(static=True, default="float64")

    def __check_init__(self):
        check_int("positions_per_pitch", self.positions_per_pitch, 2, 100000)
        check_int("face_slices", self.face_slices, 1, 10000)
        check_range("newton_rtol", self.newton_rtol, 0.0, 1e-2, low_inclusive=False)
        check_range("newton_atol", self.newton_atol, 0.0, 1e-2, low_inclusive=False)
        check_int("newton_max_steps", self.newton_max_steps, 1, 10000)
        check_choice("tca_method", self.tca_method, TCA_METHODS)
        check_int("contact_max_steps", self.contact_max_steps, 1, 10000)
        check_int("quadrature_points", self.quadrature_points, 2, 200)
        check_int("impact_max_steps", self.impact_max_steps, 1, 10000)
        check_int("impact_fit_points", self.impact_fit_points, 2, 1000)
        fit = tuple(self.impact_fit_range)
        if len(fit) != 2 or not (0.0 < fit[0] < fit[1]):
            raise ValueError(f"impact_fit_range must be (low, high) with 0 < low < high; got {self.impact_fit_range!r}")
        object.__setattr__(self, "impact_fit_range", (float(fit[0]), float(fit[1])))
        check_choice("dtype", self.dtype, DTYPES)

    @classmethod
    def preset(cls, name: str) -> "Accuracy":
        """Named presets: "fast", "default", "reference"."""
        check_choice("accuracy preset", name, tuple(PRESETS))
        return PRESETS[name]

    @classmethod
    def from_spec(cls, spec: str, finer: bool = False) -> "Accuracy":
        """`PRESET` or `PRESET@PxS`: the preset with P positions per pitch and S face
        slices (e.g. "default@64x41"), as the study tools take it on their command line;
        with `finer`, the grid through `Accuracy.finer` (a convergence check's setting)."""
        name, at, grid = spec.partition("@")
        accuracy = cls.preset(name)
        if not at:
            return accuracy
        sizes = re.fullmatch(r"([0-9]+)[xX]([0-9]+)", grid)
        if sizes is None:
            raise ValueError(f"accuracy must be PRESET or PRESET@PxS (e.g. default@64x41); got {spec!r}")
        if finer:
            return accuracy.finer(int(sizes[2]), int(sizes[1]))
        return accuracy.replace(positions_per_pitch=int(sizes[1]), face_slices=int(sizes[2]))

    def newton_tolerances(self, dtype) -> tuple[float, float]:
        """`(rtol, atol)`: `newton_rtol`, `newton_atol` floored near the precision of
        `dtype` (`floored_tolerances`)."""
        return floored_tolerances(self.newton_rtol, self.newton_atol, dtype)

    def finer(self, face_slices: int, positions_per_pitch: int | None = None) -> "Accuracy":
        """The setting a published figure is checked against: this accuracy with
        `face_slices` face slices (and `positions_per_pitch` positions, if given) and four
        times its `contact_max_steps`, since every point that enters or leaves the contact
        is one active-set step (at 161 slices `reference`'s 80 are not enough)."""
        return self.replace(face_slices=face_slices, contact_max_steps=4 * self.contact_max_steps,
                            positions_per_pitch=positions_per_pitch or self.positions_per_pitch)

    def replace(self, **changes) -> "Accuracy":
        """A copy with some fields changed (validated)."""
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        unknown = set(changes) - set(fields)
        if unknown:
            raise ValueError(f"unknown Accuracy field(s) {sorted(unknown)}; known: {sorted(fields)}")
        fields.update(changes)
        return Accuracy(**fields)


PRESETS = {
    "fast": Accuracy(
        positions_per_pitch=16, face_slices=9, newton_rtol=1e-8, newton_atol=1e-8, newton_max_steps=8
    ),
    "default": Accuracy(),
    "reference": Accuracy(
        positions_per_pitch=128,
        face_slices=81,
        newton_rtol=1e-13,
        newton_atol=1e-13,
        newton_max_steps=48,
        contact_max_steps=80,
        quadrature_points=48,
    ),
}
