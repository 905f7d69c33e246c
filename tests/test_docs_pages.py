"""The documentation pages generated when the site is built (`tools/docs_reference.py`):
the command-line reference and the gallery."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import docs_reference  # noqa: E402


def test_the_cli_page_shows_every_command_and_option():
    from gearjax.cli import COMMANDS, build_parser

    page = docs_reference.cli_page()
    parser, _ = build_parser()
    subparsers = next(a for a in parser._actions if a.dest == "command").choices
    for name in COMMANDS:
        assert f"## `gearjax {name}`" in page
        for action in subparsers[name]._actions:
            for option in action.option_strings:
                assert option in page, (name, option)


def test_every_documentation_figure_is_shown_on_a_page_and_in_the_gallery():
    figures = sorted((ROOT / "docs" / "figures").glob("*.png"))
    assert figures
    page = docs_reference.gallery_page({"notebooks/01_involute_tca.md": ["notebooks/01_involute_tca/cell03_0.png"]})
    assert "not shown on a page" not in page
    for figure in figures:
        assert f"(figures/{figure.name})" in page
    assert "![cell03_0](notebooks/01_involute_tca/cell03_0.png)" in page
