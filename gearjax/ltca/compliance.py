r"""Compliance models: the influence matrix of the contact points of one mesh position.

The contact points are the (tooth pair $k$, face slice $j$) points of the TCA. A model
returns, per position, the linear normal compliance matrix $f_{ij}$ (mm/N; block-diagonal
over tooth pairs, since different pairs only interact through the rigid approach) and, for
a nonlinear contact law, per-point coefficients $a_i$ of the extra approach $a_iF_i^{0.9}$.

Transverse tooth compliances $c_t$ (per unit face width) become normal ones through the
slice's transverse normal fraction $|n_t|$ ($\cos\beta_b$ on involute helicoids): a normal
load $F_n$ has the transverse part $F_n|n_t|$ and a transverse deflection $\delta_t$ the
normal part $\delta_t|n_t|$, so $c_n = |n_t|^2c_t$. The contact line crosses a slice of width
$\Delta z$ over $\Delta z/|n_t|$.

* `IsoCompliance`: a uniform stiffness $k_l$ per unit length of contact line, chosen so that
  the mean mesh stiffness of an unmodified pair equals ISO 6336-1's $c_{\gamma\alpha}$:
  with the mean contact-line length $\varepsilon_\alpha b/\cos\beta_b$ the transverse mesh
  stiffness per unit face width is $k_l\varepsilon_\alpha\cos\beta_b$, so
  $k_l = c_{\gamma\alpha}/(\varepsilon_\alpha\cos\beta_b)$. No coupling.
* `SliceCompliance`: per slice, potential-energy bending, shear and axial compliance and
  Sainsot's fillet foundation of both teeth at their own contact positions, plus contact.
  Neighbouring slices of a tooth are coupled by a shear (Pasternak) layer: the tooth's
  stiffness matrix is $K = \mathrm{diag}(k_j\Delta z) + k_cT$, $T = \mathrm{tridiag}(-1, 2, -1)$
  with free ends, $k_c = \bar k\lambda^2/\Delta z$, and its compliance $K^{-1}$ (in closed
  form, `symmetric_tridiagonal_inverse`). A point load then spreads along the face with the decay
  length $\lambda$ (influence $\propto e^{-|y|/\lambda}$) while a uniform load is carried as
  without coupling, so the mean stiffness is unaffected and the face ends come out about
  twice as compliant. This is the Winkler-plus-shear-layer model of Ajmi & Velex (2005,
  Mech. Mach. Theory 40:173); their coupling value is not retrievable, so $\lambda$ is a
  parameter, by default $1.1\,m_n$, the decay length of a Kantorovich–Vlasov plate
  reduction of a loaded involute tooth (our derivation, a lower bound: it ignores shear
  and body deflection).
"""

import abc
from typing import ClassVar

import equinox as eqx
from equinox import AbstractClassVar
import jax
import jax.numpy as jnp

from .._custom_types import Array, Float
from .._validate import check_choice, check_range
from ..geometry._base import SceneFileSpec
from ..geometry.involute_section import AbstractInvolutePair
from ..tca import TCAResult
from ..tca.grid import nested_vmap
from ..units import Material
from .iso import iso_mesh_stiffness
from .tooth_stiffness import (
    PALMGREN,
    foundation_compliance,
    gauss_legendre,
    hertz_linear_compliance,
    root_half_angle,
    tooth_compliance,
)

HERTZ_LAWS = ("palmgren", "linear")


class PointCompliance(eqx.Module):
    """Compliance of the contact points of every position, block by tooth pair.

    Attributes:
        blocks: linear normal compliance of each tooth pair's points (pos, pair, slice,
            slice), mm/N; points of different pairs do not interact.
        nonlinear: coefficients $a_i$ (pos, pair, slice) of the extra approach $a_i F_i^{e}$,
            mm/N^e (zero for a linear model).
        exponent: the exponent $e$ (static; 0.9 for Palmgren's line contact).
        diagonal: the blocks are diagonal (static; no coupling between slices).
    """

    blocks: Float[Array, "pos pair s s"]
    nonlinear: Float[Array, "pos pair s"]
    exponent: float = eqx.field(static=True, default=1.0)
    diagonal: bool = eqx.field(static=True, default=False)

    @property
    def matrix(self) -> Float[Array, "pos n n"]:
        """The dense block-diagonal compliance (pos, n, n), n = pairs × slices (mm/N)."""
        n_pos, n_pair, n_s, _ = self.blocks.shape
        eye = jnp.eye(n_pair, dtype=self.blocks.dtype)
        dense = jnp.einsum("kl,pkij->pkilj", eye, self.blocks)
        return dense.reshape(n_pos, n_pair * n_s, n_pair * n_s)


def _slice_lengths(tca: TCAResult, n_mid: int):
    width = tca.slice_width[..., :n_mid]
    frac = tca.transverse_normal_fraction[..., :n_mid]
    return width, frac


class AbstractCompliance(eqx.Module):
    """A compliance model of the loaded teeth: `AbstractSliceCompliance` for line contact
    (an influence matrix of the face slices' points), or a point-contact model
    (`gearjax.ltca.point_analysis.ToothSectionCompliance`).

    Attributes:
        families: the pair families whose teeth the model describes (class variable);
            `Scene` refuses a loaded scene of any other family.
        scene_file: how scene files name it in `[ltca]` (a `SceneFileSpec`: the value of
            `compliance = "..."`, its description, its option keys), or None.
        min_face_slices: the fewest face slices (`Accuracy.face_slices`) at which the
            model's results converge (class variable); `Scene` refuses a coarser loaded scene.
        needs_float64: the model's results need float64 (class variable); `Scene` refuses a
            loaded float32 scene.
    """

    families: AbstractClassVar[tuple[type, ...]]
    scene_file: ClassVar[SceneFileSpec | None] = None
    min_face_slices: ClassVar[int] = 1
    needs_float64: ClassVar[bool] = False


class AbstractSliceCompliance(AbstractCompliance):
    """A line-contact compliance model: the influence matrix of the contact points (tooth
    pair, face slice) of every position."""

    @abc.abstractmethod
    def __call__(
        self, pair, material: Material, hub_radius, tca: TCAResult, n_mid: int, quadrature: int, weights
    ) -> PointCompliance:
        """Compliance of the contact points of `tca`'s first `n_mid` slices.

        Args:
            pair: the (resolved) gear pair.
            material: both gears' material.
            hub_radius: inner radius of each gear body (mm), shape (2,).
            tca: the unloaded contact.
            n_mid: number of face slices (the midpoints; the face ends are not loaded).
            quadrature: Gauss-Legendre points of the tooth integrals.
            weights: (pos, pair, slice) scale of each slice's contact-line length.
        """


class IsoCompliance(AbstractSliceCompliance):
    """Uniform line stiffness from ISO 6336-1 method B (see the module docstring).

    Call with `(pair, material, hub_radius, tca, n_mid, quadrature, weights)`; `weights`
    scale each slice's contact-line length."""

    families: ClassVar[tuple[type, ...]] = (AbstractInvolutePair,)
    scene_file: ClassVar[SceneFileSpec] = SceneFileSpec("iso", "ISO 6336-1 line stiffness", {}, required=())

    def __call__(self, pair: AbstractInvolutePair, material: Material, hub_radius, tca: TCAResult, n_mid: int, quadrature: int, weights) -> PointCompliance:
        del hub_radius, quadrature
        iso = iso_mesh_stiffness(pair)
        width, frac = _slice_lengths(tca, n_mid)
        # N/(mm um) -> N/mm^2; stiffness per unit length of contact line, normal direction
        line_stiffness = 1000.0 * iso.mesh_stiffness / (pair.transverse_contact_ratio * jnp.cos(pair.base_helix_angle))
        lengths = width / frac * weights
        diagonal = 1.0 / (line_stiffness * lengths)  # (pos, pair, slice)
        del material
        blocks = jnp.where(jnp.eye(diagonal.shape[-1], dtype=bool), diagonal[..., None], 0.0)
        return PointCompliance(blocks, jnp.zeros_like(diagonal), 1.0, diagonal=True)


def pasternak_compliance(compliance_per_width, slice_width, decay_length):
    """Compliance matrix (mm/N) of one tooth's slices coupled by a shear layer.

    $K = \\mathrm{diag}(k_j\\Delta z) + k_cT$, $k_j = 1/c_j$, $k_c = \\bar k\\lambda^2/\\Delta z$,
    $T = \\mathrm{tridiag}(-1, 2, -1)$ with free ends ($T_{11} = T_{nn} = 1$); returns
    $K^{-1}$ (`symmetric_tridiagonal_inverse`).

    Args:
        compliance_per_width: $c_j$ of each slice (mm²/N), shape (n,).
        slice_width: $\\Delta z$ (mm).
        decay_length: $\\lambda$ (mm); 0 uncouples the slices.
    """
    c = compliance_per_width
    k = 1.0 / c
    kc = jnp.mean(k) * decay_length**2 / slice_width
    n = c.shape[-1]
    ends = jnp.zeros(n, dtype=c.dtype).at[0].set(1.0).at[-1].set(1.0)
    diag = k * slice_width + kc * (2.0 - ends)
    return symmetric_tridiagonal_inverse(diag, jnp.broadcast_to(-kc, (n - 1,)).astype(c.dtype))


def symmetric_tridiagonal_inverse(diag, off):
    r"""Inverse of a symmetric, diagonally dominant tridiagonal matrix with off-diagonal
    entries $\le 0$ (the stiffness matrix of springs in a chain), in closed form.

    With the pivots of the elimination from the top, $d_1 = a_1$,
    $d_i = a_i - b_{i-1}^2/d_{i-1}$, and from the bottom, $\delta_n = a_n$,
    $\delta_i = a_i - b_i^2/\delta_{i+1}$ ($a$ the diagonal, $b_i$ the entry $(i, i+1)$):

    $$(K^{-1})_{jj} = \frac{1}{d_j + \delta_j - a_j}, \qquad
    (K^{-1})_{ij} = (K^{-1})_{jj}\prod_{k=i}^{j-1}\left(-\frac{b_k}{d_k}\right)\quad(i < j)$$

    (Meurant, SIAM J. Matrix Anal. Appl. 13 (1992) 707, Theorem 2.3, in ratio form). The
    ratios $-b_k/d_k$ lie in $[0, 1)$, so their products are taken as differences of
    cumulative logarithms: nothing overflows at any size, unlike the recurrences for the
    minors.
    O(n) sequential steps and O(n²) elementwise work: no linear-algebra library call, which
    for many small matrices costs more than the arithmetic (on a GPU, far more).

    Args:
        diag: $a$, shape (n,).
        off: $b$, shape (n - 1,).

    Returns:
        $K^{-1}$, shape (n, n).
    """
    n = diag.shape[-1]
    if n == 1:
        return (1.0 / diag)[:, None]
    b2 = off**2

    def pivots(carry, x):
        d_prev, e_next = carry
        a_fwd, b2_fwd, a_bwd, b2_bwd = x
        d, e = a_fwd - b2_fwd / d_prev, a_bwd - b2_bwd / e_next
        return (d, e), (d, e)

    # one scan runs both eliminations: from the top over rows 2..n, from the bottom over n-1..1
    _, (d_rest, e_rest) = jax.lax.scan(pivots, (diag[0], diag[-1]), (diag[1:], b2, diag[-2::-1], b2[::-1]))
    d = jnp.concatenate([diag[:1], d_rest])
    e = jnp.concatenate([e_rest[::-1], diag[-1:]])
    inverse_diag = 1.0 / (d + e - diag)
    # the products as differences of cumulative logs; a ratio of zero (uncoupled rows) is
    # floored at the smallest normal number, and a product below its square root (1e-154 in
    # float64, 1e-19 in float32: far below rounding) is exactly zero, whatever the sums' rounding
    floor = 0.5 * jnp.log(jnp.finfo(diag.dtype).tiny)
    log_ratio = jnp.log(jnp.maximum(-off / d[:-1], jnp.finfo(diag.dtype).tiny))
    cumulative = jnp.concatenate([jnp.zeros(1, diag.dtype), jnp.cumsum(log_ratio)])
    i = jnp.arange(n)[:, None]
    j = jnp.arange(n)[None, :]
    upper = j >= i
    log_product = jnp.where(upper, cumulative[None, :] - cumulative[:, None], cumulative[:, None] - cumulative[None, :])
    product = jnp.where(log_product > floor, jnp.exp(log_product), 0.0)
    return product * jnp.where(upper, inverse_diag[None, :], inverse_diag[:, None])


class SliceCompliance(AbstractSliceCompliance):
    """Potential-energy slices with a shear-layer coupling and Hertz contact.

    Attributes:
        coupling_length: decay length $\\lambda$ of a point load along the face, in units of
            the normal module (default 1.1); 0 uncouples the slices.
        hertz: "palmgren" (nonlinear line contact, steel) or "linear" (Yang & Sun).

    Palmgren's law $\\delta = c_P Q^{0.9}/L^{0.8}$ ($c_P$ = 3.84e-5, mm and N) holds for a
    load $Q$ spread evenly over a contact line of length $L$, i.e. $\\delta = c_P w^{0.9}
    L^{0.1}$ at the load intensity $w = Q/L$. Each slice applies it at its own intensity
    $w_i = F_i/l_i$ with $L$ the pair's contact line across the whole face
    (`contact_line_length`, $b/\\cos\\beta_b$ for helical gears), so a uniform load gives
    Palmgren's approach whatever the number of slices (exactly for helical gears, to the
    midpoint rule's $\\sum_i l_i \\approx L$ for curvilinear ones): $a_i = c_PL^{0.1}/l_i^{0.9}$.
    (Taking $L = l_i$, the slice's own length, makes the approach of the same load fall as
    $l_i^{0.1}$: 7 % per doubling of the slices, without a limit.)
    """

    families: ClassVar[tuple[type, ...]] = (AbstractInvolutePair,)
    scene_file: ClassVar[SceneFileSpec] = SceneFileSpec(
        "slice", "tooth compliance per face slice: bending, shear, foundation, Hertz",
        {"coupling_length_mn": ("coupling_length", "number", "m_n", 1.0), "hertz": ("hertz", "text", "", 1.0)},
        required=(),
    )

    coupling_length: float = eqx.field(static=True, default=1.1)
    hertz: str = eqx.field(static=True, default="palmgren")

    def __check_init__(self):
        check_range("coupling_length", self.coupling_length, 0.0, 50.0, unit="m_n")
        check_choice("hertz", self.hertz, HERTZ_LAWS)

    def tooth_compliances(self, pair: AbstractInvolutePair, material: Material, hub_radius, gear: int, roll_length, quadrature: int):
        """Bending, shear, axial and foundation compliance (mm²/N) of `gear`'s tooth for a
        load at roll length `roll_length` (mm), per unit face width."""
        rb = pair.base_radius[..., gear]
        rf = pair.root_radius[..., gear]
        a2 = pair.half_base_thickness_angle(gear)
        lo, hi = pair.profile_limits(gear)
        s = jnp.clip(roll_length, lo, hi)
        a1 = s / rb - a2
        e, nu = material.youngs_modulus, material.poisson_ratio
        kb, ks, ka = tooth_compliance(a1, a2, rb, rf, e, nu, gauss_legendre(quadrature))
        theta = root_half_angle(
            pair.teeth[gear],
            pair.transverse_module,
            pair.reference_radius[..., gear],
            pair.transverse_pressure_angle,
            pair.dedendum_coefficient[..., gear] * pair.normal_module,
            pair.root_radius_coefficient[..., gear] * pair.normal_module,
        )
        kf = foundation_compliance(a1, rb, rf, hub_radius[..., gear], theta, e)
        return kb, ks, ka, kf

    def __call__(self, pair: AbstractInvolutePair, material: Material, hub_radius, tca: TCAResult, n_mid: int, quadrature: int, weights) -> PointCompliance:
        """Compliance of every point; `weights` (pos, pair, slice) scale each slice's
        contact-line length (the tooth slice itself always spans the whole cell)."""
        width, frac = _slice_lengths(tca, n_mid)  # (slice,), (pos, pair, slice)
        s1 = tca.pinion_parameter[..., :n_mid]
        s2 = tca.gear_parameter[..., :n_mid]
        c1 = sum(self.tooth_compliances(pair, material, hub_radius, 0, s1, quadrature))
        c2 = sum(self.tooth_compliances(pair, material, hub_radius, 1, s2, quadrature))
        lam = self.coupling_length * pair.normal_module

        dz = jnp.mean(width)

        def block(c1k, c2k, fk):
            transverse = pasternak_compliance(c1k, dz, lam) + pasternak_compliance(c2k, dz, lam)
            return fk[:, None] * transverse * fk[None, :]

        blocks = nested_vmap(block, [(0, 0, 0), (0, 0, 0)], c1, c2, frac)  # (pos, pair, slice, slice)
        lengths = width / frac * weights
        contact = hertz_linear_compliance(material.youngs_modulus, material.poisson_ratio) / lengths
        if self.hertz == "linear":
            blocks = blocks + jnp.where(jnp.eye(contact.shape[-1], dtype=bool), contact[..., None], 0.0)
            nonlinear = jnp.zeros_like(lengths)
            exponent = 1.0
        else:
            # Palmgren's law for the pair's whole contact line, $\delta = c_P w^{0.9}L^{0.1}$
            # at the slice's load intensity $w = F_i/l_i$: $a_i = c_PL^{0.1}/l_i^{0.9}$.
            # With $L = l_i$ ($a_i = c_P/l_i^{0.8}$, as before) the approach of a uniform load
            # fell as $l_i^{0.1}$ when the slices were refined and never converged.
            nonlinear = PALMGREN * pair.contact_line_length[..., None, None, None] ** 0.1 / lengths**0.9
            exponent = 0.9
        return PointCompliance(blocks, nonlinear, exponent, diagonal=self.coupling_length == 0.0)
