"""The scene-file key reference in `docs/scene_files.md`, generated from the code's own
declarations: the families' `[pair]` keys (`gearjax.io.scene_file.pair_reference`) and every
other section's keys (`gearjax.io.scene_keys.reference`).

    python tools/scene_file_reference.py           # print both
    python tools/scene_file_reference.py --write   # replace the blocks in docs/scene_files.md

`tests/test_scene_fuzz.py` and `tests/test_scene_keys.py` check that the page holds the
generated blocks.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from gearjax.io.scene_file import pair_reference
from gearjax.io.scene_keys import reference

PAGE = Path(__file__).resolve().parents[1] / "docs" / "scene_files.md"
BLOCKS = {
    "pair-keys": pair_reference,
    "section-keys": reference,
}


def markers(name: str) -> tuple[str, str]:
    return f"<!-- {name}:start (generated: tools/scene_file_reference.py) -->", f"<!-- {name}:end -->"


def replace_block(text: str, name: str, block: str) -> str:
    """`text` with the lines between `name`'s markers replaced by `block`."""
    start, end = markers(name)
    head, sep, rest = text.partition(start)
    if not sep or end not in rest:
        raise SystemExit(f"{PAGE}: markers {start!r} ... {end!r} not found")
    return head + start + "\n" + block + end + rest.partition(end)[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help=f"replace the blocks in {PAGE.name}")
    args = parser.parse_args()
    if args.write:
        text = PAGE.read_text()
        for name, generate in BLOCKS.items():
            text = replace_block(text, name, generate())
        PAGE.write_text(text)
        print(f"wrote the key reference to {PAGE}")
    else:
        for generate in BLOCKS.values():
            print(generate())


if __name__ == "__main__":
    main()
