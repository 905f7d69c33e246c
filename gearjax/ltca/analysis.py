r"""Loaded tooth contact analysis over a mesh cycle.

At every position of the TCA, the contact points are the (pair, face-slice) points with
their initial separations; a compliance model gives their influence matrix, and the contact
problem (`solver.py`) gives the loads and the gear's extra lag $\Theta$. Results:

* loaded transmission error $\mathrm{LTE} = \mathrm{TE} - \Theta$ (rad, gear 2), and along
  the line of action $r_{b2}\,\mathrm{LTE}$;
* loads per point, load share per tooth pair, maximum contact pressure (Hertz line
  contact, $p_0 = \sqrt{wE^*/(\pi R')}$ with $w$ the load per unit length of contact line,
  $1/E^* = 2(1-\nu^2)/E$, $1/R' = |n_t|(1/s_1 + 1/s_2)$ in the normal section);
* mesh stiffness per unit face width along the transverse line of action, secant
  $k = (T/r_{b1})/(r_{b2}\Theta\,b)$ and tangent $(\mathrm{d}T/r_{b1})/(r_{b2}\,\mathrm{d}\Theta\,b)$
  (N/(mm·µm)); $\Theta$ counts from the first rigid contact, so for modified flanks the
  secant value includes the closing of their gaps.

Point-contact flanks (double-circular-arc gears, `ToothSectionCompliance`) are solved per
tooth pair instead (`point_analysis`) and reported in the same layout.

Everything is batched over positions in one program. Several loads: a 1-D torque; the
face-coupled problems are then solved load after load, each warm-started from the one
below it, on the CPU (`solver.solve_over_loads`), and side by side on an accelerator.
"""

from __future__ import annotations

import functools as ft

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, Bool, Float, Int, Scalar
from .._numerics import safe_divide, safe_sqrt
from .._solution import RESULTS, first_failure
from ..tca import ContactKind, TCAResult
from ..tca.grid import nested_vmap
from ..units import Material
from .hertz_point import effective_modulus
from .model import ContactModel
from .point_analysis import PointContactLoads, ToothSectionCompliance, point_contact_analysis
from .solver import NO_CONTACT, ContactProblem, sequential_loads, solve_over_loads, solve_with

class LTCAResult(eqx.Module):
    """Loaded contact over a mesh cycle. Axes: position, pair, slice (midpoints only).

    Units: angular transmission-error quantities are in rad (gear 2) and carry no suffix;
    the same quantity along the transverse line of action, $r_{b2}$ times the angle, is in
    mm and carries the suffix `_line` (`transmission_error` / `transmission_error_line`,
    `lte_peak_to_peak` / `lte_peak_to_peak_line`).

    Attributes:
        pinion_angle: $\\varphi_1$ (rad).
        torque: pinion torque (N·mm).
        transmission_error: loaded TE of gear 2 (rad).
        unloaded_transmission_error: TE (rad).
        rotation: extra lag $\\Theta$ of the gear under load (rad).
        rotation_rate: $\\mathrm{d}\\Theta/\\mathrm{d}T$ (rad/(N·mm)), or None when
            `loaded_contact_analysis` ran with `rates=False`; the mesh-stiffness
            properties need it and raise `ValueError` without it.
        loads: normal load of every point (N).
        gaps: loaded gaps (mm).
        pressure: maximum Hertz pressure of every point (MPa).
        converged: the contact solve converged, per position.
        pair_index, slice_z: the points' tooth pairs and axial positions (mm).
        action_radius: $(r_{b1}, r_{b2})$ (mm), shape (2,).
        face_width: $b$ (mm).
        result: `RESULTS.successful`, or `RESULTS.ltca_unconverged` where the solve did
            not converge at some position (`converged` tells which).
        point_contact: for point-contact flanks (`ToothSectionCompliance`), each pair's
            contact in full (`PointContactLoads`: ellipse, curvatures, compliances, its
            position between the slices); None for line contact. The slice fields then
            hold each pair's contact at the face slice nearest to it.
    """

    pinion_angle: Float[Array, " pos"]
    torque: Scalar
    transmission_error: Float[Array, " pos"]
    unloaded_transmission_error: Float[Array, " pos"]
    rotation: Float[Array, " pos"]
    rotation_rate: Float[Array, " pos"] | None
    loads: Float[Array, "pos pair slice"]
    gaps: Float[Array, "pos pair slice"]
    pressure: Float[Array, "pos pair slice"]
    converged: Bool[Array, " pos"]
    pair_index: Int[Array, " pair"]
    slice_z: Float[Array, " slice"]
    action_radius: Float[Array, "2"]
    face_width: Scalar
    result: RESULTS
    point_contact: PointContactLoads | None = None

    @property
    def transmission_error_line(self):
        """Loaded TE along the line of action, $r_{b2}\\,\\mathrm{LTE}$ (mm)."""
        return self.transmission_error * self.action_radius[..., 1, None]

    @property
    def lte_peak_to_peak(self):
        """Peak-to-peak angular loaded TE over the cycle (rad)."""
        lte = self.transmission_error
        return jnp.max(lte, -1) - jnp.min(lte, -1)

    @property
    def lte_peak_to_peak_line(self):
        """Peak-to-peak loaded TE along the line of action, $r_{b2}$ times
        `lte_peak_to_peak` (mm)."""
        return self.lte_peak_to_peak * self.action_radius[..., 1]

    @property
    def normal_load(self):
        """Total normal load per position (N)."""
        return jnp.sum(self.loads, axis=(-2, -1))

    @property
    def load_share(self):
        """Share of the load carried by each tooth pair (pos, pair)."""
        per_pair = jnp.sum(self.loads, axis=-1)
        return safe_divide(per_pair, jnp.sum(per_pair, axis=-1, keepdims=True))

    @property
    def max_load_share(self):
        return jnp.max(self.load_share, axis=(-2, -1))

    def _rate(self, name):
        if self.rotation_rate is None:
            raise ValueError(
                f"LTCAResult.{name} needs rotation_rate, which was not computed: run "
                "loaded_contact_analysis(..., rates=True) (the default)"
            )
        return self.rotation_rate

    def _stiffness(self, deflection_per_torque):
        """(T/r_b1)/(r_b2 * deflection)/b in N/(mm·um)."""
        rb1, rb2 = self.action_radius[..., 0, None], self.action_radius[..., 1, None]
        return safe_divide(1.0 / rb1, rb2 * deflection_per_torque * self.face_width[..., None]) * 1e-3

    @property
    def mesh_stiffness_secant(self):
        """Secant mesh stiffness per unit face width (N/(mm·µm)); the tangent value where
        the torque is zero (so it needs `rotation_rate`)."""
        rate = self._rate("mesh_stiffness_secant")
        per_torque = safe_divide(self.rotation, self.torque[..., None])
        per_torque = jnp.where(self.torque[..., None] > 0, per_torque, rate)
        return self._stiffness(per_torque)

    @property
    def mesh_stiffness_tangent(self):
        """Tangent mesh stiffness $\\mathrm{d}P/\\mathrm{d}\\delta$ per unit face width (N/(mm·µm))."""
        return self._stiffness(self._rate("mesh_stiffness_tangent"))

    @property
    def mean_mesh_stiffness(self):
        """Cycle mean of the tangent mesh stiffness (N/(mm·µm))."""
        return jnp.mean(self.mesh_stiffness_tangent, axis=-1)

    @property
    def max_pressure(self):
        return jnp.max(self.pressure, axis=(-3, -2, -1))


def moment_arms(x, n, center2):
    """Pinion arm $p = (x\\times n)_z$ and gear arm $q = -((x - O_2)\\times n)_z$ (mm) of
    the normal `n` through the point `x` (last axis 3): the torque per unit normal load on
    the pinion, and the normal closure per unit lag of the gear."""
    p = x[..., 0] * n[..., 1] - x[..., 1] * n[..., 0]
    r = x[..., :2] - center2
    q = -(r[..., 0] * n[..., 1] - r[..., 1] * n[..., 0])
    return p, q


def _levers(tca: TCAResult, n_mid: int, center2):
    """`moment_arms` of the slice contacts; points without a contact get the position's mean."""
    valid = tca.valid[..., :n_mid]
    p, q = moment_arms(tca.pinion_point[..., :n_mid, :], tca.normal[..., :n_mid, :], center2)

    def fill(a):
        mean = safe_divide(jnp.sum(jnp.where(valid, a, 0.0), axis=(-2, -1), keepdims=True),
                           jnp.sum(valid, axis=(-2, -1), keepdims=True).astype(a.dtype))
        return jnp.where(valid, a, mean)

    return fill(p), fill(q)


def flank_weights(pair, tca: TCAResult, n_mid: int):
    """Length of contact line each slice stands for, in units of its cell width.

    A contact line crosses the active flanks over an interval $[A, B]$ of $z$: the face
    width intersected with the stretch where both contact parameters, moving at the rates
    $\\mathrm{d}u_i/\\mathrm{d}z$ of the conjugate contact (forward-mode derivative of
    `contact_guess` along the lead), stay within their limits. Each slice whose centre lies
    in $[A, B]$ takes the part of the interval nearest to it, so an end slice also takes
    the inner part of an outer neighbour's cell: weights lie in $[0, 1.5]$ and sum to
    $(B - A)/\\Delta z$. The contact-line length is then a continuous function of the
    pinion angle instead of a count of slices (exact for straight contact lines).
    """
    z = tca.slice_z[..., :n_mid]
    dz = jnp.mean(tca.slice_width[..., :n_mid])
    b = pair.face_width
    k = tca.pair_index.astype(z.dtype)

    def rates(phi, kk, zz):
        def guess(t):
            return jnp.stack(pair.contact_guess(phi - kk * pair.angular_pitch(0) + pair.lead_rotation(0, t)))

        return jax.jvp(guess, (zz,), (jnp.ones_like(zz),))[1]

    rate = nested_vmap(rates, [(0, None, None), (None, 0, None), (None, None, 0)], tca.pinion_angle, k, z)
    u = jnp.stack([tca.pinion_parameter[..., :n_mid], tca.gear_parameter[..., :n_mid]], -1)
    lo = jnp.stack([pair.profile_limits(0)[0], pair.profile_limits(1)[0]])
    hi = jnp.stack([pair.profile_limits(0)[1], pair.profile_limits(1)[1]])
    inside = (u >= lo) & (u <= hi)
    # offsets from the slice centre where each parameter reaches its limits
    t_lo = safe_divide(lo - u, rate, -jnp.inf)
    t_hi = safe_divide(hi - u, rate, jnp.inf)
    moving = rate != 0
    start = jnp.where(moving, jnp.minimum(t_lo, t_hi), jnp.where(inside, -jnp.inf, jnp.inf))
    end = jnp.where(moving, jnp.maximum(t_lo, t_hi), jnp.where(inside, jnp.inf, -jnp.inf))
    start = jnp.maximum(jnp.max(start, -1), -0.5 * b - z)
    end = jnp.minimum(jnp.min(end, -1), 0.5 * b - z)
    lower = jnp.where(start > -dz, start, -0.5 * dz)
    upper = jnp.where(end < dz, end, 0.5 * dz)
    centred = (start <= 0) & (end >= 0)
    return jnp.where(centred, jnp.clip((upper - lower) / dz, 0.0, 1.5), 0.0)


def loaded_contact_analysis(
    pair,
    tca: TCAResult,
    torque,
    model: ContactModel,
    *,
    active_pairs: Bool[Array, " pair"] | None = None,
    rates: bool = True,
) -> LTCAResult:
    """LTCA of `pair` at pinion torque `torque` (N·mm) on the positions of `tca`.

    Args:
        pair: the gear pair, of a family with "ltca" in its `supported_effects`: line
            contact of involute sections (whose transverse radius of curvature at roll
            length $s$ is $s$ itself, used for the Hertz pressure) with an
            `AbstractSliceCompliance`, or point contact with `ToothSectionCompliance`
            (`point_contact_analysis`; the result's `point_contact` holds the contacts).
        tca: its unloaded contact (`tooth_contact_analysis`).
        torque: pinion torque (N·mm), a scalar, or a 1-D array of several torques (every
            field of the result then has a leading load axis, as under `vmap`).
        model: compliance, material, hub radii, accuracy and `extended_contact`
            (`ContactModel`; `Scene.contact_model`). With `extended_contact` loaded teeth
            also touch by their tip edges beyond the active profile (the TCA's edge
            contacts; physical default); without it the classic model: flank contacts
            only, each slice weighted by the fraction of its cell on the active flanks
            (`flank_weights`).
        active_pairs: optional mask over the tooth pairs of the window; pairs outside it
            carry no load (the impact search uses it to load only the pairs already in mesh).
        rates: also compute $\\mathrm d\\Theta/\\mathrm dT$ (tangent mesh stiffness); without
            it `rotation_rate` is None and the program is smaller.
    """
    if "ltca" not in pair.supported_effects:
        raise ValueError(
            f"loaded contact analysis needs a family that supports it ('ltca' in supported_effects); "
            f"{type(pair).__name__} supports {sorted(pair.supported_effects) or 'the rigid TCA only'}"
        )
    if not isinstance(pair, model.compliance.families):
        raise ValueError(
            f"compliance {type(model.compliance).__name__} models the teeth of "
            f"{', '.join(f.__name__ for f in model.compliance.families)} only; got {type(pair).__name__}"
        )
    pair = pair.resolve()
    torque = jnp.asarray(torque, dtype=tca.separation.dtype)
    if torque.ndim > 1:
        raise ValueError(f"torque must be a scalar or a 1-D array of torques (N·mm); got shape {torque.shape}")
    if isinstance(model.compliance, ToothSectionCompliance):
        point = ft.partial(_point_loaded, pair, tca, model=model, active_pairs=active_pairs, rates=rates)
        return jax.vmap(point)(torque) if torque.ndim else point(torque)
    n_mid = model.accuracy.face_slices
    valid, weights = _loaded_slices(pair, tca, model, active_pairs)
    with jax.named_scope("ltca_compliance"):
        points = model.compliance(
            pair, model.material, model.hub_radius, tca, n_mid, model.accuracy.quadrature_points, weights
        )
    separation = jnp.where(valid, tca.separation[..., :n_mid], NO_CONTACT)
    with jax.named_scope("ltca_contact"):
        sol, rotation_rate = _solve_positions(points, separation, _levers(tca, n_mid, pair.center(1)), torque, model, rates)

    def result(torque, sol, rotation_rate):
        loads = sol.loads.reshape(valid.shape)
        return LTCAResult(
            pinion_angle=tca.pinion_angle, torque=torque,
            transmission_error=tca.transmission_error - sol.rotation, unloaded_transmission_error=tca.transmission_error,
            rotation=sol.rotation, rotation_rate=rotation_rate, loads=loads, gaps=sol.gaps.reshape(valid.shape),
            pressure=jnp.where(valid, hertz_pressure(tca, loads, weights, model.material, n_mid), 0.0),
            converged=sol.converged,
            pair_index=tca.pair_index, slice_z=tca.slice_z[..., :n_mid],
            action_radius=pair.action_radii(), face_width=pair.face_width,
            result=first_failure((~jnp.all(sol.converged), RESULTS.ltca_unconverged)),
        )

    if torque.ndim == 1:  # one result per load (the solutions' leading axis)
        return jax.vmap(result)(torque, sol, rotation_rate)
    return result(torque, sol, rotation_rate)


def _point_loaded(pair, tca: TCAResult, torque, model: ContactModel, active_pairs, rates: bool) -> LTCAResult:
    """The LTCA of point-contact flanks (`point_contact_analysis`), in the slice layout of
    `LTCAResult`: each pair's load, pressure and loaded gap at the face slice nearest its
    contact; $\\mathrm d\\Theta/\\mathrm dT$ by forward differentiation when `rates`."""
    n_mid = model.accuracy.face_slices
    ratio = pair.teeth[1] / pair.teeth[0]

    def solve(t):
        result = point_contact_analysis(pair, tca, t, model.material, model.compliance.coupling_length,
                                        active_pairs=active_pairs)
        return result.rotation, result

    torque = jnp.asarray(torque, dtype=tca.transmission_error.dtype)
    if rates:
        rotation, rotation_rate, point = jax.jvp(solve, (torque,), (jnp.ones_like(torque),), has_aux=True)
    else:
        (rotation, point), rotation_rate = solve(torque), None
    nearest = jnp.argmin(jnp.abs(point.axial_position[..., None] - tca.slice_z[..., :n_mid]), axis=-1)
    at_contact = (jnp.arange(n_mid) == nearest[..., None]) & jnp.isfinite(point.gaps)[..., None]
    on_slices = lambda x, empty=0.0: jnp.where(at_contact, x[..., None], empty)  # noqa: E731
    loaded_gap = jnp.maximum(point.gaps - point.arms * rotation[:, None], 0.0)
    total = jnp.sum(point.arms * point.loads, axis=-1)
    rtol, atol = model.accuracy.newton_tolerances(total.dtype)
    converged = jnp.abs(total - torque * ratio) <= rtol * torque * ratio + atol
    return LTCAResult(
        pinion_angle=tca.pinion_angle,
        torque=torque,
        transmission_error=point.transmission_error,
        unloaded_transmission_error=tca.transmission_error,
        rotation=rotation,
        rotation_rate=rotation_rate,
        loads=on_slices(point.loads),
        gaps=on_slices(jnp.where(jnp.isfinite(loaded_gap), loaded_gap, NO_CONTACT), NO_CONTACT),
        pressure=on_slices(point.max_pressure),
        converged=converged,
        pair_index=tca.pair_index,
        slice_z=tca.slice_z[..., :n_mid],
        action_radius=pair.action_radii(),
        face_width=pair.face_width,
        result=first_failure((~jnp.all(converged), RESULTS.ltca_unconverged)),
        point_contact=point,
    )


def _loaded_slices(pair, tca: TCAResult, model: ContactModel, active_pairs):
    """Which slice contacts may carry load, (pos, pair, slice), and the length of contact
    line each stands for in units of its cell (`flank_weights`, or 1 with
    `extended_contact`)."""
    n_mid = model.accuracy.face_slices
    valid = tca.valid[..., :n_mid]
    if active_pairs is not None:
        valid = valid & active_pairs[:, None]
    if model.extended_contact:
        return valid, jnp.ones(valid.shape, dtype=tca.separation.dtype)
    weights = flank_weights(pair, tca, n_mid)
    valid = valid & (tca.kind == ContactKind.flank)[..., :n_mid] & (weights > 1e-9)
    return valid, jnp.where(valid, weights, 1.0)


def _solve_positions(points, separation, levers, torque, model: ContactModel, rates: bool):
    """The contact problem of every position (vmapped over positions; blocks by tooth
    pair), and $\\mathrm d\\Theta/\\mathrm dT$ by forward differentiation when `rates`. A
    1-D `torque` adds a leading load axis: the loads solved in sequence, warm-started
    (`solve_over_loads`), where that pays (`sequential_loads`), else side by side."""
    data = (points.blocks, points.nonlinear, separation, *levers)

    def every_position(t):
        def one(*position):
            def solve(t):
                return solve_with(ContactProblem(*position, t, points.exponent, points.diagonal), model.accuracy)

            if rates:
                sol, dsol = jax.jvp(solve, (t,), (jnp.ones_like(t),))
                return sol, dsol.rotation
            return solve(t), None

        return jax.vmap(one)(*data)

    if torque.ndim == 0:
        return every_position(torque)
    if not sequential_loads(points.diagonal, points.exponent):
        return jax.vmap(every_position)(torque)
    problems = jax.vmap(lambda t, *position: ContactProblem(*position, t, points.exponent, points.diagonal),
                        in_axes=(None,) + (0,) * len(data))
    return solve_over_loads(lambda t: problems(t, *data), torque, model.accuracy, rates)


def hertz_pressure(tca: TCAResult, loads, weights, material: Material, n_mid: int):
    """Maximum Hertz pressure of each slice (MPa), line contact in the normal section:
    $p_0 = \\sqrt{wE^*/(\\pi R')}$, $w$ the load per unit length of contact line,
    $1/E^* = 2(1-\\nu^2)/E$, $1/R' = |n_t|(1/s_1 + 1/s_2)$ with the roll lengths $s_i$,
    the involutes' radii of curvature."""
    frac = tca.transverse_normal_fraction[..., :n_mid]
    length = tca.slice_width[..., :n_mid] / frac
    curvature = frac * (1.0 / tca.pinion_parameter[..., :n_mid] + 1.0 / tca.gear_parameter[..., :n_mid])
    e_star = effective_modulus(material.youngs_modulus, material.poisson_ratio)
    return safe_sqrt(jnp.maximum(loads, 0.0) / (length * weights) * e_star * curvature / jnp.pi)
