r"""The loaded contact problem of one mesh position (Conry & Seireg 1971), solved exactly.

Contact points $i$ (tooth pair $k$, face slice $j$) have initial separations $e_i$ (mm,
normal), a linear compliance $f_{ij}$ (mm/N), an optional nonlinear contact approach
$a_iF_i^{e}$, the pinion moment arm $p_i = (x_i \times n_i)_z$ (torque per unit normal
load, mm) and the gear arm $q_i$ (normal closure per unit extra lag of the gear, mm/rad).
Find loads $F_i \ge 0$ and the gear's extra lag $\Theta$ with

$$y_i = \sum_j f_{ij}F_j + a_iF_i^{e} + e_i - q_i\Theta \ge 0,\qquad F_iy_i = 0,\qquad
\sum_i p_iF_i = T .$$

For involute pairs $p_i = r_{b1}\cos\beta_b$ and $q_i = r_{b2}\cos\beta_b$, so
$\sum F_i = T/(r_{b1}\cos\beta_b)$ and $q\Theta$ is the rigid approach $Z$ along the normal.
The loaded transmission error is $\mathrm{TE} - \Theta$.

**Structure.** Different tooth pairs touch only through the gear's rotation $\Theta$: the
compliance is block diagonal over pairs, $f = \mathrm{diag}(C_1, \dots, C_K)$, each block
(slices × slices) a tooth pair's face. Two solvers use it:

* *Diagonal linear model* (`IsoCompliance`; uncoupled slices with a linear contact law):
  for a given $\Theta$ every point is independent, $F_i = \max(0, (q_i\Theta - e_i)/c_i)$,
  and the torque $G(\Theta) = \sum_i p_iF_i(\Theta)$ is increasing and piecewise linear with
  breakpoints $t_i = e_i/q_i$. Sorting the breakpoints, on $[t_{(k)}, t_{(k+1)}]$ the points
  $(1) \dots (k)$ carry load and $G = S_k\Theta - I_k$ with the cumulative sums
  $S_k = \sum_{m\le k} p_{(m)}q_{(m)}/c_{(m)}$, $I_k = \sum_{m\le k} p_{(m)}e_{(m)}/c_{(m)}$;
  the solution is $\Theta = (T + I_k)/S_k$ on the first segment that contains it (strictly:
  at a breakpoint, the segment to its right, so derivatives are the right-hand ones, e.g.
  the tangent stiffness of loading from zero torque). Exact, one sort per position,
  differentiable to every order through the selected segment.
* *Coupled model* (`SliceCompliance`): a primal–dual active-set method (semi-smooth Newton
  on $\min(F_i, \kappa y_i) = 0$; Hintermüller, Ito & Kunisch, SIAM J. Optim. 13 (2002) 865)
  with $\Theta$ outside the blocks. Given the active set $\mathcal A$ (points in contact)
  and the linearisation of the contact law at the current loads
  ($a F^{e} \approx a F_0^{e} + D(F - F_0)$), each block solves
  $(C_k + D_k)_{\mathcal{AA}}F_{\mathcal A} = q_{\mathcal A}\Theta - r_{\mathcal A}$, i.e.
  $F = u + \Theta w$ from one Cholesky factorisation with two right-hand sides (the
  blocks are symmetric positive definite; with identity rows for the inactive points, so
  is the masked matrix), and the torque
  balance gives $\Theta = (T - p\cdot u)/(p\cdot w)$. The new active set is
  $\{F_i - \kappa y_i > 0\}$ ($\kappa$ the mean point stiffness), always holding the point
  with the largest $F_i - \kappa y_i$ so that zero torque is solved too ($F = 0$, $\Theta$ =
  the smallest rotation that closes a gap). It starts from the diagonal model's exact
  solution with the blocks' diagonals, and stops when the active set repeats and the loads
  change by less than the Newton tolerances (linear laws: when the set repeats, which is
  exact). Cost per step: $K$ factorisations of a slices × slices block instead of one of
  all $K\cdot$slices points.

**Derivatives.** The active set is discrete; on it the solution is a smooth function of the
data. The iteration runs without derivatives, and its converged value is passed through one
step $N$ of the same Newton map with the active set fixed, whose derivative with respect
to the data at the root, $\partial N/\partial\theta = -J^{-1}\partial r/\partial\theta$, is
the implicit-function derivative (`jax.custom_jvp`; the rule is itself differentiable, so
second derivatives — used by the impact's velocity gradients — are exact as well). Where
the active set switches, derivatives are one-sided.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg

from .._custom_types import Array, Bool, Float, Scalar
from .._numerics import safe_divide
from ..accuracy import floored_tolerances

#: separations of points without a contact are replaced by this (mm): they take no load
NO_CONTACT = 1.0

#: a damped Newton step of a nonlinear contact law keeps at least this fraction of each
#: loaded point's load (`_fraction_to_boundary`)
KEEP = 0.1


class ContactProblem(eqx.Module):
    """Data of one position's contact problem (see the module docstring). Axes: tooth pair
    (block), slice.

    Attributes:
        compliance: linear compliance blocks $C_k$ (mm/N), shape (pair, slice, slice).
        nonlinear: coefficients $a_i$ of the approach $a_iF_i^{e}$ (mm/N^e).
        separation: initial separations $e_i$ (mm).
        pinion_arm, gear_arm: $p_i$, $q_i$ (mm; $q_i > 0$).
        torque: pinion torque $T$ (N·mm).
        exponent: $e$ (static; 1 for a linear law, whose `nonlinear` is ignored).
        diagonal: the blocks are diagonal (static): the exact 1-D solver applies when the
            law is linear.
    """

    compliance: Float[Array, "pair s s"]
    nonlinear: Float[Array, "pair s"]
    separation: Float[Array, "pair s"]
    pinion_arm: Float[Array, "pair s"]
    gear_arm: Float[Array, "pair s"]
    torque: Scalar
    exponent: float = eqx.field(static=True, default=1.0)
    diagonal: bool = eqx.field(static=True, default=False)

    @property
    def _floor(self):
        # smooth positive part keeps loads near zero finite in the Palmgren law's derivative;
        # the constant is removed so that zero load gives exactly zero approach
        return 1e-9 * (1.0 + jnp.abs(self.torque) / jnp.mean(self.pinion_arm))

    def approach(self, loads):
        """Nonlinear contact approach $a(F_+^{e} - (f/2)^e)$ (mm) and its derivative
        $\\mathrm dF$ (mm/N), with $F_+$ = `soft_positive`$(F, f)$."""
        if self.exponent == 1.0:
            zero = jnp.zeros_like(loads)
            return zero, zero
        floor = self._floor
        positive = soft_positive(loads, floor)
        slope = 0.5 * (1.0 + loads / jnp.sqrt(loads * loads + floor * floor))
        value = self.nonlinear * (positive**self.exponent - (0.5 * floor) ** self.exponent)
        return value, self.nonlinear * self.exponent * positive ** (self.exponent - 1.0) * slope

    def gaps(self, loads, rotation):
        """$y_i$ (mm) for loads $F$ (pair, slice) and the gear's extra lag $\\Theta$ (rad)."""
        linear = jnp.einsum("kij,kj->ki", self.compliance, loads)
        return linear + self.approach(loads)[0] + self.separation - self.gear_arm * rotation


def soft_positive(x, floor):
    """$\\tfrac12(x + \\sqrt{x^2 + f^2})$, written without cancellation for $x < 0$
    ($= \\tfrac12 f^2/(\\sqrt{x^2+f^2} - x)$): positive and smooth for every $x$."""
    root = jnp.sqrt(x * x + floor * floor)
    negative = x < 0
    return jnp.where(negative, 0.5 * floor**2 / jnp.where(negative, root - x, 1.0), 0.5 * (x + root))


class ContactSolution(eqx.Module):
    """Solution of one position.

    Attributes:
        loads: normal loads $F_i$ (N), (pair, slice).
        gaps: $y_i$ (mm), zero where loaded.
        rotation: extra lag $\\Theta$ of the gear (rad): LTE = TE - rotation.
        converged: the active set settled (and, for a nonlinear law, Newton converged)
            within the step cap.
        steps: active-set steps taken (0 for the diagonal solver).
    """

    loads: Float[Array, "pair s"]
    gaps: Float[Array, "pair s"]
    rotation: Scalar
    converged: Bool[Array, ""]
    steps: Array


def solve_with(problem: ContactProblem, accuracy) -> ContactSolution:
    """`solve_contact` with the settings of an `Accuracy` (tolerances, step cap)."""
    return solve_contact(
        problem, rtol=accuracy.newton_rtol, atol=accuracy.newton_atol, max_steps=accuracy.contact_max_steps
    )


def _diagonal_solution(problem: ContactProblem, point_compliance):
    """Exact solution of the diagonal linear problem with the point compliances $c_i$
    `point_compliance` (pair, slice): returns $(F, \\Theta)$ (see the module docstring)."""
    c0 = point_compliance
    c = c0.reshape(-1)
    e = problem.separation.reshape(-1)
    p = problem.pinion_arm.reshape(-1)
    q = problem.gear_arm.reshape(-1)
    order = jnp.argsort(jax.lax.stop_gradient(e / q))
    c, e, p, q = c[order], e[order], p[order], q[order]
    slope = jnp.cumsum(p * q / c)
    intercept = jnp.cumsum(p * e / c)
    theta = (problem.torque + intercept) / slope
    following = jnp.concatenate([(e / q)[1:], jnp.full((1,), jnp.inf, e.dtype)])
    # strictly inside: at a breakpoint (zero torque on equal separations, say) the segment
    # to its right, so that derivatives are the right-hand ones (loading from that state)
    segment = jnp.argmax(jax.lax.stop_gradient(theta) < jax.lax.stop_gradient(following))
    rotation = theta[segment]
    loads = jnp.maximum((problem.gear_arm * rotation - problem.separation) / c0, 0.0)
    return loads, rotation


def _newton_map(problem: ContactProblem, loads, rotation, active):
    """One step of the active-set Newton method with the active set `active` fixed: the
    loads and rotation that solve the problem linearised at `loads` (module docstring).
    `rotation` is not used: $\\Theta$ is eliminated through the torque balance."""
    del rotation
    value, slope = problem.approach(loads)
    matrix = problem.compliance + jax.vmap(jnp.diag)(slope)
    a = active.astype(loads.dtype)
    eye = jnp.eye(loads.shape[-1], dtype=loads.dtype)
    masked = a[:, :, None] * a[:, None, :] * matrix + (1.0 - a)[:, :, None] * eye
    residual = slope * loads - value - problem.separation
    rhs = jnp.stack([a * residual, a * problem.gear_arm], axis=-1)
    # the compliance blocks are symmetric positive definite, and so is `masked`
    solved = jax.scipy.linalg.cho_solve((jnp.linalg.cholesky(masked), True), rhs)
    u, w = solved[..., 0], solved[..., 1]
    rotation = (problem.torque - jnp.sum(problem.pinion_arm * u)) / jnp.sum(problem.pinion_arm * w)
    return u + rotation * w, rotation


def _active_set(problem: ContactProblem, loads, rotation, stiffness):
    """$\\{F_i - \\kappa y_i > 0\\}$, always with the point of the largest value."""
    score = loads - stiffness * problem.gaps(loads, rotation)
    return (score > 0) | (score == jnp.max(score))


def _fraction_to_boundary(loads, new_loads):
    """Step length $\\lambda \\in (0, 1]$ that lets no loaded point lose more than
    `1 - KEEP` of its load: $\\lambda = \\min_i (1 - \\theta)F_i/(F_i - F_i^N)$ over the points
    with $F_i > 0$ and Newton load $F_i^N < \\theta F_i$, $\\theta$ = `KEEP` (the
    fraction-to-the-boundary rule of interior-point methods; Nocedal & Wright, Numerical
    Optimization, 2nd ed., 2006).

    Palmgren's law $aF^{0.9}$ is concave, so a full Newton step from above a point's root
    overshoots, possibly below zero, where the smoothed law is flat: from there the next
    step returns to the same point above the root, and the iteration cycles with the active
    set fixed (seed 001's pair at 81 slices, 1000 N·m, one position; the loads of
    one point alternated between 48.3 and -1.26 N). The damped steps keep the loads
    positive, where the law's linearisation is not flat. Used only for steps that keep the
    active set: a step that changes it is taken in full, so a point leaving contact is
    dropped at once."""
    cut = (loads > 0) & (new_loads < KEEP * loads)
    ratio = (1.0 - KEEP) * loads / jnp.where(cut, loads - new_loads, 1.0)
    return jnp.min(jnp.where(cut, ratio, 1.0))


@eqx.filter_custom_jvp
def _implicit(problem: ContactProblem, loads, rotation, active):
    """Identity in value on the converged `(loads, rotation)`; derivatives by the implicit
    function theorem through one Newton step (module docstring)."""
    return loads, rotation


@_implicit.def_jvp
def _implicit_jvp(primals, tangents):
    problem, loads, rotation, active = primals
    t_problem = tangents[0]
    out = _implicit(problem, loads, rotation, active)
    _, t_out = eqx.filter_jvp(lambda pr: _newton_map(pr, out[0], out[1], active), (problem,), (t_problem,))
    return out, t_out


def _exact_when_idle(problem: ContactProblem, loads, rotation):
    """At zero torque: no load and the gear rotated just until the first gap closes,
    exactly in value (equal separations would otherwise share zero load as round-off of
    either sign); derivatives are kept (the tangent compliance of loading from rest)."""
    idle = problem.torque == 0
    exact = jnp.min(problem.separation / problem.gear_arm)
    loads = loads - jax.lax.stop_gradient(jnp.where(idle, loads, 0.0))
    rotation = rotation + jax.lax.stop_gradient(jnp.where(idle, exact - rotation, 0.0))
    return loads, rotation


class WarmStart(eqx.Module):
    """A start for `solve_contact` from the solution at another torque (a load sweep's
    previous load): its loads (N), lag (rad), active set and torque (N·mm)."""

    loads: Float[Array, "pair s"]
    rotation: Scalar
    active: Bool[Array, "pair s"]
    torque: Scalar


def solve_contact(problem: ContactProblem, *, rtol: float, atol: float, max_steps: int,
                  start: WarmStart | None = None) -> ContactSolution:
    """Solve one position's contact problem exactly (module docstring).

    Args:
        problem: the position's data.
        rtol, atol: tolerances on the change of the loads between Newton steps, relative to
            the largest load and in units of it (nonlinear laws only; floored near the
            dtype's precision, `floored_tolerances`).
        max_steps: cap on the active-set steps.
        start: optional warm start (`WarmStart`, no derivatives flow through it): the active
            iteration starts from its active set, with its loads scaled by the ratio of the
            torques, instead of from the diagonal model (where its torque is zero, from the
            diagonal model). The solution is the same, to the tolerances: the problem's
            solution is unique; only the number of steps changes (`solve_over_loads`).
    """
    return _solve(problem, rtol, atol, max_steps, start)[0]


def _solve(problem: ContactProblem, rtol, atol, max_steps, start):
    """`(solution, active set)` of `solve_contact`."""
    dtype = problem.separation.dtype
    if problem.diagonal and problem.exponent == 1.0:
        compliance = jnp.diagonal(problem.compliance, axis1=-2, axis2=-1)
        loads, rotation = _exact_when_idle(problem, *_diagonal_solution(problem, compliance))
        solution = ContactSolution(
            loads=loads, gaps=problem.gaps(loads, rotation), rotation=rotation,
            converged=jnp.asarray(True), steps=jnp.asarray(0),
        )
        return solution, loads > 0
    rtol, atol = floored_tolerances(rtol, atol, dtype)
    frozen = jax.tree_util.tree_map(jax.lax.stop_gradient, problem)
    # start: the exact diagonal solution with each point's own compliance, the contact
    # law's tangent at the mean load included (so a rigid tooth with a contact law works)
    mean_load = jnp.abs(frozen.torque) / jnp.sum(frozen.pinion_arm) + frozen._floor
    compliance = jnp.diagonal(frozen.compliance, axis1=-2, axis2=-1) + frozen.approach(jnp.full_like(frozen.separation, mean_load))[1]
    stiffness = 1.0 / jnp.mean(compliance)
    loads0, rotation0 = _diagonal_solution(frozen, compliance)
    active0 = _active_set(frozen, loads0, rotation0, stiffness)
    if start is not None:
        start = jax.lax.stop_gradient(start)
        warm = start.torque > 0
        scale = safe_divide(frozen.torque, start.torque)
        loads0 = jnp.where(warm, jnp.where(start.active, start.loads * scale, 0.0), loads0)
        rotation0 = jnp.where(warm, start.rotation, rotation0)
        active0 = jnp.where(warm, start.active, active0)

    def step(carry):
        loads, rotation, active, _, i = carry
        new_loads, new_rotation = _newton_map(frozen, loads, rotation, active)
        new_active = _active_set(frozen, new_loads, new_rotation, stiffness)
        settled = jnp.all(new_active == active)
        if problem.exponent != 1.0:
            damping = jnp.where(settled, _fraction_to_boundary(loads, new_loads), 1.0)
            new_loads = loads + damping * (new_loads - loads)
            new_rotation = rotation + damping * (new_rotation - rotation)
            scale = jnp.max(jnp.abs(new_loads))
            settled = settled & (jnp.max(jnp.abs(new_loads - loads)) <= rtol * scale + atol * (1.0 + scale))
        return new_loads, new_rotation, new_active, settled, i + 1

    def more(carry):
        return (~carry[3]) & (carry[4] < max_steps)

    init = (loads0, rotation0, active0, jnp.asarray(False), jnp.asarray(0))
    loads, rotation, active, settled, steps = jax.lax.while_loop(more, step, init)
    loads, rotation = _exact_when_idle(problem, *_implicit(problem, loads, rotation, active))
    solution = ContactSolution(
        loads=loads, gaps=problem.gaps(loads, rotation), rotation=rotation, converged=settled, steps=steps
    )
    return solution, active


def sequential_loads(diagonal: bool, exponent: float) -> bool:
    """Whether several loads are solved one after another, each warm-started from the
    solution below it (`solve_over_loads`): for the iterative solver (face-coupled blocks
    or a nonlinear contact law) on the CPU, where the warm start's fewer steps pay; on an
    accelerator the loads are solved side by side, where a batch costs little more than
    one problem. The exact diagonal solver has no steps to save."""
    return not (diagonal and exponent == 1.0) and jax.default_backend() == "cpu"


def solve_over_loads(problems_at, torques, accuracy, rates: bool):
    """The contact problems `problems_at(T)` (a `ContactProblem` with a leading position
    axis) at every torque of `torques` (N·mm, 1-D), in ascending order, each position
    warm-started from its solution at the torque below (`WarmStart`): `(solutions,
    dTheta/dT or None)` with axes (load, position), the loads in the order of `torques`.

    Neighbouring loads have nearly the same active set, so a warm start needs one or two
    active-set steps where the diagonal model's start needs four to seven; the loads are
    then solved one after another (`lax.scan`), not side by side. With `rates` the rate
    $\\mathrm d\\Theta/\\mathrm dT$ comes from forward differentiation at each load."""
    order = jnp.argsort(torques)
    shape = problems_at(torques[0]).separation.shape
    start = WarmStart(jnp.zeros(shape, torques.dtype), jnp.zeros(shape[:1], torques.dtype),
                      jnp.zeros(shape, bool), jnp.zeros((), torques.dtype))
    rtol, atol, steps = accuracy.newton_rtol, accuracy.newton_atol, accuracy.contact_max_steps

    def solve(t, start):
        one = jax.vmap(lambda problem, start: _solve(problem, rtol, atol, steps, start),
                       in_axes=(0, WarmStart(0, 0, 0, None)))
        return one(problems_at(t), start)

    def at_load(start, t):
        if rates:
            (sol, active), (dsol, _) = jax.jvp(lambda t: solve(t, start), (t,), (jnp.ones_like(t),))
            rate = dsol.rotation
        else:
            (sol, active), rate = solve(t, start), None
        return WarmStart(sol.loads, sol.rotation, active, t), (sol, rate)

    _, (solutions, rotation_rates) = jax.lax.scan(at_load, start, torques[order])
    inverse = jnp.argsort(order)
    return jax.tree_util.tree_map(lambda x: x[inverse], (solutions, rotation_rates))
