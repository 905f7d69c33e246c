"""MkDocs hook (`hooks:` in mkdocs.yml): pages generated from the code and the stored
figures, so that they cannot drift.

* `cli.md`: the command line's reference, the `--help` of `gearjax` and of each
  sub-command as `gearjax.cli.build_parser` builds them.
* `gallery.md`: every figure of the documentation (`docs/figures/*.png`, each linked to the
  pages that show it) and of the stored notebooks (linked to its notebook).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"
NOTEBOOKS = DOCS.parent / "notebooks"
_TITLE = re.compile(r"^# (.+)$", re.M)


def cli_page() -> str:
    """The `--help` of `gearjax` and of each sub-command, at 100 columns."""
    from gearjax.cli import COMMANDS, build_parser

    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"  # argparse wraps at $COLUMNS when it formats
    try:
        parser, _ = build_parser()
        subparsers = next(a for a in parser._actions if a.dest == "command").choices
        helps = [parser.format_help()] + [subparsers[name].format_help() for name in COMMANDS]
    finally:
        if previous is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = previous
    parts = [
        "# Command line\n",
        "*Generated from the parser (`gearjax.cli.build_parser`) when the site is built.*\n",
        "Every command reads a TOML scene file ([Scene files](scene_files.md)), or runs the "
        "built-in default scene when none is given. A bad scene file or argument prints one line, "
        "`gearjax CMD: error: ...` naming the field as `[section] key: ...`, and exits with status 2; "
        "a finished run exits with 0. Compiled programs are cached on disk "
        "(`$GEARJAX_CACHE_DIR`, default `~/.cache/gearjax/jax`), so a second run of the same scene "
        "structure starts in seconds.\n",
        "```text\n" + helps[0].rstrip() + "\n```\n",
    ]
    for name, text in zip(COMMANDS, helps[1:]):
        parts.append(f"## `gearjax {name}`\n")
        parts.append("```text\n" + text.rstrip() + "\n```\n")
    return "\n".join(parts)


def _title(path: Path) -> str:
    match = _TITLE.search(path.read_text(encoding="utf-8"))
    return match[1].strip() if match else path.stem


def gallery_page(notebook_figures: dict[str, list[str]]) -> str:
    """Every documentation figure, with the pages that show it, and every notebook figure
    (`notebook_figures`: notebook page -> its figure files), with its notebook."""
    pages = sorted(DOCS.rglob("*.md"))
    parts = ["# Gallery\n", "*Every figure of the documentation and of the notebooks, generated when the site is "
             "built; each links to the page that explains it (and states its accuracy).*\n"]
    for figure in sorted((DOCS / "figures").glob("*.png")):
        shown = [p for p in pages if f"figures/{figure.name}" in p.read_text(encoding="utf-8")]
        links = ", ".join(f"[{_title(p)}]({p.relative_to(DOCS).as_posix()})" for p in shown) or "not shown on a page"
        parts.append(f"### {figure.stem.replace('_', ' ')}\n\n![{figure.stem}](figures/{figure.name})\n\nShown in: {links}.\n")
    for page, figures in notebook_figures.items():
        notebook = NOTEBOOKS / f"{Path(page).stem}.ipynb"
        parts.append(f"### Notebook {Path(page).stem.replace('_', ' ')}\n")
        parts.append(f"From [`notebooks/{notebook.name}`]({page}).\n")
        parts.extend(f"![{Path(f).stem}]({f})\n" for f in figures)
    return "\n".join(parts)


def on_files(files, config):
    from mkdocs.structure.files import File  # the hook's pages need only gearjax (tests import them)

    notebook_figures: dict[str, list[str]] = {}
    for file in files:
        path = file.src_uri
        if path.startswith("notebooks/") and path.endswith(".png"):
            notebook = path.split("/")[1]
            notebook_figures.setdefault(f"notebooks/{notebook}.md", []).append(path)
    files.append(File.generated(config, "cli.md", content=cli_page()))
    files.append(File.generated(config, "gallery.md", content=gallery_page(dict(sorted(notebook_figures.items())))))
    return files
