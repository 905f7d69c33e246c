r"""The loaded contact problem of one mesh position (Conry & Seireg 1971).

Contact points $i$ (all tooth pairs and slices) have initial separations $e_i$ (mm, normal),
a linear compliance $f_{ij}$ (mm/N), an optional nonlinear contact approach $a_iF_i^{e}$, the
pinion moment arm $p_i = (x_i \times n_i)_z$ (torque per unit normal load, mm) and the gear
arm $q_i$ (normal closure per unit extra lag of the gear, mm/rad). Find loads $F_i \ge 0$ and
the gear's extra lag $\Theta$ with

$$y_i = \sum_j f_{ij}F_j + a_iF_i^{e} + e_i - q_i\Theta \ge 0,\qquad F_iy_i = 0,\qquad
\sum_i p_iF_i = T .$$

For involute pairs $p_i = r_{b1}\cos\beta_b$ and $q_i = r_{b2}\cos\beta_b$, so
$\sum F_i = T/(r_{b1}\cos\beta_b)$ and $q\Theta$ is the rigid approach $Z$ along the normal.
The loaded transmission error is $\mathrm{TE} - \Theta$.

The unknowns are the torque fractions $g_i = p_iF_i/T$ ($\sum g_i = 1$) and $\Theta$, which
keeps zero torque well posed ($F = 0$, $\Theta$ = the smallest rotation closing a gap = 0).
Complementarity is the smoothed Fischer–Burmeister equation
$\phi_\varepsilon(a, b) = a + b - \sqrt{a^2 + b^2 + 2\varepsilon^2} = 0$ on $a_i = ng_i$,
$b_i = y_i/\bar y$ ($\bar y$ = 1 µm), whose solutions have $a_ib_i = \varepsilon^2$: the
smoothing $\varepsilon$ (`Accuracy.contact_smoothing`) bounds the complementarity residual.
Newton (optimistix) with a continuation $\varepsilon$ = 0.1, 0.01, 1e-4 warm-starts the final
solve at the requested $\varepsilon$, which alone carries the implicit-adjoint gradients.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx

from .._custom_types import Array, Float, Scalar
from .._solution import ADJOINT

#: deflection scale of the complementarity equations (mm)
DEFLECTION_SCALE = 1e-3
#: separations of points without a contact are replaced by this (mm): they take no load
NO_CONTACT = 1.0


class ContactProblem(eqx.Module):
    """Data of one position's contact problem (see the module docstring)."""

    compliance: Float[Array, "n n"]
    nonlinear: Float[Array, " n"]
    separation: Float[Array, " n"]
    pinion_arm: Float[Array, " n"]
    gear_arm: Float[Array, " n"]
    torque: Scalar
    exponent: float = eqx.field(static=True, default=1.0)

    def loads(self, fractions):
        return self.torque * fractions / self.pinion_arm

    def gaps(self, fractions, rotation):
        loads = self.loads(fractions)
        y = self.compliance @ loads + self.separation - self.gear_arm * rotation
        if self.exponent != 1.0:
            # smooth positive part keeps Newton iterates with F < 0 finite; the constant is
            # removed so that zero load gives exactly zero approach
            floor = 1e-9 * (1.0 + jnp.abs(self.torque) / jnp.mean(self.pinion_arm))
            positive = soft_positive(loads, floor)
            y = y + self.nonlinear * (positive**self.exponent - (0.5 * floor) ** self.exponent)
        return y


def soft_positive(x, floor):
    """$\\tfrac12(x + \\sqrt{x^2 + f^2})$, written without cancellation for $x < 0$
    ($= \\tfrac12 f^2/(\\sqrt{x^2+f^2} - x)$): positive and smooth for every $x$."""
    root = jnp.sqrt(x * x + floor * floor)
    negative = x < 0
    return jnp.where(negative, 0.5 * floor**2 / jnp.where(negative, root - x, 1.0), 0.5 * (x + root))


def _scale_rotation(problem):
    return DEFLECTION_SCALE / jnp.mean(problem.gear_arm)


def _residual(x, args):
    problem, eps = args
    fractions, rotation = x[:-1], x[-1] * _scale_rotation(problem)
    n = fractions.shape[-1]
    a = n * fractions
    b = problem.gaps(fractions, rotation) / DEFLECTION_SCALE
    fb = a + b - jnp.sqrt(a * a + b * b + 2 * eps**2)
    return jnp.concatenate([fb, (jnp.sum(fractions) - 1.0)[None]])


class ContactSolution(eqx.Module):
    """Solution of one position.

    Attributes:
        loads: normal loads $F_i$ (N).
        gaps: $y_i$ (mm), zero (to the smoothing) where loaded.
        rotation: extra lag $\\Theta$ of the gear (rad): LTE = TE - rotation.
        converged: the final Newton solve converged.
    """

    loads: Float[Array, " n"]
    gaps: Float[Array, " n"]
    rotation: Scalar
    converged: Array


def solve_with(problem: ContactProblem, accuracy) -> ContactSolution:
    """`solve_contact` with the settings of an `Accuracy` (smoothing, tolerances, cap)."""
    return solve_contact(
        problem,
        smoothing=accuracy.contact_smoothing,
        rtol=accuracy.newton_rtol,
        atol=accuracy.newton_atol,
        max_steps=accuracy.contact_max_steps,
    )


def solve_contact(problem: ContactProblem, *, smoothing: float, rtol: float, atol: float, max_steps: int) -> ContactSolution:
    """Solve one position's contact problem (differentiable by the implicit adjoint)."""
    dtype = problem.separation.dtype
    weights = jax.nn.softmax(-(problem.separation - jnp.min(problem.separation)) / DEFLECTION_SCALE)
    gaps0 = problem.gaps(weights, jnp.zeros((), dtype))
    rotation0 = jnp.sum(weights * gaps0 / problem.gear_arm) / _scale_rotation(problem)
    x = jnp.concatenate([weights, rotation0[None]])
    solver = optx.Newton(rtol=rtol, atol=atol)

    def stage(x, eps):
        sol = optx.root_find(
            _residual, solver, x, args=(problem, eps), max_steps=max_steps, throw=False, adjoint=ADJOINT
        )
        return sol.value, None

    stages = jnp.maximum(jnp.asarray([1e-1, 1e-2, 1e-4], dtype=dtype), smoothing)
    x, _ = jax.lax.scan(stage, x, stages)
    x = jax.lax.stop_gradient(x)
    sol = optx.root_find(
        _residual, solver, x, args=(problem, jnp.asarray(smoothing, dtype)), max_steps=max_steps,
        throw=False, adjoint=ADJOINT,
    )
    fractions, rotation = sol.value[:-1], sol.value[-1] * _scale_rotation(problem)
    converged = sol.result == optx.RESULTS.successful
    # Zero torque: no load, and the gear rotates just until the first gap closes (zero: the
    # separations count from the binding contact). Exact in value; the derivative with
    # respect to the torque (the initial compliance) still comes from the smooth solve.
    idle = problem.torque == 0
    exact = jnp.min(problem.separation / problem.gear_arm)
    rotation = rotation + jax.lax.stop_gradient(jnp.where(idle, exact - rotation, 0.0))
    return ContactSolution(
        loads=problem.loads(fractions),
        gaps=problem.gaps(fractions, rotation),
        rotation=rotation,
        converged=converged | idle,
    )
