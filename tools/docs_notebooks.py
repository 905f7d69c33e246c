"""MkDocs hook (`hooks:` in mkdocs.yml): the stored notebooks (`notebooks/*.ipynb`) as pages of the site.

Each notebook becomes `notebooks/<name>.md`: its markdown cells as they are, its code cells
as Python blocks, their text output as text blocks and their figures as PNG files beside
the page. Nothing is executed: the pages show the outputs stored in the notebooks
(`tools/run_notebooks.py` stores them).
"""

from __future__ import annotations

import base64
from pathlib import Path

import nbformat
from mkdocs.structure.files import File

NOTEBOOK_DIR = Path(__file__).resolve().parents[1] / "notebooks"


def _text(output) -> str | None:
    """The text of one output, or None (a figure, or nothing to show)."""
    kind = output.get("output_type")
    if kind == "stream":
        return output.get("text", "")
    if kind == "error":
        return "\n".join(output.get("traceback", []))
    data = output.get("data", {})
    if "image/png" in data:
        return None
    return data.get("text/plain")


def page(path: Path) -> tuple[str, dict[str, bytes]]:
    """The page's markdown and its figures (file name -> PNG bytes)."""
    nb = nbformat.read(path, as_version=4)
    parts = []
    figures: dict[str, bytes] = {}
    for k, cell in enumerate(nb.cells):
        if cell.cell_type == "markdown":
            parts.append(cell.source + "\n")
            if k == 0:  # after the title
                parts.append(f"*The notebook `notebooks/{path.name}`, shown with the outputs stored in it.*\n")
            continue
        if cell.cell_type != "code":
            continue
        parts.append(f"```python\n{cell.source}\n```\n")
        for j, output in enumerate(cell.get("outputs", [])):
            png = output.get("data", {}).get("image/png")
            if png:
                name = f"{path.stem}/cell{k:02d}_{j}.png"
                figures[name] = base64.b64decode(png)
                parts.append(f"![figure of cell {k}]({name})\n")
                continue
            text = _text(output)
            if text:
                parts.append(f"```text\n{text.rstrip()}\n```\n")
    return "\n".join(parts), figures


def on_files(files, config):
    for path in sorted(NOTEBOOK_DIR.glob("*.ipynb")):
        markdown, figures = page(path)
        files.append(File.generated(config, f"notebooks/{path.stem}.md", content=markdown))
        for name, data in figures.items():
            files.append(File.generated(config, f"notebooks/{name}", content=data))
    return files
