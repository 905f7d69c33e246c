"""Bad scene files found by a machine: valid scene files of every family, mutated at random
(values replaced by huge, tiny, negative, non-finite numbers, strings, booleans, lists and
tables; keys and sections removed; unknown keys added), are either a valid scene or one
`SceneFileError` whose message is one line naming its section. Anything else (an
`OverflowError`, a `MemoryError`, a `TypeError`, a traceback) fails.

Only parsing and the scene's construction run (no contact analysis is traced), so a few
thousand examples (2 000, derandomised: the same each run) take about a minute.
"""

from __future__ import annotations

import copy
import inspect
import math
import tomllib
from pathlib import Path

import jax
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gearjax.geometry import FAMILIES
from gearjax.io.scene_file import DEFAULT_SCENE_TOML, SceneFileError, pair_reference, scene_from_dict

CURVILINEAR = """
[pair]
family = "curvilinear"
teeth = [20, 30]
normal_module = 2.0
face_width = 20.0
tooth_trace_radius = 40.0

[modification]
tip_relief_um = 8.0
tip_relief_length = 1.5

[operating]
torque_Nm = 50.0

[ltca]
compliance = "slice"
coupling_length_mn = 1.1
hertz = "palmgren"
hub_radius = 10.0
extended_contact = true

[analysis]
accuracy = "fast"
tca_method = "surface"
positions_per_pitch = 16
face_slices = 11
dtype = "float64"
"""

DOUBLE_ARC = """
[pair]
family = "double_circular_arc"
teeth = [24, 24]
normal_module = 4.0
helix_angle_deg = 15.0
face_width = 55.0
axial_pitch_error_um = 10.0

[analysis]
accuracy = "fast"
"""

INVOLUTE_EXTRA = """
[pair]
teeth = [23, 41]
normal_module = 4.0
face_width = 20.0
profile_shift = [0.3, 0.2]

[gear_modification]
tip_relief_um = 5.0
tip_relief_length = 2.0

[errors]
base_pitch_deviation_um = 3.0
misalignment_um = 4.0

[material]
youngs_modulus = 206000.0
density = 7.85e-9

[impact]
inertia_kg_m2 = [0.01, 0.05]

[operating]
torque_Nm = 200.0
speed_rpm = 3000.0

[analysis]
effects = ["impact"]
pitches = 2
"""

SCENES = {name: tomllib.loads(text) for name, text in
          {"involute": DEFAULT_SCENE_TOML, "curvilinear": CURVILINEAR, "double_arc": DOUBLE_ARC,
           "involute_extra": INVOLUTE_EXTRA}.items()}

BAD_VALUES = st.one_of(
    st.sampled_from([
        0, -1, 1, 2**63, -(2**63), 10**400, 1e308, -1e308, 1e-308, 5e-324, math.inf, -math.inf, math.nan,
        True, False, "", "five", "1e308", [], [1.0], [1.0, 2.0, 3.0], [[1.0, 2.0]], ["a", "b"], {}, {"x": 1.0},
    ]),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.lists(st.floats(min_value=-1e3, max_value=1e3), max_size=3),
    st.text(max_size=8),
)


def _paths(data: dict):
    return [(section, key) for section, table in data.items() if isinstance(table, dict) for key in table]


@st.composite
def mutated_scenes(draw):
    data = copy.deepcopy(SCENES[draw(st.sampled_from(sorted(SCENES)))])
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["replace", "replace", "replace", "scale", "remove", "add", "drop_section"]))
        paths = _paths(data)
        if kind == "drop_section" or not paths:
            if data:
                del data[draw(st.sampled_from(sorted(data)))]
            continue
        section, key = draw(st.sampled_from(paths))
        if kind == "replace":
            data[section][key] = draw(BAD_VALUES)
        elif kind == "scale" and isinstance(value := data[section][key], (int, float)) and not isinstance(value, bool):
            # numbers of the right type, out of range
            if isinstance(value, int):
                data[section][key] = value * draw(st.sampled_from([-1, 0, 1000, 10**9, 10**18]))
            else:
                data[section][key] = value * draw(st.sampled_from([-1.0, 0.0, 1e-6, 1e3, 1e9, 1e300]))
        elif kind == "remove":
            del data[section][key]
        elif kind == "add":
            data[section][draw(st.sampled_from(["colour", "torque", "face_width", "teeth", "x"]))] = draw(BAD_VALUES)
    return data


@settings(max_examples=2000, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(mutated_scenes())
def test_mutated_scene_files_are_a_scene_or_one_line_naming_the_field(data):
    try:
        scene_from_dict(data)
    except SceneFileError as err:
        message = str(err)
        assert "\n" not in message and message.strip() == message and message, repr(message)
        assert message.startswith("["), message  # names its section: "[section] key: ..."


def test_pair_reference_in_the_docs_is_the_generated_one():
    """`docs/scene_files.md` holds the `[pair]` table that the families' declarations give
    (`python tools/scene_file_reference.py --write` regenerates it)."""
    page = (Path(__file__).resolve().parents[1] / "docs" / "scene_files.md").read_text()
    block = page.split("<!-- pair-keys:start (generated: tools/scene_file_reference.py) -->\n", 1)[1]
    assert block.split("<!-- pair-keys:end -->", 1)[0] == pair_reference()


@pytest.mark.parametrize("cls", FAMILIES, ids=lambda cls: cls.scene_file.family)
def test_each_declared_pair_key_reaches_its_constructor_keyword(cls):
    """Every `[pair]` key a family declares names a keyword of its constructor, and a file
    that gives each optional key a value off its default builds the pair the constructor
    builds from the same values (units converted): the declaration is what is read."""
    spec = cls.scene_file
    parameters = inspect.signature(cls.__init__).parameters
    table = {"family": spec.family, "teeth": [24, 26], "normal_module": 3.0}
    kwargs = {"teeth": (24, 26), "normal_module": 3.0}
    for key, (keyword, kind, unit, factor) in spec.keys.items():
        assert keyword in parameters, (key, keyword)
        # the key's name carries its unit where it is not the engine's (mm, rad via *_deg)
        assert (unit, factor) == (("µm", 1e-3) if key.endswith("_um") else ("deg", 1.0) if key.endswith("_deg")
                                  else (unit, 1.0)), (key, unit, factor)
        if key in table or kind in ("teeth", "text") or keyword == "center_distance":
            continue
        default = parameters[keyword].default
        base = default[0] if isinstance(default, tuple) else default
        value = 1.02 * base / factor if base else 0.1  # 2 % off the default, or 0.1 for a zero one
        table[key] = value
        kwargs[keyword] = value * factor
    pair = scene_from_dict({"pair": table}).pair
    expected = cls(**kwargs)
    for name in ("teeth", "face_width", "normal_module"):
        np.testing.assert_allclose(np.asarray(getattr(pair, name)), np.asarray(getattr(expected, name)), rtol=1e-15)
    leaves, expected_leaves = jax.tree_util.tree_leaves(pair), jax.tree_util.tree_leaves(expected)
    assert len(leaves) == len(expected_leaves)
    for a, b in zip(leaves, expected_leaves):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-15)
