"""The declared family interface, resolved geometry and the open compliance interface.

Cheap checks (no contact solve is compiled): what a family must declare, that a resolved
pair carries no nested Newton solve, and that `Scene` checks the declared capabilities.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gearjax as gj
from gearjax.geometry import (
    AbstractFlankPair,
    AbstractGearPair,
    AbstractInvolutePair,
    CurvilinearGearPair,
    DoubleArcGearPair,
    DoubleArcZone,
    InvoluteGearPair,
)
from gearjax.geometry import involute_section
from gearjax.geometry._base import _derived_names
from gearjax.papers.seed001 import paper_optimum
from gearjax.ltca import AbstractSliceCompliance, IsoCompliance, SliceCompliance

FAMILIES = (InvoluteGearPair, CurvilinearGearPair, DoubleArcGearPair, DoubleArcZone)


def test_a_family_that_forgets_a_capability_cannot_be_instantiated():
    class Forgetful(AbstractFlankPair):
        pass

    with pytest.raises(TypeError, match="conjugate_slices|screen_edges|linear_lead|supported_effects"):
        Forgetful()


@pytest.mark.parametrize("family", FAMILIES + (AbstractInvolutePair, AbstractFlankPair, IsoCompliance, SliceCompliance))
def test_no_concrete_method_is_overridden(family):
    """Abstract or final (equinox's rule): a method that a base class implements is not
    implemented again below it; a family without a closed form calls the generic function
    (`geometry._base.generic_*`) from its own method instead."""
    for name, value in vars(family).items():
        if not callable(value) or name.startswith("__"):
            continue
        for base in family.__mro__[1:]:
            inherited = vars(base).get(name)
            if inherited is not None and callable(inherited):
                assert getattr(inherited, "__isabstractmethod__", False), f"{family.__name__}.{name} overrides {base.__name__}.{name}"


@pytest.mark.parametrize("family", FAMILIES)
def test_concrete_families_are_final(family):
    """No concrete family subclasses another: every base is abstract."""
    for base in family.__mro__[1:]:
        if issubclass(base, AbstractGearPair):
            assert base.__name__.startswith("Abstract"), (family.__name__, base.__name__)


def test_single_zone_families_are_their_own_zone(seed_pair):
    assert seed_pair.contact_zones() == (seed_pair,)
    pair = DoubleArcGearPair((24, 24), 4.0, 15.0, 55.0)
    zones = pair.contact_zones()
    assert [type(z) for z in zones] == [DoubleArcZone, DoubleArcZone]
    assert [z.zone for z in zones] == [0, 1]
    # the zones are the same teeth: same placement, different working arcs
    assert float(zones[0].placement(1)) == float(zones[1].placement(1))
    assert float(zones[0].profile(0, zones[0].profile_limits(0)[1])[0]) != pytest.approx(
        float(zones[1].profile(0, zones[1].profile_limits(0)[1])[0])
    )
    with pytest.raises(ValueError, match="zone"):
        DoubleArcZone(pair, 2)


def _count_while(fn, *args):
    text = str(jax.make_jaxpr(fn)(*args))
    return text.count("while[")


def test_resolved_pair_carries_no_nested_solve(seed_pair):
    """The working pressure angle is an inverse-involute Newton solve (a while loop);
    a resolved pair reads it, so its flank points trace without any loop."""
    shifted = InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0, profile_shift=(0.3, -0.1))

    def point(pair):
        return pair.flank_point(0, 20.0, 3.0, 0.01)

    assert _count_while(point, shifted) >= 1
    assert _count_while(lambda p: point(p.resolve()), shifted) >= 1  # solved once, here
    resolved = shifted.resolve()
    assert _count_while(point, resolved) == 0
    assert jnp.allclose(point(resolved), point(shifted), rtol=0, atol=1e-12)
    assert resolved.resolve() is resolved


def test_a_scene_resolves_its_pair_once_for_its_checks_and_keeps_it_as_given(seed_pair, monkeypatch):
    """`resolve()` gives every derived quantity the value of its formula on the unresolved
    pair, bit for bit (every family); a scene's checks (modification fit, pair window, hub
    radius) read one resolution of its pair, so they solve its working pressure angle once,
    and the scene keeps the pair as given; built inside `jit` around a concrete pair, a
    scene asks for its pairs."""
    pairs = (
        InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0, profile_shift=(0.3, -0.1)),
        CurvilinearGearPair((20, 30), 2.0, 20.0, 20.0, 60.0),
        DoubleArcGearPair((24, 24), 4.0, 15.0, 55.0, 0.0),
    )
    for pair in pairs:
        resolved = pair.resolve()
        names = _derived_names(type(pair))
        assert names and set(resolved.derived) == set(names)
        for name in names:
            assert np.array_equal(resolved.derived[name], getattr(pair, name)), name
    solves = []  # the working pressure angle's inverse-involute solves
    solve = involute_section.inverse_involute
    monkeypatch.setattr(involute_section, "inverse_involute", lambda value: solves.append(value) or solve(value))
    scene = gj.Scene(seed_pair, paper_optimum(), operating=gj.OperatingPoint(torque_Nm=100.0))
    assert len(solves) == 1 and scene.pair is seed_pair
    with pytest.raises(ValueError, match="pairs must be given"):
        jax.jit(lambda x: gj.Scene(seed_pair).hub_radius + x)(0.0)


def test_gradient_through_resolve_matches_finite_difference():
    """d a / d x1 through `resolve()` against a central difference of the closed form
    a = a0 cos(alpha_t)/cos(alpha_wt)."""

    def distance(x1):
        pair = InvoluteGearPair((29, 71), 5.0, 20.0, 27.5, 42.0, profile_shift=(x1, 0.0))
        return pair.resolve().placement(1) + pair.resolve().center_distance

    x, h = 0.2, 1e-6
    grad = float(jax.grad(distance)(x))
    fd = (float(distance(x + h)) - float(distance(x - h))) / (2 * h)
    assert grad == pytest.approx(fd, rel=1e-6)


def test_scene_checks_declared_stages():
    pair = DoubleArcGearPair((24, 24), 4.0, 15.0, 55.0)
    assert pair.supported_effects == frozenset({"ltca", "impact"})
    zone = pair.contact_zones()[0]
    with pytest.raises(ValueError, match="not available for DoubleArcZone.*rigid TCA only: load the DoubleArcGearPair"):
        gj.Scene(zone, effects=("impact",), operating=gj.OperatingPoint(torque=1.0e5))

    class RigidOnly:
        supported_effects = frozenset()

    # the stage itself reads the same declaration (it refuses before using its other inputs)
    with pytest.raises(ValueError, match="RigidOnly supports the rigid TCA only"):
        gj.loaded_contact_analysis(RigidOnly(), None, 1.0e5, None)


def test_any_abstract_compliance_is_accepted_and_others_refused(spur_pair):
    class Stiff(AbstractSliceCompliance):
        families = (AbstractInvolutePair,)

        def __call__(self, *args):
            return IsoCompliance()(*args)

    scene = gj.Scene(spur_pair, operating=gj.OperatingPoint(torque=1.0e5), compliance=Stiff())
    assert isinstance(scene.compliance, Stiff)
    with pytest.raises(ValueError, match="compliance must be a compliance model"):
        gj.Scene(spur_pair, operating=gj.OperatingPoint(torque=1.0e5), compliance="iso")

    class SpurOnly(Stiff):
        families = (CurvilinearGearPair,)

    with pytest.raises(ValueError, match="models the teeth of CurvilinearGearPair only"):
        gj.Scene(spur_pair, operating=gj.OperatingPoint(torque=1.0e5), compliance=SpurOnly())
