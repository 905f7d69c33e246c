"""TOML scene files and the built-in default scene.

Field names carry their unit where it differs from the engine's (mm, N, s, rad):
`helix_angle_deg`, `torque_Nm`, `speed_rpm`, `tip_relief_um`. The format and every key:
`docs/scene_files.md` (the keys' declarations: `scene_keys`). Errors are one line naming the
field as `[section] key: ...`.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from ..accuracy import Accuracy
from ..geometry import FAMILIES
from ..geometry.errors import MeshErrors
from ..geometry.modification import FlankModification
from ..ltca import COMPLIANCE_MODELS, default_compliance
from ..scene import EFFECTS, MAX_PITCHES, OperatingPoint, Scene
from ..units import Material
from .scene_keys import check_declared, declared, field_message, toml_value

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, packaged as tomli
    import tomli as tomllib


class SceneFileError(ValueError):
    """A scene file that cannot be turned into a `Scene`; the message names the field."""


DEFAULT_SCENE_TOML = """\
# Seed 001 (mesh-in impact of helical gears): the 29/71 pair with the paper's optimal
# modification (its Table 2), at the design point 1000 N·m and 5000 rpm.
[pair]
family = "involute"
teeth = [29, 71]
normal_module = 5.0          # mm
pressure_angle_deg = 20.0
helix_angle_deg = 27.5
hand = "right"               # of the pinion; the gear is left hand
face_width = 42.0            # mm
profile_shift = [0.0, 0.0]   # the paper's a = 261.0 mm is inconsistent: a = 281.85 mm

[modification]               # pinion flank, seed 001 Table 2
root_relief_um = 5.9         # y1
tip_relief_um = 6.8          # y2
root_relief_length = 3.8     # y3, mm of roll length
tip_relief_length = 4.3      # y4, mm of roll length
crowning_um = 6.2            # y5
unmodified_length = 4.6      # y6, mm of face width

[operating]
torque_Nm = 1000.0
speed_rpm = 5000.0

[analysis]
accuracy = "default"
effects = ["impact"]         # LTCA runs whenever a torque is given
"""

#: `[optimize]` is read by `gearjax.optimize.settings` (the `gearjax optimize` command).
_SECTIONS = ("pair", "modification", "gear_modification", "errors", "operating", "material", "ltca", "impact", "analysis", "optimize")


def _names(section: str) -> frozenset[str]:
    """The keys declared for `section`."""
    return frozenset(k.key for k in declared(section))


#: The keys of each section, from their declarations (`scene_keys`); the amounts in µm map
#: to the constructors' mm fields of the same name without `_um`.
_MOD_KEYS = {k.key: (k.key.removesuffix("_um"), 1e-3 if k.unit == "µm" else 1.0) for k in declared("modification")}
_ERROR_KEYS = {k.key: k.key.removesuffix("_um") for k in declared("errors")}
_OPERATING_KEYS = _names("operating")
_MATERIAL_KEYS = _names("material")
_IMPACT_KEYS = _names("impact")
#: The `Scene` constructor's keywords that its errors name: (section, file key).
_SCENE_FIELDS = {"hub_radius": ("ltca", "hub_radius"), "inertia": ("impact", "inertia_kg_m2"),
                 "compliance": ("ltca", "compliance")} | {name: ("modification", key) for key, (name, _) in _MOD_KEYS.items()}
_LTCA_KEYS = _names("ltca")
_ANALYSIS_KEYS = _names("analysis")


def _fail(field: str, message: str) -> SceneFileError:
    """The error for `field` ("section.key", or "section"): `[section] key: message`, the
    one style of every scene-file error."""
    section, _, key = field.partition(".")
    return SceneFileError(f"[{section}] {key}: {message}" if key else f"[{section}] {message}")


def _unknown(section: str, table: dict, allowed) -> None:
    for key in table:
        if key not in allowed:
            raise _fail(f"{section}.{key}", f"unknown field; allowed: {', '.join(sorted(allowed))}")


def _number(section: str, key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _fail(f"{section}.{key}", f"must be a number; got {value!r}")
    try:
        return float(value)
    except OverflowError:  # an integer beyond the float range
        raise _fail(f"{section}.{key}", f"must be a finite number; got an integer of {len(str(abs(value)))} digits") from None


def _numbers(section: str, key: str, value: Any, n: int) -> tuple:
    if not isinstance(value, list) or len(value) != n:
        raise _fail(f"{section}.{key}", f"must be a list of {n} numbers; got {value!r}")
    return tuple(_number(section, key, v) for v in value)


def _build(section: str, factory, fields: dict | None = None, **kwargs):
    """Call a constructor; its ValueError in the scene file's style (`field_message`), the
    keywords named by their file keys (`fields`: keyword -> (section, key))."""
    try:
        return factory(**kwargs)
    except SceneFileError:
        raise
    except ValueError as err:
        names = {k: (section, k) for k in kwargs} | (fields or {})
        raise SceneFileError(field_message(section, str(err), names)) from None


def scene_from_dict(data: dict) -> Scene:
    """Build a `Scene` from a parsed scene file (see the README for the format)."""
    if not isinstance(data, dict):
        raise SceneFileError("scene: the file must be a TOML table")
    _unknown("scene", data, _SECTIONS)
    for section, table in data.items():
        if section not in ("pair", "optimize") and isinstance(table, dict):
            try:
                check_declared(section, table)
            except ValueError as err:
                raise SceneFileError(str(err)) from None
    if "pair" not in data:
        raise _fail("pair", "missing section: every scene needs a [pair]")
    pair = _pair_from(data["pair"])
    modification = _modification_from(data, "modification")
    gear_modification = _modification_from(data, "gear_modification")
    errors = _errors_from(data)
    operating = _operating_from(data)
    material = _material_from(data)
    compliance, hub_radius, extended = _ltca_from(data.get("ltca", {}), pair)
    inertia = _inertia_from(data.get("impact", {}))
    accuracy, effects, pitches = _analysis_from(data.get("analysis", {}))
    return _build(
        "analysis",
        Scene,
        _SCENE_FIELDS,
        pair=pair,
        modification=modification,
        gear_modification=gear_modification,
        errors=errors,
        operating=operating,
        material=material,
        compliance=compliance,
        hub_radius=hub_radius,
        inertia=inertia,
        effects=effects,
        accuracy=accuracy,
        pitches=pitches,
        extended_contact=extended,
    )


def _pair_from(p: dict):
    """[pair]: the gear pair of the family it names (default "involute"), read as the
    family declares (`AbstractGearPair.scene_file`)."""
    _unknown("pair", p, _pair_keys())
    family = p.get("family", "involute")
    by_name = {cls.scene_file.family: cls for cls in FAMILIES}
    if not isinstance(family, str) or family not in by_name:
        raise _fail("pair.family", f"must be one of {', '.join(repr(f) for f in by_name)}; got {family!r}")
    cls = by_name[family]
    spec = cls.scene_file
    _check_family_keys(p, spec)
    kwargs: dict[str, Any] = {}
    for key, value in p.items():
        if key == "family":
            continue
        keyword, kind, _, factor = spec.keys[key]
        kwargs[keyword] = _read_value("pair", key, kind, value, factor)
    fields = {keyword: ("pair", key) for key, (keyword, *_) in spec.keys.items()} | {key: ("pair", key) for key in spec.keys}
    return _build("pair", cls, fields, **kwargs)


def pair_reference() -> str:
    """The `[pair]` keys of every family as a Markdown table, generated from the families'
    declarations (`AbstractGearPair.scene_file`) and their constructors' defaults, so the
    reference cannot drift from the code (`docs/scene_files.md` holds it; `python
    tools/scene_file_reference.py --write` regenerates it)."""
    import inspect

    specs = [cls.scene_file for cls in FAMILIES]
    defaults = [inspect.signature(cls.__init__).parameters for cls in FAMILIES]
    keys = list(dict.fromkeys(key for spec in specs for key in spec.keys))
    header = "| key | unit | " + " | ".join(f"`{spec.family}`" for spec in specs) + " |"
    rows = [header, "|---|---|" + "---|" * len(specs)]
    for key in keys:
        unit = next(spec.keys[key][2] for spec in specs if key in spec.keys)
        cells = []
        for spec, parameters in zip(specs, defaults):
            if key in spec.keys:
                keyword, _, _, factor = spec.keys[key]
                default = parameters[keyword].default
                if key in spec.required:
                    cells.append("required")
                elif default is None:
                    cells.append("optional")
                else:
                    value = [v / factor for v in default] if isinstance(default, tuple) else default
                    value = value / factor if isinstance(value, float) else value
                    cells.append(f"default `{toml_value(value)}`")
            elif key in spec.fixed[0]:
                cells.append("fixed")
            else:
                cells.append("—")
        rows.append(f"| `{key}` | {unit} | " + " | ".join(cells) + " |")
    notes = [f"`{spec.family}`: {', '.join(f'`{k}`' for k in spec.fixed[0])}, {spec.fixed[1]}." for spec in specs
             if spec.fixed[0]]
    return "\n".join(rows) + ("\n\nFixed: " + " ".join(notes) if notes else "") + "\n"


def _pair_keys() -> set:
    """Every key any family accepts in [pair], and `family`."""
    return {"family"}.union(*(cls.scene_file.keys for cls in FAMILIES))


def _read_value(section: str, key: str, kind: str, value: Any, factor: float):
    """One value of a `SceneFileSpec` kind, in engine units."""
    if kind == "teeth":
        if not isinstance(value, list) or len(value) != 2 or not all(
                isinstance(t, int) and not isinstance(t, bool) for t in value):
            raise _fail(f"{section}.{key}", f"must be a list of two integers; got {value!r}")
        return tuple(value)
    if kind == "text":
        return value
    if kind == "number_or_pair" and isinstance(value, list):
        return tuple(v * factor for v in _numbers(section, key, value, 2))
    return _number(section, key, value) * factor


def _check_family_keys(p: dict, spec) -> None:
    """Keys that belong to other families, or that this family fixes, are errors; the
    family's required keys must be there."""
    fixed, why = spec.fixed
    for key in p:
        if key == "family" or key in spec.keys:
            continue
        if key in fixed:
            raise _fail(f"pair.{key}", f"is {why} for family = '{spec.family}'")
        owners = [cls.scene_file.family for cls in FAMILIES if key in cls.scene_file.keys]
        if len(owners) == 1:
            raise _fail(f"pair.{key}", f"applies to family = '{owners[0]}' only")
        raise _fail(f"pair.{key}", f"applies to the {' and '.join(owners)} families only")
    for required in spec.required:
        if required not in p:
            raise _fail(f"pair.{required}", "missing required field")


def _modification_from(data: dict, section: str):
    """[modification] / [gear_modification]: a `FlankModification` (µm amounts), or None."""
    if section not in data:
        return None
    table = data[section]
    _unknown(section, table, _MOD_KEYS)
    args = {name: _number(section, key, table[key]) * scale for key, (name, scale) in _MOD_KEYS.items() if key in table}
    return _build(section, FlankModification, {name: (section, key) for key, (name, _) in _MOD_KEYS.items()}, **args)


def _errors_from(data: dict):
    """[errors]: `MeshErrors` (µm), or None."""
    if "errors" not in data:
        return None
    table = data["errors"]
    _unknown("errors", table, _ERROR_KEYS)
    return _build("errors", MeshErrors, {name: ("errors", key) for key, name in _ERROR_KEYS.items()}, **{name: _number("errors", key, table[key]) * 1e-3 for key, name in _ERROR_KEYS.items() if key in table})


def _operating_from(data: dict):
    """[operating]: `OperatingPoint` from N·m and rpm, or None (unloaded)."""
    if "operating" not in data:
        return None
    table = data["operating"]
    _unknown("operating", table, _OPERATING_KEYS)
    torque = _number("operating", "torque_Nm", table["torque_Nm"]) if "torque_Nm" in table else None
    speed = _number("operating", "speed_rpm", table.get("speed_rpm", 0.0))
    return _build("operating", OperatingPoint, torque_Nm=torque, speed_rpm=speed)


def _material_from(data: dict):
    """[material]: `Material`, or None (steel)."""
    if "material" not in data:
        return None
    table = data["material"]
    _unknown("material", table, _MATERIAL_KEYS)
    return _build("material", Material, **{k: _number("material", k, v) for k, v in table.items()})


def _ltca_from(ltca: dict, pair):
    """[ltca]: (compliance model, hub radius or None, extended_contact); the compliance
    model by default `default_compliance(pair)`."""
    _unknown("ltca", ltca, _LTCA_KEYS)
    by_name = {cls.scene_file.family: cls for cls in COMPLIANCE_MODELS}
    default = default_compliance(pair)
    kind = ltca.get("compliance", default.scene_file.family)
    if not isinstance(kind, str) or kind not in by_name:
        raise _fail("ltca.compliance", f"must be {' or '.join(repr(name) for name in by_name)}; got {kind!r}")
    spec = by_name[kind].scene_file
    options = {}
    for key, value in ltca.items():
        owners = [name for name, cls in by_name.items() if key in cls.scene_file.keys]
        if not owners:
            continue  # one of [ltca]'s own keys
        if key not in spec.keys:
            raise _fail(f"ltca.{key}", f"applies to compliance = {' or '.join(repr(o) for o in owners)} only")
        keyword, value_kind, _, factor = spec.keys[key]
        options[keyword] = _read_value("ltca", key, value_kind, value, factor)
    compliance = _build("ltca", by_name[kind], {kw: ("ltca", key) for key, (kw, *_) in spec.keys.items()}, **options)
    hub_radius = None
    if "hub_radius" in ltca:
        value = ltca["hub_radius"]
        hub_radius = _numbers("ltca", "hub_radius", value, 2) if isinstance(value, list) else _number("ltca", "hub_radius", value)
    extended = ltca.get("extended_contact", True)
    if not isinstance(extended, bool):
        raise _fail("ltca.extended_contact", f"must be true or false; got {extended!r}")

    return compliance, hub_radius, extended


def _inertia_from(impact: dict):
    """[impact]: $(J_1, J_2)$ in t·mm² from kg·m², or None (solid discs)."""
    _unknown("impact", impact, _IMPACT_KEYS)
    if "inertia_kg_m2" not in impact:
        return None
    # 1 kg m^2 = 1e-3 t * 1e6 mm^2 = 1e3 t mm^2
    return [1e3 * v for v in _numbers("impact", "inertia_kg_m2", impact["inertia_kg_m2"], 2)]


def _analysis_from(analysis: dict):
    """[analysis]: (accuracy, effects, pitches)."""
    _unknown("analysis", analysis, _ANALYSIS_KEYS)
    preset = analysis.get("accuracy", "default")
    try:
        accuracy = Accuracy.preset(preset)
        overrides = {k: analysis[k] for k in ("tca_method", "positions_per_pitch", "face_slices", "dtype") if k in analysis}
        if overrides:
            accuracy = accuracy.replace(**overrides)
    except ValueError as err:
        raise SceneFileError(field_message("analysis", str(err), {k: ("analysis", k) for k in _ANALYSIS_KEYS})) from None
    effects = analysis.get("effects", [])
    if not isinstance(effects, list) or not all(isinstance(e, str) for e in effects):
        raise _fail("analysis.effects", f"must be a list of strings from {EFFECTS}; got {effects!r}")
    pitches = analysis.get("pitches", 1)
    if isinstance(pitches, bool) or not isinstance(pitches, int) or not 1 <= pitches <= MAX_PITCHES:
        raise _fail("analysis.pitches", f"must be an integer in [1, {MAX_PITCHES}]; got {pitches!r}")

    return accuracy, tuple(effects), pitches


def read_scene_text(path: str | Path) -> str:
    """The text of a scene file; `SceneFileError` (one line) if it cannot be read or is not
    UTF-8 text."""
    path = Path(path)
    try:
        return path.read_text(encoding="utf-8")
    except OSError as err:
        raise SceneFileError(f"{path}: cannot read the scene file ({err.strerror})") from None
    except UnicodeDecodeError as err:
        raise SceneFileError(f"{path}: not a scene file (not UTF-8 text: byte {err.object[err.start]:#04x} "
                             f"at position {err.start})") from None


def load_scene(path: str | Path) -> tuple[Scene, dict]:
    """Read a TOML scene file; returns the scene and the parsed table."""
    return parse_scene(read_scene_text(path), str(path))


def parse_scene(text: str, name: str = "scene") -> tuple[Scene, dict]:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SceneFileError(f"{name}: not valid TOML ({err})") from None
    return scene_from_dict(data), data


def default_scene() -> tuple[Scene, dict]:
    """The built-in default scene (seed 001 pair and optimal modification)."""
    return parse_scene(DEFAULT_SCENE_TOML, "default scene")
