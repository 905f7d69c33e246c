"""The scene file's keys outside `[pair]`: unit, default, allowed values and meaning.

`[pair]` is declared by the families (`AbstractGearPair.scene_file`,
`gearjax.io.scene_file.pair_reference`); every other section is declared here, and
`reference()` writes the whole table that `docs/scene_files.md` holds (`python
tools/scene_file_reference.py --write`). The readers (`gearjax.io.scene_file`,
`gearjax.optimize.settings`) and these declarations are kept together by tests: the same
keys per section, each declared bound rejected one step beyond and accepted at the bound,
and each declared default giving the scene that leaving the key out gives.
"""

from __future__ import annotations

import dataclasses
import functools
import re
from collections.abc import Callable

from ..accuracy import DTYPES, PRESETS, TCA_METHODS
from ..ltca import COMPLIANCE_MODELS
from ..ltca.compliance import HERTZ_LAWS
from ..operating import MAX_SPEED_RPM, MAX_TORQUE_NM
from ..optimize.settings import scene_keys as optimize_scene_keys
from ..scene import EFFECTS, MAX_PITCHES
from .declared_keys import INF as _INF
from .declared_keys import SceneKey as SceneKey
from .declared_keys import check_keys, range_text
from .declared_keys import toml_value as toml_value

_AMOUNT = (0.0, 1000.0, True, True)
_LENGTH = (0.0, _INF, False, True)
_ERROR = (-1000.0, 1000.0, True, True)
_POSITIVE = (0.0, _INF, False, True)
_NON_NEGATIVE = (0.0, _INF, True, True)
_PRESETS = tuple(PRESETS)


def _modification(whose: str) -> tuple[SceneKey, ...]:
    return (
        SceneKey("root_relief_um", "µm", 0.0, f"y1: {whose} root relief at the start of active profile", _AMOUNT),
        SceneKey("tip_relief_um", "µm", 0.0, f"y2: {whose} tip relief at the tip", _AMOUNT),
        SceneKey("root_relief_length", "mm", 1.0, "y3: roll length of the root relief", _LENGTH,
                 allowed="within the active flank"),
        SceneKey("tip_relief_length", "mm", 1.0, "y4: roll length of the tip relief", _LENGTH,
                 allowed="within the active flank"),
        SceneKey("crowning_um", "µm", 0.0, "y5: lead crowning at the face ends", _AMOUNT),
        SceneKey("unmodified_length", "mm", 0.0, "y6: face width left uncrowned", _NON_NEGATIVE,
                 allowed="less than the face width"),
    )


def _ltca_keys() -> tuple[SceneKey, ...]:
    slice_model = COMPLIANCE_MODELS[0]
    fields = {f.name: f.default for f in dataclasses.fields(slice_model)}
    return (
        SceneKey("compliance", "", None, "tooth compliance model: "
                 + "; ".join(f"`{m.scene_file.family}`, {m.scene_file.description}" for m in COMPLIANCE_MODELS),
                 choices=tuple(m.scene_file.family for m in COMPLIANCE_MODELS),
                 absent="the family's: `slice` for involute and curvilinear pairs, `point` for double-circular-arc pairs"),
        SceneKey("coupling_length_mn", "m_n", fields["coupling_length"],
                 "decay length of a point load along the face (`slice` and `point`)", (0.0, 50.0, True, True),
                 allowed="positive for `point`"),
        SceneKey("hertz", "", fields["hertz"], "contact law of a slice: line contact (Palmgren) or linear (`slice` only)",
                 choices=HERTZ_LAWS),
        SceneKey("hub_radius", "mm", None, "inner radius of the gear bodies: the fillet foundation's (`slice`) and the "
                 "impact's inertias", absent="half the root radius",
                 allowed="(0, r_f): inside the root circle; one number or one per gear"),
        SceneKey("extended_contact", "", True, "loaded teeth may also touch by their tip edges (`slice`, `iso`; `point` "
                 "always takes the TCA's edge contacts)", allowed="`true` \\| `false`"),
    )


@functools.cache
def _sections() -> dict[str, Callable[[], tuple[SceneKey, ...]]]:
    """Every section but `[pair]`: section name -> the function declaring its keys (each
    built on demand; `[optimize]`'s are the optimiser's own, `gearjax.optimize.settings`)."""
    return {
        "modification": lambda: _modification("pinion's drive-flank"),
        "gear_modification": lambda: _modification("gear's drive-flank"),
        "errors": lambda: (
            SceneKey("base_pitch_deviation_um", "µm", 0.0, "f_pb: pinion minus gear base pitch; pair k shifted by k f_pb", _ERROR),
            SceneKey("pitch_deviation_um", "µm", 0.0, "f_p: the tooth of pair 0 stands proud", _ERROR),
            SceneKey("misalignment_um", "µm", 0.0, "f_ma: linear lead deviation over the face width", _ERROR),
        ),
        "operating": lambda: (
            SceneKey("torque_Nm", "N·m", None, "pinion torque; a torque runs the loaded contact", (0.0, MAX_TORQUE_NM, True, True),
                     absent="unloaded: the rigid TCA only"),
            SceneKey("speed_rpm", "rpm", 0.0, "pinion speed; used by the impact only", (0.0, MAX_SPEED_RPM, True, True)),
        ),
        "material": lambda: (
            SceneKey("youngs_modulus", "MPa", 206000.0, "Young's modulus E of both gears", _POSITIVE),
            SceneKey("poisson_ratio", "", 0.3, "Poisson's ratio ν", (0.0, 0.5, True, False)),
            SceneKey("density", "t/mm³", 7.85e-9, "density ρ (the gears' inertia when `[impact]` gives none)", _POSITIVE),
        ),
        "ltca": _ltca_keys,
        "impact": lambda: (
            SceneKey("inertia_kg_m2", "kg·m²", None, "J1, J2 of the rotating assemblies", _POSITIVE,
                     absent="solid discs of the gears' tip radius and face width", allowed="two numbers"),
        ),
        "analysis": lambda: (
            SceneKey("accuracy", "", "default", "accuracy preset (docs: What accuracy costs)", choices=_PRESETS),
            SceneKey("effects", "", [], "stages beyond the TCA: " + ", ".join(f"`{e}`" for e in EFFECTS)
                     + " (the loaded contact runs whenever a torque is given)", allowed="a list of " + ", ".join(
                         f'`"{e}"`' for e in EFFECTS)),
            SceneKey("tca_method", "", None, "rigid contact: on the tooth surfaces, or in the plane of action "
                     "(involute fast path)", choices=TCA_METHODS, absent="the preset's"),
            SceneKey("positions_per_pitch", "", None, "mesh positions per angular pitch", (2, 100000, True, True),
                     absent="the preset's", integer=True),
            SceneKey("face_slices", "", None, "slices of the face width", (1, 10000, True, True),
                     absent="the preset's", integer=True),
            SceneKey("dtype", "", None, "floating-point precision", choices=DTYPES, absent="the preset's"),
            SceneKey("pitches", "", 1, "angular pitches covered", (1, MAX_PITCHES, True, True), integer=True),
        ),
        "optimize": optimize_scene_keys,
    }


def section_keys() -> dict[str, tuple[SceneKey, ...]]:
    """Every section but `[pair]`: section name -> its keys, in the order of the reference."""
    return {name: declare() for name, declare in _sections().items()}


def declared(section: str) -> tuple[SceneKey, ...]:
    """The keys of one section (not `[pair]`), in the order of the reference."""
    return _sections()[section]()


def check_declared(section: str, table: dict) -> None:
    """The declared bounds and choices of `section`'s keys in `table` (`check_keys`)."""
    check_keys(section, declared(section) if section in _sections() else (), table)


_FIELD = re.compile(r"^(?P<fields>[A-Za-z_]+(?:\.[A-Za-z_]+)?(?:\[\d\])?(?: \([^)]*\))?(?: / [A-Za-z_]+)*)(?:=| )(?P<rest>.*)$", re.S)


def field_message(section: str, message: str, fields: dict[str, tuple[str, str]]) -> str:
    """A constructor's `ValueError` message in the scene file's style, `[section] key: ...`.

    The message's leading field (`face_width must ...`, `teeth[0] (pinion) must ...`,
    `modification.tip_relief_length (y4) must ...`) is a constructor's keyword; `fields`
    maps the keywords to (section, file key). A message that names no known field keeps its
    text after `[section]`."""
    if message.startswith("["):
        return message
    match = _FIELD.match(message)
    head = re.match(r"[A-Za-z_.]+", match["fields"])[0] if match else ""
    if head not in fields and "." in head:  # `modification.tip_relief_length`: a section's own key
        prefix, name = head.split(".", 1)
        fields = {head: (prefix, fields.get(name, (prefix, name))[1])}
    if head not in fields:
        return f"[{section}] {message}"
    where, key = fields[head]
    return f"[{where}] {key}{match['fields'][len(head):]}: {match['rest']}"


def reference() -> str:
    """The keys of every section but `[pair]` as Markdown tables (one per section)."""
    out = []
    for section, keys in section_keys().items():
        out.append(f"#### `[{section}]`\n")
        out.append("| key | unit | default | allowed | meaning |")
        out.append("|---|---|---|---|---|")
        for k in keys:
            meaning = k.meaning.replace("|", "\\|")  # a table cell
            out.append(f"| `{k.key}` | {k.unit} | {k.default_text()} | {k.allowed_text()} | {meaning} |")
        out.append("")
    return "\n".join(out)
