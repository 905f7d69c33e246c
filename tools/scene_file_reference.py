"""The `[pair]` key reference in `docs/scene_files.md`, generated from the families'
declarations (`gearjax.io.scene_file.pair_reference`).

    python tools/scene_file_reference.py           # print it
    python tools/scene_file_reference.py --write   # replace the block in docs/scene_files.md

`tests/test_scene_fuzz.py` checks that the page holds the generated block.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from gearjax.io.scene_file import pair_reference

PAGE = Path(__file__).resolve().parents[1] / "docs" / "scene_files.md"
START, END = "<!-- pair-keys:start (generated: tools/scene_file_reference.py) -->", "<!-- pair-keys:end -->"


def replace_block(text: str, block: str) -> str:
    """`text` with the lines between the markers replaced by `block`."""
    head, sep, rest = text.partition(START)
    if not sep or END not in rest:
        raise SystemExit(f"{PAGE}: markers {START!r} ... {END!r} not found")
    return head + START + "\n" + block + END + rest.partition(END)[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help=f"replace the block in {PAGE.name}")
    args = parser.parse_args()
    if args.write:
        PAGE.write_text(replace_block(PAGE.read_text(), pair_reference()))
        print(f"wrote the [pair] reference to {PAGE}")
    else:
        print(pair_reference(), end="")


if __name__ == "__main__":
    main()
