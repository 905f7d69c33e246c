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
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Array, ArrayLike, Float, Scalar
from .._numerics import as_float, perp2, rotate2, safe_divide, safe_norm


class AbstractGearPair(eqx.Module):
    """A gear pair of one tooth family: geometry of both drive flanks and their placement.

    Concrete families are final classes; they hold their parameters as array fields (so a
    pair can be differentiated and batched with `vmap`) and tooth counts as static fields.
    """

    teeth: eqx.AbstractVar[tuple[int, int]]
    face_width: eqx.AbstractVar[Array]

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

    @property
    @abc.abstractmethod
    def center_distance(self) -> Scalar:
        """Operating centre distance $a$ (mm)."""

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
    def action_radius(self, gear: int) -> Scalar:
        """Radius (mm) converting an angular transmission error of `gear` into a
        displacement along the line of action (the base radius of an involute gear)."""

    @abc.abstractmethod
    def relief_coordinates(self, gear: int) -> tuple[Scalar, Scalar]:
        """Profile coordinates where profile relief is referenced: the start of the active
        profile (mating tip circle) and the tip, $(u_\\text{start}, u_\\text{tip})$ (mm)."""

    # ------------------------------------------------------------------ derived geometry
    @property
    def gear_ratio(self) -> float:
        """$u = z_2 / z_1$."""
        return self.teeth[1] / self.teeth[0]

    def angular_pitch(self, gear: int) -> float:
        """$2\\pi / z$ (rad)."""
        return 2.0 * jnp.pi / self.teeth[gear]

    def center(self, gear: int) -> Float[Array, "2"]:
        """Axis position of `gear` in the fixed frame (mm)."""
        a = self.center_distance
        zero = jnp.zeros_like(a)
        return jnp.stack([zero, zero]) if gear == 0 else jnp.stack([a, zero])

    def local_profile(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        """Drive-flank profile of tooth 0 in the gear's local frame (mm, relative to its axis)."""
        return rotate2(self.placement(gear), self.profile(gear, u))

    def profile_tangent(self, gear: int, u: ArrayLike) -> tuple[Float[Array, "2"], Float[Array, "2"]]:
        """Point and derivative $\\mathrm{d}P/\\mathrm{d}u$ of the local profile."""
        u = as_float(u)
        return jax.jvp(lambda t: self.local_profile(gear, t), (u,), (jnp.ones_like(u),))

    def profile_normal(self, gear: int, u: ArrayLike) -> Float[Array, "2"]:
        """Outward unit normal of the local profile."""
        _, tangent = self.profile_tangent(gear, u)
        return safe_divide(perp2(tangent), safe_norm(tangent)[..., None])

    def lead_rate(self, gear: int, z: ArrayLike) -> Scalar:
        """$\\mathrm{d}\\psi/\\mathrm{d}z$ (rad/mm)."""
        z = as_float(z)
        return jax.jvp(lambda t: self.lead_rotation(gear, t), (z,), (jnp.ones_like(z),))[1]

    def transverse_normal_fraction(self, gear: int, u: ArrayLike, z: ArrayLike) -> Scalar:
        r"""Length of the transverse part of the flank's 3-D unit normal.

        For $r(u, z) = (R(\psi(z)) P(u), z)$ the normal is $\propto (P_u^\perp, \pm(\hat t
        \cdot P)\psi')$, hence $|n_t| = 1/\sqrt{1 + ((\hat t\cdot P)\,\psi')^2}$
        ($\cos\beta_b$ for an involute helicoid). A normal offset $\delta$ of the flank is a
        transverse offset $\delta/|n_t|$ to first order in $\delta$.
        """
        point, tangent = self.profile_tangent(gear, u)
        unit_tangent = safe_divide(tangent, safe_norm(tangent)[..., None])
        lever = jnp.sum(unit_tangent * point, axis=-1) * self.lead_rate(gear, z)
        return 1.0 / jnp.sqrt(1.0 + lever**2)

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

    def slice_point(
        self,
        gear: int,
        u: ArrayLike,
        z: ArrayLike,
        slice_rotation: ArrayLike,
        depth: ArrayLike = 0.0,
    ) -> Float[Array, "2"]:
        """Planar point of the transverse section at `z`, turned by `slice_rotation` (rad,
        lead included), with `depth` (mm, normal) of material removed."""
        local = self.local_profile(gear, u)
        normal = self.profile_normal(gear, u)
        offset = depth / self.transverse_normal_fraction(gear, u, z)
        local = local - offset * normal
        sense = 1.0 if gear == 0 else -1.0
        return self.center(gear) + rotate2(sense * slice_rotation, local)

    def tip_edge(self, gear: int, z: ArrayLike, rotation: ArrayLike = 0.0) -> Float[Array, "3"]:
        """Tip edge of the drive flank (the curve $u = u_\\text{tip}$) at axial `z` (mm)."""
        return self.flank_point(gear, self.profile_limits(gear)[1], z, rotation)

    def face_end(
        self, gear: int, u: ArrayLike, side: int, rotation: ArrayLike = 0.0
    ) -> Float[Array, "3"]:
        """Face-end edge of the drive flank, `side` = -1 (z = -b/2) or +1 (z = +b/2)."""
        return self.flank_point(gear, u, 0.5 * side * self.face_width, rotation)
