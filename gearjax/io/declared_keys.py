"""A scene-file key's declaration (`SceneKey`) and the check of a section's table against
its keys (`check_keys`), in the file's units. Each section's keys are declared where its
reader lives: `gearjax.io.scene_keys` for the scene's sections, `gearjax.optimize.settings`
for `[optimize]`; `scene_keys.reference()` writes them all."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

INF = float("inf")


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
            parts.append(("integer in " if self.integer else "") + range_text(self.bounds))
        if self.allowed:
            parts.append(self.allowed)
        return "; ".join(parts)

    def default_text(self) -> str:
        return f"`{toml_value(self.default)}`" if self.default is not None else self.absent


def range_text(bounds: tuple[float, float, bool, bool]) -> str:
    """`[low, high]`, `(low, ∞)`, ...: an interval as the reference and the errors print it."""
    low, high, low_in, high_in = bounds
    opens = "[" if low_in and abs(low) != INF else "("
    closes = "]" if high_in and abs(high) != INF else ")"
    return f"{opens}{_num(low)}, {_num(high)}{closes}"


def _num(value: float) -> str:
    return "∞" if value == INF else "−∞" if value == -INF else f"{value:g}"


def toml_value(value) -> str:
    """A value as it is written in a scene file."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return repr(value)


def _inside(value: float, bounds: tuple[float, float, bool, bool]) -> bool:
    low, high, low_in, high_in = bounds
    try:
        value = float(value)
    except OverflowError:  # an integer beyond the float range
        return False
    if not math.isfinite(value):
        return False
    return (value >= low if low_in else value > low) and (value <= high if high_in else value < high)


def check_keys(section: str, keys, table: dict) -> None:
    """The bounds and choices of `keys` (`SceneKey`s of `section`) for the values in
    `table`, in the file's units: `ValueError("[section] key: must be in [low, high] unit;
    got value unit")`. Keys not declared and values of another type are left to the
    section's reader, which names them."""
    declared = {k.key: k for k in keys}
    for name, value in table.items():
        key = declared.get(name)
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
            raise ValueError(f"[{section}] {name}: must be in {range_text(key.bounds)}{unit}; got {shown}{unit}")
