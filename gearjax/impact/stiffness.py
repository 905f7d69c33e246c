r"""Local stiffness at the first contact point M (seed 001, "local mesh stiffness").

The incoming tooth pair alone is loaded quasi-statically at the configuration of first
contact: its contact points (the face slices of that pair) start with the initial
separations $e_j = q_j(\Delta^* - \Delta_j)$ from M ($\Delta_j$ the slice's touching offset,
$q_j$ the gear arm), and a normal force $F$ pushes the two teeth together by the rigid
approach $\delta$ (mm, along the normal at M):

$$y_j = \sum_l f_{jl}F_l + a_jF_j^{e} + e_j - \delta \ge 0,\quad F_jy_j = 0,\quad
\sum_j F_j = F,$$

with the scene's compliance model ($f$, $a$) and the contact solver of the LTCA (unit arms).
As $F$ grows the contact spreads from M along the contact line, so the curve stiffens.
$\delta(F)$ at `Accuracy.impact_fit_points` forces, geometrically spaced over
`Accuracy.impact_fit_range` times the reference load, is fitted by least squares in
log–log coordinates as $F = K_s\delta^n$.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, Float, Scalar
from .._solution import RESULTS, first_failure
from ..accuracy import Accuracy
from ..ltca.solver import NO_CONTACT, ContactProblem, solve_with


class LocalStiffness(eqx.Module):
    """Power-law fit $F = K_s\\delta^n$ of the incoming pair's force–approach curve.

    Attributes:
        coefficient: $K_s$ (N/mm$^n$).
        exponent: $n$ (-).
        forces: the fitted forces (N).
        approaches: the computed approaches $\\delta$ (mm).
        fit_error: largest relative error of the fit over the fitted forces (-).
        result: `RESULTS.successful`, or `RESULTS.stiffness_fit_failed` where a contact
            solve of the curve did not converge.
    """

    coefficient: Scalar
    exponent: Scalar
    forces: Float[Array, " fit"]
    approaches: Float[Array, " fit"]
    fit_error: Scalar
    result: RESULTS

    def force(self, approach):
        """$F = K_s\\delta^n$ (N) at approach $\\delta$ (mm)."""
        return self.coefficient * approach**self.exponent

    def stiffness(self, approach):
        """Tangent stiffness $\\mathrm dF/\\mathrm d\\delta = nK_s\\delta^{n-1}$ (N/mm)."""
        return self.exponent * self.coefficient * approach ** (self.exponent - 1.0)


def local_stiffness(
    compliance: Float[Array, "n n"],
    nonlinear: Float[Array, " n"],
    exponent: float,
    separation: Float[Array, " n"],
    valid,
    reference_load: Scalar,
    accuracy: Accuracy,
) -> LocalStiffness:
    """Fit $F = K_s\\delta^n$ for one tooth pair's points.

    Args:
        compliance: linear normal compliance of the pair's points (mm/N).
        nonlinear: coefficients of the nonlinear contact approach $aF^{e}$.
        exponent: $e$ of that law (static).
        separation: initial separations from the first contact point (mm).
        valid: points that exist on the flanks.
        reference_load: load scale of the fit (N).
        accuracy: `impact_fit_points`, `impact_fit_range` and the contact solver settings.
    """
    dtype = separation.dtype
    lo, hi = accuracy.impact_fit_range
    fractions = jnp.geomspace(lo, hi, accuracy.impact_fit_points).astype(dtype)
    forces = reference_load * fractions
    ones = jnp.ones_like(separation)
    separation = jnp.where(valid, separation, NO_CONTACT)

    def approach(force):
        problem = ContactProblem(compliance[None], nonlinear[None], separation[None], ones[None], ones[None], force, exponent)
        sol = solve_with(problem, accuracy)
        return sol.rotation, sol.converged

    delta, converged = jax.vmap(approach)(forces)
    return power_law_fit(forces, delta, converged)


def point_local_stiffness(linear: Scalar, hertz: Scalar, reference_load: Scalar, accuracy: Accuracy) -> LocalStiffness:
    """Fit $F = K_s\\delta^n$ for a pair touching at one point (`gearjax.ltca.point_contact`):
    its approach is explicit, $\\delta = cF + hF^{2/3}$, with the linear tooth compliance
    $c$ (mm/N) and the Hertz coefficient $h$ (mm/N$^{2/3}$), so $n$ lies between 1 (the
    teeth's bending dominates) and 3/2 (Hertz alone, $K_s = h^{-3/2}$). Forces as
    `local_stiffness`'s."""
    lo, hi = accuracy.impact_fit_range
    forces = reference_load * jnp.geomspace(lo, hi, accuracy.impact_fit_points).astype(jnp.result_type(hertz))
    delta = linear * forces + hertz * jnp.cbrt(forces) ** 2
    return power_law_fit(forces, delta, jnp.isfinite(delta))


def power_law_fit(forces: Float[Array, " fit"], approaches: Float[Array, " fit"], converged) -> LocalStiffness:
    """Least-squares fit of $\\log F = \\log K_s + n\\log\\delta$ (`LocalStiffness`; failed
    where any entry of `converged` is False)."""
    x, y = jnp.log(approaches), jnp.log(forces)
    xm, ym = jnp.mean(x), jnp.mean(y)
    n = jnp.sum((x - xm) * (y - ym)) / jnp.sum((x - xm) ** 2)
    log_k = ym - n * xm
    fit = jnp.exp(log_k + n * x)
    return LocalStiffness(
        coefficient=jnp.exp(log_k),
        exponent=n,
        forces=forces,
        approaches=approaches,
        fit_error=jnp.max(jnp.abs(fit / forces - 1.0)),
        result=first_failure((~jnp.all(converged), RESULTS.stiffness_fit_failed)),
    )
