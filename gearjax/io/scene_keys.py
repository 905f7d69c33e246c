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
import math
import re
from collections.abc import Callable
from typing import Any

from ..accuracy import DTYPES, PRESETS, TCA_METHODS
from ..ltca import COMPLIANCE_MODELS
from ..ltca.compliance import HERTZ_LAWS
from ..operating import MAX_SPEED_RPM, MAX_TORQUE_NM
from ..scene import EFFECTS, MAX_PITCHES

_INF = float("inf")


@dataclasses.dataclass(frozen=True)
class SceneKey:
    """One key of a scene-file section.

    Attributes:
        key: the name in the file.
        unit: the unit of its value in the file ("" for none).
        default: the value that leaving the key out means, as written in a file; None
            where leaving it out means something else (`absent` says what).
        meaning: what it sets, in an engineer's words.
        bounds: (low, high, low inclusive, high inclusive) of a number, or of each
            number of a list, in the file's unit; None where `choices` or `allowed` say it.
        choices: the allowed strings.
        allowed: the allowed values in words, where bounds and choices do not say it all.
        absent: what leaving the key out means when `default` is None.
        integer: the value is an integer.
    """

    key: str
    unit: str
    default: Any
    meaning: str
    bounds: tuple[float, float, bool, bool] | None = None
    choices: tuple[str, ...] | None = None
    allowed: str = ""
    absent: str = ""
    integer: bool = False

    def allowed_text(self) -> str:
        """The allowed values as the reference prints them."""
        parts = []
        if self.choices is not None:
            parts.append(" \\| ".join(f'`"{c}"`' for c in self.choices))
        if self.bounds is not None:
            parts.append(("integer in " if self.integer else "") + _range(self.bounds))
        if self.allowed:
            parts.append(self.allowed)
        return "; ".join(parts)

    def default_text(self) -> str:
        return f"`{toml_value(self.default)}`" if self.default is not None else self.absent


def _range(bounds: tuple[float, float, bool, bool]) -> str:
    """`[low, high]`, `(low, ∞)`, ...: an interval as the reference and the errors print it."""
    low, high, low_in, high_in = bounds
    opens = "[" if low_in and abs(low) != _INF else "("
    closes = "]" if high_in and abs(high) != _INF else ")"
    return f"{opens}{_num(low)}, {_num(high)}{closes}"


def _num(value: float) -> str:
    return "∞" if value == _INF else "−∞" if value == -_INF else f"{value:g}"


def toml_value(value) -> str:
    """A value as it is written in a scene file."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return repr(value)


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


def _optimize_keys() -> tuple[SceneKey, ...]:
    # the optimiser's declarations; imported here, since the optimiser reads scene files
    from ..optimize.objective import AGGREGATES, QUANTITIES
    from ..optimize.run import METHODS
    from ..optimize.settings import OptimizeSettings
    from ..optimize.space import _MODULE_BOUNDS
    from ..optimize.space import SCENE_KEYS as DESIGN_KEYS

    d = {f.name: f.default for f in dataclasses.fields(OptimizeSettings)}
    count = lambda key, low, meaning: SceneKey(key, "", d[key], meaning, (low, _INF, True, True), integer=True)  # noqa: E731
    weight = lambda key, unit, meaning: SceneKey(key, unit, d[key], meaning, _NON_NEGATIVE)  # noqa: E731
    keys = [
        SceneKey("method", "", d["method"], "search method", choices=METHODS),
        SceneKey("objective", "", d["objective"], "quantity minimised: " + "; ".join(
            f"`{name}`, {what} ({unit})" for name, (unit, what, _) in QUANTITIES.items()), choices=tuple(QUANTITIES)),
        SceneKey("loads_Nm", "N·m", None, "pinion torques of the load spectrum", (0.0, _INF, False, True),
                 absent="the scene's torque", allowed="a non-empty list"),
        SceneKey("load_weights", "", None, "weights of the loads", _NON_NEGATIVE, absent="equal",
                 allowed="one per load, with a positive sum"),
        SceneKey("aggregate", "", d["aggregate"], "over the loads: weighted mean or maximum", choices=AGGREGATES),
        count("error_samples", 0, "sampled mesh errors per design (0: the scene's own errors)"),
        weight("misalignment_um", "µm", "tolerance of f_ma: samples drawn from U(−t, t)"),
        weight("base_pitch_deviation_um", "µm", "tolerance of f_pb"),
        SceneKey("max_pressure_MPa", "MPa", None, "limit of the largest Hertz pressure (penalised beyond)",
                 _POSITIVE, absent="no limit"),
        weight("pressure_penalty", "", "weight of the pressure penalty, in the objective's unit"),
        SceneKey("max_lte_um", "µm", None, "limit of the loaded TE peak-to-peak (penalised beyond)", _POSITIVE,
                 absent="no limit"),
        weight("lte_penalty", "", "weight of the loaded-TE penalty, in the objective's unit"),
        SceneKey("accuracy", "", None, "accuracy preset of the search", choices=_PRESETS,
                 absent="the scene's (`[analysis] accuracy`)"),
        SceneKey("certify", "", d["certify"], "preset at which the best candidates are evaluated again "
                 "(`none`: no certification)", choices=_PRESETS + ("none",)),
        count("certify_top", 1, "candidates certified"),
        count("population", 2, "GA population"),
        count("generations", 1, "GA generations"),
        count("starts", 1, "gradient: Latin-hypercube starts"),
        count("iterations", 1, "gradient: Adam iterations per start"),
        SceneKey("learning_rate", "", d["learning_rate"], "gradient: Adam's learning rate, in the unit cube of the bounds",
                 (0.0, 1.0, False, True)),
        SceneKey("smoothing", "", d["smoothing"], "gradient: σ₀ of the Gaussian smoothing of the objective, in "
                 "the unit cube of the bounds, annealed to 0 (0: none)", (0.0, 0.5, True, True)),
        count("smoothing_pairs", 1, "gradient: antithetic sample pairs per start and iteration when smoothing"),
        count("seed", 0, "random seed of the search and of the error samples"),
    ]
    scales = ("m_n",) * 5 + ("b",)
    for i, ((key, _), (low, high), scale) in enumerate(zip(DESIGN_KEYS, _MODULE_BOUNDS, scales)):
        keys.append(SceneKey(key, "µm" if key.endswith("_um") else "mm", None,
                             f"bounds `[lower, upper]` of y{i + 1} (`[modification] {key}`)",
                             absent=f"seed 001's: [{low:g}, {high:g}] {scale}",
                             allowed="lower < upper; within the active flank and face width"))
    return tuple(keys)


@functools.cache
def _sections() -> dict[str, Callable[[], tuple[SceneKey, ...]]]:
    """Every section but `[pair]`: section name -> the function declaring its keys (each
    built on demand: `[optimize]`'s declarations import the optimiser, which reads scene
    files)."""
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
        "optimize": _optimize_keys,
    }


def section_keys() -> dict[str, tuple[SceneKey, ...]]:
    """Every section but `[pair]`: section name -> its keys, in the order of the reference."""
    return {name: declare() for name, declare in _sections().items()}


def declared(section: str) -> tuple[SceneKey, ...]:
    """The keys of one section (not `[pair]`), in the order of the reference."""
    return _sections()[section]()


def check_declared(section: str, table: dict) -> None:
    """The declared bounds and choices of `section`'s keys in `table`, in the file's units:
    `ValueError("[section] key: must be in [low, high] unit; got value unit")`. Values of
    another type are left to the section's reader, which names them."""
    keys = {k.key: k for k in declared(section)} if section in _sections() else {}
    for name, value in table.items():
        key = keys.get(name)
        if key is None:
            continue
        if key.choices is not None and isinstance(value, str) and value not in key.choices:
            raise ValueError(f"[{section}] {name}: must be {' or '.join(repr(c) for c in key.choices)}; got {value!r}")
        if key.bounds is None:
            continue
        for v in value if isinstance(value, list) else [value]:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or _inside(v, key.bounds):
                continue
            unit = f" {key.unit}" if key.unit else ""
            shown = f"{v:g}" if isinstance(v, float) else (str(v) if len(str(v)) < 20 else f"an integer of {len(str(abs(v)))} digits")
            raise ValueError(f"[{section}] {name}: must be in {_range(key.bounds)}{unit}; got {shown}{unit}")


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


def _inside(value: float, bounds: tuple[float, float, bool, bool]) -> bool:
    low, high, low_in, high_in = bounds
    try:
        value = float(value)
    except OverflowError:  # an integer beyond the float range
        return False
    if not math.isfinite(value):
        return False
    return (value >= low if low_in else value > low) and (value <= high if high_in else value < high)


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
