r"""The tooth-family interface that the contact analysis works on.

Frames (all lengths mm, angles rad):

* Fixed frame $S_f$: the pinion (gear 1) axis is the z axis through $O_1 = (0, 0, 0)$, the
  gear (gear 2) axis is parallel through $O_2 = (a, 0, 0)$; $z = 0$ is mid-face.
* The pinion turns counter-clockwise by $\varphi_1$ about $+z$, the gear clockwise by
  $\varphi_2$ (external pair; $\varphi_2 = \varphi_1 z_1/z_2$ for conjugate action).
* Each gear has a local frame that coincides with $S_f$ (translated to its centre) at zero
  rotation. Its *drive flank* is the counter-clockwise-facing flank of a tooth: the
  pinion's leading flank and the gear's trailing flank, which the pinion pushes.

A family provides, for gear $i \in \{0, 1\}$:

* `profile(i, u)`: the transverse drive-flank profile of one tooth whose centre line is the
  local +x axis, as a planar curve $P_i(u)$ (mm). The parameter $u$ (mm) grows from root to
  tip; the outward unit normal (out of the tooth, towards the mate) is the tangent
  $\mathrm{d}P/\mathrm{d}u$ rotated by +90 degrees.
* `profile_limits(i)`: the active flank $[u_\text{form}, u_\text{tip}]$.
* `lead_rotation(i, z)`: the extra rotation (in the gear's sense of rotation) of the
  transverse profile at axial position $z$, e.g. $z \tan\beta / r$ for a helical gear.
* `placement(i)`: the angle of tooth 0's centre line at zero rotation (local frame).

Everything else (3-D surface $r(u, z)$, unit normals, tip and face-end edges, modified
flanks) is derived here, so the contact analysis needs nothing family-specific.

Two levels, both declared here:

* `AbstractGearPair`: what a user holds and a `Scene` takes. It declares the stages the
  family supports (`supported_effects`) and its contact zones (`contact_zones()`, one
  surface pair per zone of simultaneous contact; `contact_zone(index)` for a traced index).
* `AbstractFlankPair`: one zone's pair of drive flanks, the interface above, on which the
  TCA works. It declares how the TCA may treat it: `conjugate_slices` (plane-of-action
  fast path), `screen_edges` (edge candidates screened by the conjugate contact) and
  `linear_lead` (peak refinement of edge candidates between slices).

A family that leaves any of these undeclared cannot be instantiated (equinox names the
missing attributes): nothing downstream probes a pair with `getattr`/`hasattr`.

**Derived geometry resolved once.** Quantities that depend on the pair only (working
pressure angle, centre distance, radii, placements) are `derived` properties;
`pair.resolve()` evaluates them once into a pair that carries their values (`derived`),
so the contact solves' residuals read constants (lineax's `init`/`compute` split).
Gradients flow through `resolve()`. A resolved pair keeps the values it was resolved
with: edit an unresolved one (e.g. with `eqx.tree_at`).
"""

import abc
import dataclasses
import functools
from collections.abc import Callable
from typing import ClassVar

import equinox as eqx
from equinox import AbstractClassVar, AbstractVar
import jax
import jax.numpy as jnp

from .._custom_types import Array, ArrayLike, Float, Scalar
from .._numerics import as_float, perp2, rotate2, safe_divide, safe_norm

#: Stages beyond the rigid TCA that a family may support.
EFFECTS = ("ltca", "impact")


@dataclasses.dataclass(frozen=True)
class SceneFileSpec:
    """How a family is written in a scene file's `[pair]` section (`gearjax.io.scene_file`
    reads it; adding a family adds no code there).

    Attributes:
        family: the value of `family = "..."`.
        description: the pair in an engineer's words (reports).
        keys: file key -> (constructor keyword, kind, unit in the file, factor to engine
            units); kind is "teeth" (two integers), "number", "number_or_pair" (one
            number, or one per gear) or "text"; the constructor's default is the key's.
        required: keys a file must give.
        fixed: keys other families accept but this one fixes, with why (`is <why> for ...`).
    """

    family: str
    description: str
    keys: dict
    required: tuple[str, ...] = ("teeth", "normal_module")
    fixed: tuple[tuple[str, ...], str] = ((), "")


def derived(method):
    """A property of a gear pair that depends on its parameters only: the formula on an
    unresolved pair, `pair.derived` on a pair returned by `resolve()`."""
    name = method.__name__

    @functools.wraps(method)
    def getter(self):
        cache = self.derived
        if cache is not None and name in cache:
            return cache[name]
        return method(self)

    getter.is_derived = True
    return property(getter)


def _derived_names(cls) -> tuple[str, ...]:
    names = []
    for klass in reversed(cls.__mro__):
        for name, value in vars(klass).items():
            if isinstance(value, property) and getattr(value.fget, "is_derived", False) and name not in names:
                names.append(name)
    return tuple(names)


class AbstractGearPair(eqx.Module):
    """A gear pair of one tooth family, as a `Scene` holds it.

    Concrete families are final classes; they hold their parameters as array fields (so a
    pair can be differentiated and batched with `vmap`) and tooth counts as static fields.

    Declared capabilities (class variables every family sets):
        supported_effects: the stages beyond the rigid TCA it supports, a subset of
            `EFFECTS` = ("ltca", "impact"); `Scene` refuses the others.
        effects_note: what to use instead of an unsupported stage (for the error message).
        zone_names: the contact zones' names, in the order of `contact_zones()`.
        scene_file: its `[pair]` keys in scene files (`SceneFileSpec`), or None for a
            family that scene files cannot name.
    """

    teeth: AbstractVar[tuple[int, int]]
    face_width: AbstractVar[Array]
    derived: AbstractVar[dict[str, Array] | None]

    supported_effects: AbstractClassVar[frozenset[str]]
    effects_note: ClassVar[str] = ""
    scene_file: ClassVar[SceneFileSpec | None] = None
    zone_names: ClassVar[tuple[str, ...]] = ("drive flank",)

    @abc.abstractmethod
    def contact_zones(self) -> "tuple[AbstractFlankPair, ...]":
        """The pair's zones of simultaneous contact, one flank pair each, in the order of
        `TCAResult.pair_zone`; `(self,)` for single-zone families."""

    @abc.abstractmethod
    def contact_zone(self, index) -> "AbstractFlankPair":
        """Zone `index` of `contact_zones()`; also for an integer array `index`, so that one
        `vmap` over the zone index analyses every zone in one trace."""

    @property
    @abc.abstractmethod
    def center_distance(self) -> Scalar:
        """Operating centre distance $a$ (mm)."""

    @property
    @abc.abstractmethod
    def root_radius(self) -> Float[Array, "2"]:
        """Root radius $r_f$ of each gear (mm), shape (..., 2)."""

    @abc.abstractmethod
    def action_radius(self, gear: int) -> Scalar:
        """Radius (mm) converting an angular transmission error of `gear` into a
        displacement along the line of action (the base radius of an involute gear)."""

    @abc.abstractmethod
    def geometry_report(self) -> dict[str, ArrayLike]:
        """Named geometry quantities for reports: keys carry their unit as a suffix
        (`_mm`, `_deg`, `_um`; none for ratios), values are arrays (per gear: shape 2)."""

    # ------------------------------------------------------------------ derived geometry
    @abc.abstractmethod
    def resolve(self):
        """This pair with every `derived` quantity evaluated once (see the module
        docstring); a resolved pair is returned as it is. Families with derived quantities
        of their own return `resolve_derived(self)`."""

    @property
    def gear_ratio(self) -> float:
        """$u = z_2 / z_1$."""
        return self.teeth[1] / self.teeth[0]

    def angular_pitch(self, gear: int) -> float:
        """$2\\pi / z$ (rad)."""
        return 2.0 * jnp.pi / self.teeth[gear]

    def action_radii(self) -> Float[Array, "2"]:
        """`action_radius` of both gears, shape (..., 2) (mm)."""
        return jnp.stack([self.action_radius(0), self.action_radius(1)], -1)

    def center(self, gear: int) -> Float[Array, "2"]:
        """Axis position of `gear` in the fixed frame (mm)."""
        a = self.center_distance
        zero = jnp.zeros_like(a)
        return jnp.stack([zero, zero]) if gear == 0 else jnp.stack([a, zero])


class AbstractFlankPair(AbstractGearPair):
    """The drive flanks of one contact zone: the interface the TCA works on.

    Declared capabilities (class variables every family sets):
        conjugate_slices: each transverse slice is a conjugate pair (line contact on the
            plane of action): the `plane_of_action` TCA applies.
        screen_edges: `contact_guess` follows the contact, so tip-edge candidates are
            solved only near the ends of the conjugate contact; otherwise wherever the
            flank candidate is.
        linear_lead: `lead_rotation` is linear in $z$, so the TCA's peak refinement
            between slices also applies to edge candidates.
    """

    conjugate_slices: AbstractClassVar[bool]
    screen_edges: AbstractClassVar[bool]
    linear_lead: AbstractClassVar[bool]

    def contact_zones(self) -> "tuple[AbstractFlankPair, ...]":
        """A flank pair is its own single zone."""
        return (self,)

    def contact_zone(self, index) -> "AbstractFlankPair":
        return self

    # ------------------------------------------------------------------ family interface
    @abc.abstractmethod
    def profile(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        """Drive-flank transverse profile of a tooth centred on the local +x axis (mm)."""

    @abc.abstractmethod
    def profile_limits(self, gear: int) -> tuple[Scalar, Scalar]:
        """Active flank $[u_\\text{form}, u_\\text{tip}]$ of `gear` (mm)."""

    @abc.abstractmethod
    def lead_rotation(self, gear: int, z: ArrayLike) -> Scalar:
        """Rotation (rad, in the gear's turning sense) of the transverse profile at `z` (mm)."""

    @abc.abstractmethod
    def placement(self, gear: int) -> Scalar:
        """Angle (rad, counter-clockwise, local frame) of tooth 0's centre line."""

    @abc.abstractmethod
    def contact_guess(self, angle: ArrayLike) -> tuple[Scalar, Scalar]:
        """Nominal flank contact $(u_1, u_2)$ of a slice whose pinion tooth is turned by
        `angle` (rad) from the reference position, used to start the Newton solves."""

    @abc.abstractmethod
    def parameter_domain(self, gear: int) -> tuple[Scalar, Scalar]:
        """Range of $u$ on which `profile` is well defined (mm); Newton iterates are clipped
        to it."""

    @abc.abstractmethod
    def parameter_at_radius(self, gear: int, radius: ArrayLike) -> Scalar:
        """Profile parameter $u$ of the flank point at distance `radius` (mm) from the
        gear axis (an approximation is enough: it only starts Newton solves)."""

    @abc.abstractmethod
    def relief_coordinates(self, gear: int) -> tuple[Scalar, Scalar]:
        """Profile coordinates where profile relief is referenced: the start of the active
        profile (mating tip circle) and the tip, $(u_\\text{start}, u_\\text{tip})$ (mm)."""

    # ------------------------------------------------------------------ derived geometry
    def local_profile(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        """Drive-flank profile of tooth 0 in the gear's local frame (mm, relative to its axis)."""
        return rotate2(self.placement(gear), self.profile(gear, u))

    @abc.abstractmethod
    def profile_tangent(self, gear: int, u: ArrayLike) -> tuple[Float[Array, "2"], Float[Array, "2"]]:
        """Point and derivative $\\mathrm{d}P/\\mathrm{d}u$ of the local profile (closed form,
        or `generic_profile_tangent`)."""

    @abc.abstractmethod
    def profile_normal(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        """Outward unit normal of the local profile (closed form, or `generic_profile_normal`)."""

    def lead_rate(self, gear: int, z: ArrayLike) -> Scalar:
        """$\\mathrm{d}\\psi/\\mathrm{d}z$ (rad/mm)."""
        z = as_float(z)
        return jax.jvp(lambda t: self.lead_rotation(gear, t), (z,), (jnp.ones_like(z),))[1]

    @abc.abstractmethod
    def transverse_normal_fraction(self, gear: int, u: ArrayLike, z: ArrayLike) -> Scalar:
        """Length $|n_t|$ of the transverse part of the flank's 3-D unit normal (closed form,
        or `generic_transverse_normal_fraction`): a normal offset $\\delta$ of the flank is a
        transverse offset $\\delta/|n_t|$ to first order in $\\delta$."""

    def flank_point(
        self,
        gear: int,
        u: ArrayLike,
        z: ArrayLike,
        rotation: ArrayLike,
        depth: ArrayLike = 0.0,
    ) -> Float[Array, "3"]:
        """Point of the (modified) drive flank in the fixed frame (mm).

        Args:
            gear: 0 pinion, 1 gear.
            u: profile parameter (mm).
            z: axial position from mid-face (mm).
            rotation: rotation of the tooth from its reference position (rad, in the gear's
                turning sense), *excluding* the lead rotation at `z`, which is added here.
            depth: material removed normal to the flank (mm); modifications and errors.
        """
        planar = self.slice_point(gear, u, z, rotation + self.lead_rotation(gear, z), depth)
        return jnp.concatenate([planar, jnp.reshape(as_float(z), (1,))])

    @abc.abstractmethod
    def slice_point(
        self,
        gear: int,
        u: ArrayLike,
        z: ArrayLike,
        slice_rotation: ArrayLike,
        depth: ArrayLike = 0.0,
    ) -> Float[Array, "2"]:
        """Planar point of the transverse section at `z`, turned by `slice_rotation` (rad,
        lead included), with `depth` (mm, normal) of material removed (closed form, or
        `generic_slice_point`)."""

    @abc.abstractmethod
    def slice_point_tangent(
        self,
        gear: int,
        u: ArrayLike,
        z: ArrayLike,
        slice_rotation: ArrayLike,
        depth: Callable[[Array], Array] | None = None,
    ) -> tuple[Float[Array, "2"], Float[Array, "2"]]:
        """`slice_point` and its derivative $\\mathrm{d}X/\\mathrm{d}u$ (mm/mm), the material
        depth a function `depth(u)` (mm) of the profile parameter (None: unmodified); closed
        form, or `generic_slice_point_tangent` (the TCA's Newton residuals hold these
        tangents, so every operation here is differentiated twice more in a solve)."""

    def tip_edge(self, gear: int, z: ArrayLike, rotation: ArrayLike = 0.0) -> Float[Array, "3"]:
        """Tip edge of the drive flank (the curve $u = u_\\text{tip}$) at axial `z` (mm)."""
        return self.flank_point(gear, self.profile_limits(gear)[1], z, rotation)

    def face_end(
        self, gear: int, u: ArrayLike, side: int, rotation: ArrayLike = 0.0
    ) -> Float[Array, "3"]:
        """Face-end edge of the drive flank, `side` = -1 (z = -b/2) or +1 (z = +b/2)."""
        return self.flank_point(gear, u, 0.5 * side * self.face_width, rotation)


# ---------------------------------------------------------------------------------------
# Generic implementations of the flank methods, by differentiation of the family's profile
# and lead: a family without closed forms returns these from its methods.
def resolve_derived(pair):
    """`pair` with every `derived` quantity evaluated once (see the module docstring); a
    resolved pair is returned as it is."""
    if pair.derived is not None:
        return pair
    resolved = eqx.tree_at(lambda p: p.derived, pair, {}, is_leaf=lambda x: x is None)
    for name in _derived_names(type(pair)):
        # Each quantity is evaluated on the partly resolved pair, so it reuses the
        # ones before it (the working pressure angle is solved once).
        value = getattr(resolved, name)
        resolved = eqx.tree_at(lambda p: p.derived, resolved, {**resolved.derived, name: value})
    return resolved


def generic_profile_tangent(pair: AbstractFlankPair, gear: int, u: ArrayLike):
    """Point and derivative $\\mathrm{d}P/\\mathrm{d}u$ of the local profile, by forward-mode
    differentiation of `local_profile`."""
    u = as_float(u)
    return jax.jvp(lambda t: pair.local_profile(gear, t), (u,), (jnp.ones_like(u),))


def generic_profile_normal(pair: AbstractFlankPair, gear: int, u: ArrayLike) -> Float[Array, "2"]:
    """Outward unit normal of the local profile, from `profile_tangent`."""
    _, tangent = pair.profile_tangent(gear, u)
    return safe_divide(perp2(tangent), safe_norm(tangent)[..., None])


def generic_transverse_normal_fraction(pair: AbstractFlankPair, gear: int, u: ArrayLike, z: ArrayLike) -> Scalar:
    r"""Length of the transverse part of the flank's 3-D unit normal.

    For $r(u, z) = (R(\psi(z)) P(u), z)$ the normal is $\propto (P_u^\perp, \pm(\hat t
    \cdot P)\psi')$, hence $|n_t| = 1/\sqrt{1 + ((\hat t\cdot P)\,\psi')^2}$
    ($\cos\beta_b$ for an involute helicoid).
    """
    point, tangent = pair.profile_tangent(gear, u)
    unit_tangent = safe_divide(tangent, safe_norm(tangent)[..., None])
    lever = jnp.sum(unit_tangent * point, axis=-1) * pair.lead_rate(gear, z)
    return 1.0 / jnp.sqrt(1.0 + lever**2)


def generic_slice_point(pair: AbstractFlankPair, gear: int, u: ArrayLike, z: ArrayLike, slice_rotation: ArrayLike,
                        depth: ArrayLike = 0.0) -> Float[Array, "2"]:
    """`AbstractFlankPair.slice_point` from the local profile, its normal and
    `transverse_normal_fraction`; a `depth` of Python 0 traces the profile point alone (the
    normal and the fraction each trace the profile's derivative)."""
    local = pair.local_profile(gear, u)
    if not (isinstance(depth, (int, float)) and depth == 0):
        local = local - depth / pair.transverse_normal_fraction(gear, u, z) * pair.profile_normal(gear, u)
    sense = 1.0 if gear == 0 else -1.0
    return pair.center(gear) + rotate2(sense * slice_rotation, local)


def generic_slice_point_tangent(pair: AbstractFlankPair, gear: int, u: ArrayLike, z: ArrayLike,
                                slice_rotation: ArrayLike, depth: Callable[[Array], Array] | None = None):
    """`AbstractFlankPair.slice_point_tangent` by forward-mode differentiation of
    `slice_point`."""
    u = as_float(u)
    depth = (lambda t: 0.0) if depth is None else depth
    return jax.jvp(lambda t: pair.slice_point(gear, t, z, slice_rotation, depth(t)), (u,), (jnp.ones_like(u),))
