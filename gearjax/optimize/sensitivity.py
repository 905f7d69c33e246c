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

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._custom_types import ArrayLike
from .objective import Objective
from .space import PARAMETERS, SCENE_KEYS, DesignSpace

_ERRORS = (("base_pitch_deviation", "base_pitch_deviation_um"), ("pitch_deviation", "pitch_deviation_um"),
           ("misalignment", "misalignment_um"))


@eqx.filter_jit
def _gradients(objective: Objective, design, torques, speed, errors):
    def J(design, torques, speed, errors):
        o = eqx.tree_at(lambda o: (o.torques, o.scene.operating.speed, o.errors), objective, (torques, speed, errors))
        return o(design)

    return jax.value_and_grad(J, argnums=(0, 1, 2, 3))(design, torques, speed, errors)


def sensitivities(objective: Objective, design: ArrayLike, space: DesignSpace | None = None) -> dict:
    """Gradient of the objective at `design` (mm, shape (6,)).

    Args:
        objective: the `Objective`.
        design: $(y_1, \\dots, y_6)$ (mm).
        space: the design space, for the normalised parameter sensitivities (optional).

    Returns:
        A dict with `objective` ($J$), `parameters`: for each modification parameter its
        value and $\\partial J/\\partial y$ in the scene file's units (per µm of an amount,
        per mm of a length) and, with a space, `per_bound_width` ($w\\,\\partial J/\\partial y$);
        `loads`: $\\partial J/\\partial T$ per N·m for each load; `speed`:
        $\\partial J/\\partial n$ per rpm and the log-derivative
        $(\\omega/J)\\,\\partial J/\\partial\\omega$; `errors`: $\\partial J/\\partial f$ per µm
        for a common shift of each error over all samples.
    """
    dtype = objective.torques.dtype
    design = jnp.asarray(design, dtype)
    speed = jnp.asarray(objective.scene.operating.speed, dtype)
    value, (g_design, g_torque, g_speed, g_errors) = _gradients(objective, design, objective.torques, speed, objective.errors)
    value = float(value)
    parameters = {}
    for i, ((key, factor), name) in enumerate(zip(SCENE_KEYS, PARAMETERS)):
        entry = {"key": key, "value": float(design[i]) * factor, "gradient": float(g_design[i]) / factor}
        if space is not None:
            entry["per_bound_width"] = float(g_design[i] * space.width[i])
        parameters[name] = entry
    rpm = 2.0 * np.pi / 60.0  # rad/s per rpm
    return {
        "objective": value,
        "parameters": parameters,
        "loads": [
            {"torque_Nm": float(t) / 1000.0, "gradient_per_Nm": float(g) * 1000.0}
            for t, g in zip(np.asarray(objective.torques), np.asarray(g_torque))
        ],
        "speed": {
            "speed_rpm": float(speed) / rpm,
            "gradient_per_rpm": float(g_speed) * rpm,
            "log_derivative": float(g_speed) * float(speed) / value,
        },
        "errors": {key: float(jnp.sum(getattr(g_errors, name))) * 1e-3 for name, key in _ERRORS},
    }


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
    lines.append(f"speed {s['speed_rpm']:g} rpm         dJ/dn = {s['gradient_per_rpm']:.4g} per rpm (log-derivative {s['log_derivative']:.4f})")
    for key, g in result["errors"].items():
        lines.append(f"{key:24s} dJ/df = {g:.4g} per um")
    return "\n".join(lines)
