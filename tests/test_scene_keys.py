"""The scene-file reference (`gearjax.io.scene_keys`) against the readers it documents:
the same keys, the declared bounds and the declared defaults."""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import equinox as eqx
import pytest

from gearjax.io import scene_file
from gearjax.io.scene_keys import SceneKey, reference, section_keys
from gearjax.optimize import settings

SECTIONS = section_keys()
READERS = {
    "modification": set(scene_file._MOD_KEYS),
    "gear_modification": set(scene_file._MOD_KEYS),
    "errors": set(scene_file._ERROR_KEYS),
    "operating": scene_file._OPERATING_KEYS,
    "material": scene_file._MATERIAL_KEYS,
    "ltca": scene_file._LTCA_KEYS,
    "impact": scene_file._IMPACT_KEYS,
    "analysis": scene_file._ANALYSIS_KEYS,
    "optimize": settings._KEYS,
}
BASE = tomllib.loads(scene_file.DEFAULT_SCENE_TOML)
#: Keys whose value is a list of numbers: how one number is written as that list.
LISTS = {"inertia_kg_m2": lambda v: [v, v], "loads_Nm": lambda v: [v], "load_weights": lambda v: [v],
         "speeds_rpm": lambda v: [v]}
CASES = [(section, key) for section, keys in SECTIONS.items() for key in keys]


def _read(data: dict, section: str):
    """What the section's reader makes of the file (the `[optimize]` settings, or the scene)."""
    if section == "optimize":
        return settings.OptimizeSettings.from_dict(data.get("optimize", {}))
    return scene_file.scene_from_dict(data)


def _with(section: str, key: str, value) -> dict:
    data = copy.deepcopy(BASE)
    table = data.setdefault(section, {})
    if value is _ABSENT:
        table.pop(key, None)
    else:
        table[key] = value
    return data


_ABSENT = object()


def test_the_reference_declares_exactly_the_keys_the_readers_accept():
    assert set(SECTIONS) == set(scene_file._SECTIONS) - {"pair"}
    for section, keys in SECTIONS.items():
        assert {k.key for k in keys} == set(READERS[section]), section


_RELIEF = {"root_relief_um": 8.0, "tip_relief_um": 9.0, "root_relief_length": 3.0, "tip_relief_length": 4.0,
           "crowning_um": 7.0, "unmodified_length": 5.0}
#: A valid value other than the default file's (or the default) for every declared key of
#: the scene's sections, written here by hand: the scene readers take their key sets from the
#: declarations, so a declared key that no reader uses would otherwise go unnoticed.
CHANGED = {
    **{("modification", k): v for k, v in _RELIEF.items()},
    **{("gear_modification", k): v for k, v in _RELIEF.items()},
    ("errors", "base_pitch_deviation_um"): 1.0, ("errors", "pitch_deviation_um"): 2.0,
    ("errors", "misalignment_um"): 3.0,
    ("operating", "torque_Nm"): 500.0, ("operating", "speed_rpm"): 3000.0,
    ("material", "youngs_modulus"): 2.1e5, ("material", "poisson_ratio"): 0.29, ("material", "density"): 7.8e-9,
    ("ltca", "compliance"): "iso", ("ltca", "coupling_length_mn"): 2.0, ("ltca", "hertz"): "linear",
    ("ltca", "hub_radius"): 60.0, ("ltca", "extended_contact"): False,
    ("impact", "inertia_kg_m2"): [0.1, 0.2],
    ("analysis", "accuracy"): "fast", ("analysis", "effects"): [], ("analysis", "tca_method"): "plane_of_action",
    ("analysis", "positions_per_pitch"): 20, ("analysis", "face_slices"): 11, ("analysis", "dtype"): "float32",
    ("analysis", "pitches"): 2,
}


def test_every_declared_scene_key_has_a_changed_value_to_try():
    declared = {(section, k.key) for section, keys in SECTIONS.items() if section != "optimize" for k in keys}
    assert declared == set(CHANGED)


@pytest.mark.parametrize("case", sorted(CHANGED), ids=lambda c: f"{c[0]}.{c[1]}")
def test_each_declared_scene_key_changes_the_scene(case):
    """The reader uses every key it accepts: another value gives another `Scene`."""
    section, key = case
    base = scene_file.scene_from_dict(copy.deepcopy(BASE))
    changed = scene_file.scene_from_dict(_with(section, key, CHANGED[case]))
    assert not bool(eqx.tree_equal(changed, base)), f"[{section}] {key} = {CHANGED[case]!r} left the scene as it was"


def _id(case):
    section, key = case
    return f"{section}.{key.key}"


def _check_bound(section: str, key: SceneKey) -> None:
    """At an inclusive bound (or just inside an exclusive one) the file is read; one step
    beyond it, the reader refuses it with one `[section] key: ...` line."""
    low, high, low_in, high_in = key.bounds
    write = LISTS.get(key.key, lambda v: v)
    for bound, inclusive, outward in ((low, low_in, -1.0), (high, high_in, 1.0)):
        if math.isinf(bound):
            continue
        step = 1 if key.integer else max(abs(bound) * 1e-6, 1e-9)
        inside = bound if inclusive else bound - outward * step
        beyond = bound + outward * step if inclusive else bound
        if key.integer:
            inside, beyond = int(inside), int(beyond)
        _read(_with(section, key.key, write(inside)), section)
        with pytest.raises(ValueError) as err:
            _read(_with(section, key.key, write(beyond)), section)
        message = str(err.value)
        assert message.startswith(f"[{section}] {key.key}: "), message
        assert "\n" not in message


@pytest.mark.parametrize("case", [c for c in CASES if c[1].bounds is not None], ids=_id)
def test_each_declared_bound_is_the_readers(case):
    _check_bound(*case)


def test_a_declaration_wider_than_the_constructor_fails_the_bound_check():
    """The check can fail: a Poisson ratio declared up to 0.6 is read by `check_declared` at
    0.6 - 1e-6, where `Material` refuses it."""
    wrong = SceneKey("poisson_ratio", "", 0.3, "", (0.0, 0.6, True, False))
    with pytest.raises(ValueError, match=r"^\[material\] poisson_ratio: must be in \[0, 0.5\)"):
        _check_bound("material", wrong)


@pytest.mark.parametrize("case", [c for c in CASES if c[1].default is not None], ids=_id)
def test_each_declared_default_is_what_leaving_the_key_out_gives(case):
    section, key = case
    without = _read(_with(section, key.key, _ABSENT), section)
    written = _read(_with(section, key.key, key.default), section)
    if section == "optimize":
        assert written == without
    else:
        assert bool(eqx.tree_equal(written, without))


#: Choices that another family's scene takes: a minimal scene of that family with the choice.
OTHER_FAMILY = {("ltca", "compliance", "point"): {
    "pair": {"family": "double_circular_arc", "teeth": [24, 24], "normal_module": 4.0, "helix_angle_deg": 15.0,
             "face_width": 55.0}, "ltca": {"compliance": "point"}}}


@pytest.mark.parametrize("case", [c for c in CASES if c[1].choices is not None], ids=_id)
def test_each_declared_choice_is_read_and_another_word_is_refused(case):
    section, key = case
    for choice in key.choices:
        other = OTHER_FAMILY.get((section, key.key, choice))
        _read(copy.deepcopy(other) if other else _with(section, key.key, choice), section)
    with pytest.raises(ValueError, match=rf"^\[{section}\] {key.key}: "):
        _read(_with(section, key.key, "no-such-choice"), section)


def test_scene_file_page_holds_the_generated_reference():
    """`docs/scene_files.md` holds `reference()` (`python tools/scene_file_reference.py
    --write` regenerates it)."""
    page = (Path(__file__).resolve().parents[1] / "docs" / "scene_files.md").read_text()
    block = page.split("<!-- section-keys:start (generated: tools/scene_file_reference.py) -->\n", 1)[1]
    assert block.split("<!-- section-keys:end -->", 1)[0] == reference()
