r"""Sensitivities of the objective at a design: what matters, and how much.

The gradient of $J$ (`Objective`) with respect to the six modification parameters, the
loads, the pinion speed and the mesh errors, by reverse-mode differentiation through the
whole chain (TCA, LTCA, first-contact search, stiffness fit, energy method). For the
parameters it is also given normalised by the bound widths,
$\partial J/\partial x_i = w_i\,\partial J/\partial y_i$ (the change of $J$ across the
whole range of $y_i$, to first order), which ranks them on one scale.

Where the impact force is the objective, the speed enters only through
$F_s \propto v_n^{2n/(n+1)}$, so $\omega\,\partial F_s/\partial\omega = \tfrac{2n}{n+1}F_s$:
a check of the derivative chain that `tests/test_optimize.py` uses.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from .._custom_types import ArrayLike
from .objective import Objective
from .batch import batch_gradients
from .space import PARAMETERS, SCENE_KEYS, DesignSpace

_ERRORS = (("base_pitch_deviation", "base_pitch_deviation_um"), ("pitch_deviation", "pitch_deviation_um"),
           ("misalignment", "misalignment_um"))


def sensitivities(objective: Objective, design: ArrayLike, space: DesignSpace | None = None) -> dict | list[dict]:
    """Gradient of the objective at `design` (mm, shape (6,)), or at each of several designs
    (shape (K, 6)) in one compiled call: the program that gradient descent runs with K
    starts (`gearjax.optimize.batch.batch_gradients`), so sensitivities at as many designs as
    the descent has starts cost no compilation after a descent, and none before one.

    Args:
        objective: the `Objective`.
        design: $(y_1, \\dots, y_6)$ (mm), shape (6,) or (K, 6).
        space: the design space, for the normalised parameter sensitivities (optional).

    Returns:
        For one design a dict (a list of them for K designs) with `objective` ($J$),
        `parameters`: for each modification parameter its value and
        $\\partial J/\\partial y$ in the scene file's units (per µm of an amount, per mm of a
        length) and, with a space, `per_bound_width` ($w\\,\\partial J/\\partial y$);
        `loads`: for each load $\\partial J/\\partial T$ per N·m and its speed with
        $\\partial J/\\partial n$ per rpm; `speed`: the time-weighted mean speed, and for every
        load's speed moved together $\\partial J/\\partial n$ per rpm and the log-derivative
        $\\sum_l(\\omega_l/J)\\,\\partial J/\\partial\\omega_l$ (with one speed for all loads,
        $(\\omega/J)\\,\\partial J/\\partial\\omega$); `errors`: $\\partial J/\\partial f$ per µm
        for a common shift of each error over all samples.
    """
    designs = np.asarray(design, dtype=float)
    if not (designs.shape == (6,) or (designs.ndim == 2 and designs.shape[1] == 6 and len(designs) > 0)):
        raise ValueError(f"design must have shape (6,) or (K, 6) (y1..y6, mm); got shape {designs.shape}")
    if not np.all(np.isfinite(designs)):
        raise ValueError("design must be finite (y1..y6, mm)")
    values, (g_design, g_torque, g_speed, g_errors) = batch_gradients(objective, designs.reshape(-1, 6))
    speeds, weights = np.asarray(objective.speeds), np.asarray(objective.weights)
    rpm = 2.0 * np.pi / 60.0  # rad/s per rpm
    results = []
    for k, y in enumerate(designs.reshape(-1, 6)):
        value = float(values[k])
        parameters = {}
        for i, ((key, factor), name) in enumerate(zip(SCENE_KEYS, PARAMETERS, strict=True)):
            entry = {"key": key, "value": float(y[i]) * factor, "gradient": float(g_design[k, i]) / factor}
            if space is not None:
                entry["per_bound_width"] = float(g_design[k, i] * space.width[i])
            parameters[name] = entry
        results.append({
            "objective": value,
            "parameters": parameters,
            "loads": [
                {"torque_Nm": float(t) / 1000.0, "gradient_per_Nm": float(g) * 1000.0, "speed_rpm": float(n) / rpm,
                 "speed_gradient_per_rpm": float(gn) * rpm}
                for t, g, n, gn in zip(np.asarray(objective.torques), np.asarray(g_torque[k]), speeds,
                                       np.asarray(g_speed[k]), strict=True)
            ],
            "speed": {
                "speed_rpm": float(np.sum(weights * speeds)) / rpm,
                "gradient_per_rpm": float(np.sum(g_speed[k])) * rpm,
                "log_derivative": float(np.sum(np.asarray(g_speed[k]) * speeds)) / value,
            },
            "errors": {key: float(jnp.sum(getattr(g_errors, name)[k])) * 1e-3 for name, key in _ERRORS},
        })
    return results[0] if designs.ndim == 1 else results


def sensitivity_table(result: dict) -> str:
    """A plain-text table of `sensitivities`' result."""
    lines = [f"objective J = {result['objective']:.6g}", "parameter              value        dJ/dp          w dJ/dp"]
    for name, e in result["parameters"].items():
        unit = "um" if e["key"].endswith("_um") else "mm"
        width = f"{e['per_bound_width']:12.4g}" if "per_bound_width" in e else ""
        lines.append(f"{name:20s} {e['value']:9.4g} {unit}  {e['gradient']:12.4g}/{unit}  {width}")
    for load in result["loads"]:
        lines.append(f"torque {load['torque_Nm']:g} N·m        dJ/dT = {load['gradient_per_Nm']:.4g} per N·m")
    s = result["speed"]
    speeds = {load["speed_rpm"] for load in result["loads"]}
    if len(speeds) > 1:
        for load in result["loads"]:
            lines.append(f"speed at {load['torque_Nm']:g} N·m {load['speed_rpm']:g} rpm  "
                         f"dJ/dn = {load['speed_gradient_per_rpm']:.4g} per rpm")
    what = f"speed {s['speed_rpm']:g} rpm" if len(speeds) == 1 else "all speeds together"
    lines.append(f"{what:24s} dJ/dn = {s['gradient_per_rpm']:.4g} per rpm (log-derivative {s['log_derivative']:.4f})")
    for key, g in result["errors"].items():
        lines.append(f"{key:24s} dJ/df = {g:.4g} per um")
    return "\n".join(lines)
