"""Named results: enumerations through jit/vmap, solver outcomes as RESULTS codes, the
`throw` option of `simulate`, and a compiled program without host callbacks."""

import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gearjax as gj
from gearjax import pipeline
from gearjax._solution import RESULTS, SimulationError, enum_message, enum_name
from gearjax.ltca import IsoCompliance
from gearjax.papers.seed001 import paper_optimum
from gearjax.pipeline import check_results as _check_results, program_text
from gearjax.tca import ContactKind
from gearjax.tca._slice_problem import CANDIDATES, contact_kind

TINY = gj.Accuracy(positions_per_pitch=4, face_slices=3)
# A host callback is a custom call whose target names a (Python) callback; the debug
# locations also hold Python function names, so match the op, not the bare word.
CALLBACK = re.compile(r"custom_call @\w*callback")


def test_contact_kind_names_follow_the_candidate_order_under_jit_and_vmap():
    index = jnp.array([[0, 1, 2], [2, 2, 0]])
    kinds = jax.jit(jax.vmap(contact_kind))(index)
    assert enum_name(kinds).tolist() == [
        ["flank", "gear_tip_edge", "pinion_tip_edge"],
        ["pinion_tip_edge", "pinion_tip_edge", "flank"],
    ]
    np.testing.assert_array_equal(np.asarray(kinds == ContactKind.pinion_tip_edge), np.asarray(index) == 2)
    assert [enum_name(c) for c in CANDIDATES] == ["flank", "gear_tip_edge", "pinion_tip_edge"]
    with pytest.raises(ValueError, match="same type"):
        _ = kinds == RESULTS.successful  # items of different enumerations never compare
    with pytest.raises(ValueError, match="concrete"):
        jax.jit(lambda i: jnp.asarray(len(enum_name(contact_kind(i)))))(jnp.asarray(0))


def test_tca_kind_is_an_enumeration_matching_the_edge_contacts(spur_pair):
    """A spur cycle has all three kinds among its slice contacts (the approaching pair's
    gear tip edge, the receding pair's pinion tip edge), while perfect involutes bind on
    their flanks; the names of `kind` agree with the equality masks."""
    tca = gj.simulate(gj.Scene(spur_pair, accuracy=gj.Accuracy(positions_per_pitch=8, face_slices=3))).tca
    names = tca.kind_name
    assert names.shape == tca.valid.shape
    for item in CANDIDATES:
        np.testing.assert_array_equal(np.asarray(tca.kind == item), names == enum_name(item))
    assert set(names[np.asarray(tca.valid)].tolist()) == {"flank", "gear_tip_edge", "pinion_tip_edge"}
    pair_idx, slice_idx = (np.asarray(a) for a in tca.binding)
    assert set(names[np.arange(names.shape[0]), pair_idx, slice_idx].tolist()) == {"flank"}
    assert bool(tca.result == RESULTS.tca_unconverged) == bool(np.asarray(tca.unconverged).any())
    assert tca.action_radius.shape == (2,)
    np.testing.assert_allclose(np.asarray(tca.action_radius), np.asarray(spur_pair.base_radius), rtol=1e-12)


def _loaded(pair, **accuracy):
    return gj.Scene(pair, paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0), accuracy=TINY.replace(**accuracy))


def test_unconverged_ltca_raises_with_throw_and_returns_its_code_without(seed_pair):
    good = gj.simulate(_loaded(seed_pair)).ltca
    assert bool(good.result == RESULTS.successful) and bool(np.all(np.asarray(good.converged)))
    scene = _loaded(seed_pair, contact_max_steps=1)  # one Newton step cannot close the contact
    with pytest.raises(SimulationError, match="contact_max_steps") as info:
        gj.simulate(scene)
    assert isinstance(info.value, RuntimeError) and info.value.stage == "ltca"
    assert "LTCA" in str(info.value) and "throw=False" in str(info.value)
    bad = gj.simulate(scene, throw=False).ltca
    assert bool(bad.result == RESULTS.ltca_unconverged)
    assert enum_name(bad.result) == "ltca_unconverged"
    assert "contact_max_steps" in enum_message(bad.result)
    assert not np.all(np.asarray(bad.converged))


def test_unconverged_tca_candidates_are_a_code_not_an_error(seed_pair):
    scene = gj.Scene(seed_pair, paper_optimum(), accuracy=TINY.replace(newton_max_steps=1))
    tca = gj.simulate(scene).tca  # throw=True raises for LTCA/impact failures only
    assert int(np.asarray(tca.unconverged).sum()) > 0
    assert bool(tca.result == RESULTS.tca_unconverged)
    assert bool(gj.simulate(gj.Scene(seed_pair, paper_optimum(), accuracy=TINY)).tca.result == RESULTS.successful)


def test_unconverged_first_contact_search_raises(seed_pair):
    y = jnp.array([5.9, 6.8, 3800.0, 4300.0, 6.2, 4600.0]) / 1000.0
    scene = gj.Scene(
        seed_pair, gj.FlankModification.from_vector(y), operating=gj.OperatingPoint(torque_Nm=1000.0, speed_rpm=5000.0),
        effects=("impact",), accuracy=gj.Accuracy(positions_per_pitch=16, face_slices=9, impact_max_steps=1),
        pairs=(-2, -1, 0, 1, 2),
    )
    imp = gj.simulate(scene, throw=False).impact
    assert bool(imp.result == RESULTS.first_contact_unconverged)
    with pytest.raises(SimulationError, match="impact_max_steps") as info:
        gj.simulate(scene)
    assert info.value.stage == "impact"


def test_throw_is_skipped_for_traced_results_and_codes_come_out_batched(seed_pair):
    """Under an outer vmap the results are tracers: no check; one code per batch entry (at
    zero torque the contact solve is exact, at 1000 N·m one step is not enough)."""
    scene = _loaded(seed_pair, contact_max_steps=1)

    def code(torque):
        return gj.simulate(eqx.tree_at(lambda s: s.operating.torque, scene, torque)).ltca.result

    codes = jax.vmap(code)(jnp.array([0.0, 1.0e6]))
    assert enum_name(codes).tolist() == ["successful", "ltca_unconverged"]
    np.testing.assert_array_equal(np.asarray(codes == RESULTS.successful), [True, False])


def test_error_if_shows_up_as_a_callback_in_the_lowered_text():
    """What the check below looks for: `eqx.error_if` lowers to a Python CPU callback."""
    text = jax.jit(lambda x: eqx.error_if(x, x < 0, "negative")).lower(jnp.ones(3)).as_text()
    assert CALLBACK.search(text)
    assert not CALLBACK.search(jax.jit(lambda x: 2 * x).lower(jnp.ones(3)).as_text())


@pytest.mark.parametrize(
    "effects, compliance",
    [
        pytest.param((), None, id="tca"),
        pytest.param(("ltca",), IsoCompliance(), id="ltca-iso"),
        pytest.param(("ltca",), None, id="ltca-slice"),
        pytest.param(("impact",), IsoCompliance(), id="impact-iso"),
    ],
)
def test_compiled_simulate_program_has_no_host_callback(seed_pair, effects, compliance):
    """Solver outcomes are result codes, so the program stays cacheable by JAX's
    persistent compilation cache (which never stores a program with a host callback)."""
    scene = gj.Scene(
        seed_pair, paper_optimum(), operating=gj.OperatingPoint(torque_Nm=1000.0 if effects else None, speed_rpm=5000.0),
        compliance=compliance, effects=effects, accuracy=TINY, pairs=(-2, -1, 0, 1, 2),
    )
    assert not CALLBACK.search(program_text(scene))


def test_out_of_range_traced_inputs_give_nan_and_a_named_code(seed_pair):
    """Inside jit the constructors cannot check traced values: a
    modification with y6 = b (the crowning parabola's 0/0) gives NaN outputs and
    `invalid_modification` on every stage, a negative torque `invalid_operating_point`;
    in range, the same compiled program gives the concrete scene's numbers; and a
    concrete out-of-range code raises `SimulationError` naming it."""
    b = float(seed_pair.face_width)
    pairs = gj.Scene(seed_pair, accuracy=TINY).pairs  # the tooth-pair window needs concrete geometry

    def run(y, torque):
        scene = gj.Scene(seed_pair, gj.FlankModification.from_vector(y), operating=gj.OperatingPoint(torque=torque),
                         accuracy=TINY, pairs=pairs)
        result = gj.simulate(scene)  # traced: no check here, the codes come out
        return result.tca.transmission_error, result.ltca.transmission_error, result.tca.result, result.ltca.result

    good = jnp.asarray(paper_optimum().as_vector())
    f = jax.jit(run)
    te, lte, tca_code, ltca_code = f(good, jnp.asarray(1.0e6))
    assert enum_name(tca_code) == "successful" and enum_name(ltca_code) == "successful"
    concrete = gj.simulate(_loaded(seed_pair))
    np.testing.assert_allclose(np.asarray(lte), np.asarray(concrete.ltca.transmission_error), rtol=1e-10)
    for y, torque, name in ((good.at[5].set(b), 1.0e6, "invalid_modification"),
                            (good.at[2].set(-1.0), 1.0e6, "invalid_modification"),
                            (good, -1.0, "invalid_operating_point")):
        te, lte, tca_code, ltca_code = f(y, jnp.asarray(torque))
        assert enum_name(tca_code) == enum_name(ltca_code) == name
        assert np.isnan(np.asarray(te)).all() and np.isnan(np.asarray(lte)).all()
    assert "y6 in [0, the face width)" in enum_message(RESULTS.invalid_modification)
    # the gradient in range stays finite through the guard
    grad = jax.grad(lambda y: jnp.sum(run(y, jnp.asarray(1.0e6))[1]))(good)
    assert np.isfinite(np.asarray(grad)).all()
    # a concrete result with the code raises, naming the stage and the code
    bad = jax.jit(lambda y: gj.simulate(gj.Scene(seed_pair, gj.FlankModification.from_vector(y), accuracy=TINY,
                                                 pairs=pairs)))(
        good.at[5].set(b))
    with pytest.raises(SimulationError, match="invalid_modification") as info:
        _check_results(bad)
    assert info.value.stage == "tca"


def test_the_sweeps_chain_guards_traced_inputs_per_load(seed_pair):
    """The chain the sweeps, the design rows and the objective run (`pipeline.over_loads`,
    `unloaded`/`loaded`/`impact`) guards traced inputs as `simulate` does: y6 = b gives NaN
    and `invalid_modification` at every load, and a negative torque among valid ones names
    `invalid_operating_point` at that load only, leaving the others' numbers alone."""
    b = float(seed_pair.face_width)
    pairs = gj.Scene(seed_pair, accuracy=TINY).pairs

    @jax.jit
    def run(y, torques):
        scene = gj.Scene(seed_pair, gj.FlankModification.from_vector(y), operating=gj.OperatingPoint(torque=1.0e6),
                         accuracy=TINY, pairs=pairs)
        tca, ltca, impact = pipeline.over_loads(scene, torques)
        assert impact is None
        return tca.result, ltca.result, ltca.transmission_error

    good = jnp.asarray(paper_optimum().as_vector())
    tca_code, ltca_code, lte = run(good, jnp.asarray([1.0e6, -1.0]))
    assert enum_name(tca_code) == "successful"
    assert enum_name(ltca_code).tolist() == ["successful", "invalid_operating_point"]
    concrete = gj.simulate(_loaded(seed_pair)).ltca.transmission_error
    np.testing.assert_allclose(np.asarray(lte[0]), np.asarray(concrete), rtol=1e-10)
    assert np.isnan(np.asarray(lte[1])).all()
    tca_code, ltca_code, lte = run(good.at[5].set(b), jnp.asarray([1.0e6, 2.0e6]))
    assert enum_name(tca_code) == "invalid_modification"
    assert enum_name(ltca_code).tolist() == ["invalid_modification"] * 2
    assert np.isnan(np.asarray(lte)).all()
