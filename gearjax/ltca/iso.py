r"""Mesh stiffness by ISO 6336-1:2019, method B.

$$q' = C_1 + \frac{C_2}{z_{n1}} + \frac{C_3}{z_{n2}} + C_4x_1 + C_5\frac{x_1}{z_{n1}} + C_6x_2 + C_7\frac{x_2}{z_{n2}}
      + C_8x_1^2 + C_9x_2^2 \quad (\mathrm{mm\,\mu m/N}),$$

$z_n = z/(\cos^2\beta_b\cos\beta)$, $c'_{th} = 1/q'$, $c' = c'_{th} C_M C_R C_B \cos\beta$ with
$C_B = [1 + 0.5(1.2 - h_{fP}/m_n)][1 - 0.02(20° - \alpha_{Pn})]$ (mean of both gears),
$c_{\gamma\alpha} = c'(0.75\varepsilon_\alpha + 0.25)$ and $c_{\gamma\beta} = 0.85c_{\gamma\alpha}$, all in
N/(mm·µm). Valid for $F_tK_A/b \ge 100$ N/mm and solid steel discs ($C_R = 1$).

ISO/TR 6336-30:2022, example 1 evaluates $q'$ with the printed (rounded) profile shift
$x_1 = 0.145$ and gets $c' = 12.370$, $c_{\gamma\alpha} = 17.465$;
`tests/test_ltca_compliance.py` reproduces both.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from .._custom_types import ArrayLike, Scalar
from ..geometry.involute_section import AbstractInvolutePair

#: C1 ... C9 of ISO 6336-1 method B (mm·µm/N).
ISO_Q_COEFFICIENTS = (0.04723, 0.15551, 0.25791, -0.00635, -0.11654, -0.00193, -0.24188, 0.00529, 0.00182)


class IsoStiffness(eqx.Module):
    """ISO 6336-1 method B stiffness values, N/(mm·µm).

    Attributes:
        single_stiffness_theoretical: $c'_{th} = 1/q'$.
        single_stiffness: $c'$, maximum single-pair stiffness per unit face width.
        mesh_stiffness: $c_{\\gamma\\alpha}$, mean mesh stiffness per unit face width.
        mesh_stiffness_beta: $c_{\\gamma\\beta} = 0.85\\,c_{\\gamma\\alpha}$.
    """

    single_stiffness_theoretical: Scalar
    single_stiffness: Scalar
    mesh_stiffness: Scalar
    mesh_stiffness_beta: Scalar


def iso_mesh_stiffness(
    pair: AbstractInvolutePair,
    *,
    profile_shift: ArrayLike | None = None,
    transverse_contact_ratio: ArrayLike | None = None,
    mesh_factor: float = 0.8,
    blank_factor: float = 1.0,
) -> IsoStiffness:
    """ISO 6336-1 method B mesh stiffness of an involute pair.

    Args:
        pair: the gear pair; its basic rack supplies $h_{fP}$ and $\\alpha_{Pn}$.
        profile_shift: $(x_1, x_2)$ used in $q'$ (default: the pair's; the ISO/TR example
            uses its printed, rounded value).
        transverse_contact_ratio: $\\varepsilon_\\alpha$ (default: the pair's).
        mesh_factor: $C_M$ (0.8).
        blank_factor: $C_R$ (1 for solid discs).
    """
    c = ISO_Q_COEFFICIENTS
    x = pair.profile_shift if profile_shift is None else jnp.asarray(profile_shift)
    x1, x2 = x[..., 0], x[..., 1]
    beta = pair.helix_angle
    factor = jnp.cos(pair.base_helix_angle) ** 2 * jnp.cos(beta)
    zn1, zn2 = pair.teeth[0] / factor, pair.teeth[1] / factor
    q = (
        c[0] + c[1] / zn1 + c[2] / zn2 + c[3] * x1 + c[4] * x1 / zn1 + c[5] * x2 + c[6] * x2 / zn2
        + c[7] * x1**2 + c[8] * x2**2
    )
    alpha_pn_deg = jnp.degrees(pair.normal_pressure_angle)
    basic_rack = (1 + 0.5 * (1.2 - pair.dedendum_coefficient)) * (1 - 0.02 * (20.0 - alpha_pn_deg[..., None]))
    c_b = jnp.mean(basic_rack, axis=-1)
    c_th = 1.0 / q
    c_single = c_th * mesh_factor * blank_factor * c_b * jnp.cos(beta)
    eps = pair.transverse_contact_ratio if transverse_contact_ratio is None else jnp.asarray(transverse_contact_ratio)
    c_alpha = c_single * (0.75 * eps + 0.25)
    return IsoStiffness(c_th, c_single, c_alpha, 0.85 * c_alpha)
