r"""Compliance of one involute tooth and of the contact, per unit face width.

All compliances are deflection per unit load per unit face width, in the transverse plane,
along the load line (mm²/N: divide by a slice width in mm to get mm/N). Plane stress.

**Potential energy** (Yang & Lin 1987: bending and axial compression; Tian 2004: shear;
collected by Chaari et al. 2009 and Ma et al. 2014). With $\alpha_2$ the half tooth angle on
the base circle and $\alpha_1 = s/r_b - \alpha_2$ the load angle of a contact at roll length
$s$, $D(\alpha) = \sin\alpha + (\alpha_2 - \alpha)\cos\alpha$:

$$\frac1{k_b} = \int_{-\alpha_1}^{\bar\alpha} \frac{3[1 + \cos\alpha_1((\alpha_2-\alpha)\sin\alpha - \cos\alpha)]^2
  (\alpha_2-\alpha)\cos\alpha}{2ED^3}\,d\alpha,\quad
\frac1{k_s} = \int \frac{1.2(1+\nu)(\alpha_2-\alpha)\cos\alpha\cos^2\alpha_1}{ED}\,d\alpha,\quad
\frac1{k_a} = \int \frac{(\alpha_2-\alpha)\cos\alpha\sin^2\alpha_1}{2ED}\,d\alpha .$$

If the base circle lies above the root circle ($r_b > r_f$) the tooth continues below it as
a straight segment of half thickness $r_b\sin\alpha_2$ down to the root circle
($\bar\alpha = \alpha_2$, closed-form terms added; *base-circle convention*); otherwise it is
clamped at the root circle, $\bar\alpha = \alpha_2 - \sqrt{(r_f/r_b)^2 - 1}$. The
integrals use Gauss–Legendre quadrature.

**Fillet foundation** (Sainsot, Velex & Duverger 2004, J. Mech. Des. 126:748):

$$\delta_f = \frac{\cos^2\alpha_m}{E}\Big[L^*\Big(\frac{u_f}{S_f}\Big)^2 + M^*\frac{u_f}{S_f} + P^*(1 + Q^*\tan^2\alpha_m)\Big],$$

$X^* = A/\theta_f^2 + Bh_f^2 + Ch_f/\theta_f + D/\theta_f + Eh_f + F$ (table below), with
$\alpha_m = \alpha_1$, $u_f = r_b/\cos\alpha_m - r_f$ (distance along the tooth centre line from
the root circle to the load line), $S_f = 2r_f\theta_f$, $h_f = r_f/r_\text{hub}$ and $\theta_f$
the half angle of the tooth at the root circle of a rack-generated gear,
$\theta_f = \pi/z - w/r$, $w = \pi m_t/4 - h_{fP}\tan\alpha_t - \rho_{fP}(1-\sin\alpha_t)/\cos\alpha_t$
(the tool's tip flat; transverse approximation). The fit covers $1.4 \le h_f \le 7$,
$0.01 \le \theta_f \le 0.12$; small pinions ($z \lesssim 25$) extrapolate.

**Contact**: linear, load-independent $1/k_h = 4(1-\nu^2)/(\pi E)$ per unit contact length
(Yang & Sun 1985), or Palmgren's steel line contact $\delta = 3.84\cdot10^{-5}Q^{0.9}/L^{0.8}$
(mm, N) for a load $Q$ over a contact line of length $L$ (how the slice model applies it:
`gearjax.ltca.SliceCompliance`).

The coefficient table and the verification of the integrals against direct integration
along the tooth axis are recorded in the research notes of the LTCA issue; the test
`tests/test_ltca_compliance.py` repeats the direct integration independently.
"""

from __future__ import annotations

import numpy as np
import jax.numpy as jnp

from .._numerics import safe_arcsin, safe_sqrt

#: Sainsot et al. (2004) Table 1: rows L*, M*, P*, Q*; columns A, B, C, D, E, F.
SAINSOT_COEFFICIENTS = np.array(
    [
        [-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045],
        [60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086],
        [-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236],
        [-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904],
    ]
)

#: Palmgren's line contact, steel: delta = PALMGREN * Q**0.9 / L**0.8 (mm, N) for a load Q
#: spread evenly over a contact line of length L.
PALMGREN = 3.84e-5
PALMGREN_EXPONENT = 0.9


def gauss_legendre(n: int):
    """Nodes and weights on [-1, 1] (numpy, static)."""
    return np.polynomial.legendre.leggauss(n)


def _integrate(f, lower, upper, nodes):
    t, w = nodes
    half = 0.5 * (upper - lower)
    mid = 0.5 * (upper + lower)
    a = mid[..., None] + half[..., None] * t
    return half * jnp.sum(w * f(a), axis=-1)


def tooth_compliance(load_angle, half_base_angle, base_radius, root_radius, youngs_modulus, poisson_ratio, nodes):
    """Bending, shear and axial-compression compliance of one tooth (mm²/N each).

    Args:
        load_angle: $\\alpha_1 = s/r_b - \\alpha_2$ (rad).
        half_base_angle: $\\alpha_2$ (rad).
        base_radius, root_radius: $r_b$, $r_f$ (mm).
        youngs_modulus, poisson_ratio: $E$ (MPa), $\\nu$.
        nodes: Gauss–Legendre nodes and weights.
    """
    a1, a2 = load_angle, half_base_angle
    e, nu = youngs_modulus, poisson_ratio
    ratio = root_radius / base_radius
    above = base_radius > root_radius
    upper = jnp.where(above, a2, a2 - safe_sqrt(ratio**2 - 1.0))
    c1, s1 = jnp.cos(a1), jnp.sin(a1)

    def arm(a):
        return (a2[..., None] - a) * jnp.cos(a)

    def thickness(a):
        return jnp.sin(a) + (a2[..., None] - a) * jnp.cos(a)

    def bending(a):
        moment = 1 + c1[..., None] * ((a2[..., None] - a) * jnp.sin(a) - jnp.cos(a))
        return 3 * moment**2 * arm(a) / (2 * e[..., None] * thickness(a) ** 3)

    def shear(a):
        return 1.2 * (1 + nu[..., None]) * arm(a) * c1[..., None] ** 2 / (e[..., None] * thickness(a))

    def axial(a):
        return arm(a) * s1[..., None] ** 2 / (2 * e[..., None] * thickness(a))

    lower = -a1
    kb = _integrate(bending, lower, upper, nodes)
    ks = _integrate(shear, lower, upper, nodes)
    ka = _integrate(axial, lower, upper, nodes)

    # Straight segment between the base and root circles (base-circle convention).
    a3 = safe_arcsin(jnp.sin(a2) / jnp.where(above, ratio, 1.0))
    sa2 = jnp.sin(a2)
    kb_root = ((1 - ratio * c1 * jnp.cos(a3)) ** 3 - (1 - c1 * jnp.cos(a2)) ** 3) / (2 * e * c1 * sa2**3)
    length = jnp.cos(a2) - ratio * jnp.cos(a3)
    ks_root = 1.2 * (1 + nu) * c1**2 * length / (e * sa2)
    ka_root = s1**2 * length / (2 * e * sa2)
    return (
        kb + jnp.where(above, kb_root, 0.0),
        ks + jnp.where(above, ks_root, 0.0),
        ka + jnp.where(above, ka_root, 0.0),
    )


def root_half_angle(teeth, transverse_module, reference_radius, transverse_pressure_angle, dedendum, tool_tip_radius):
    """$\\theta_f$ (rad): half angle of a rack-generated tooth at its root circle."""
    a = transverse_pressure_angle
    flat = jnp.pi * transverse_module / 4 - dedendum * jnp.tan(a) - tool_tip_radius * (1 - jnp.sin(a)) / jnp.cos(a)
    return jnp.pi / teeth - flat / reference_radius


def foundation_compliance(load_angle, base_radius, root_radius, hub_radius, root_angle, youngs_modulus):
    """Sainsot's fillet-foundation compliance (mm²/N)."""
    hf = root_radius / hub_radius
    theta = root_angle
    terms = jnp.stack([1 / theta**2, hf**2, hf / theta, 1 / theta, hf, jnp.ones_like(hf)], -1)
    coeff = jnp.asarray(SAINSOT_COEFFICIENTS, dtype=terms.dtype)
    big_l, big_m, big_p, big_q = (jnp.sum(terms * coeff[i], -1) for i in range(4))
    uf = base_radius / jnp.cos(load_angle) - root_radius
    sf = 2 * root_radius * theta
    ratio = uf / sf
    return jnp.cos(load_angle) ** 2 / youngs_modulus * (
        big_l * ratio**2 + big_m * ratio + big_p * (1 + big_q * jnp.tan(load_angle) ** 2)
    )


def hertz_linear_compliance(youngs_modulus, poisson_ratio):
    """Yang & Sun's load-independent contact compliance per unit length (mm²/N), both
    bodies of the same material: $4(1-\\nu^2)/(\\pi E)$."""
    return 4 * (1 - poisson_ratio**2) / (jnp.pi * youngs_modulus)
