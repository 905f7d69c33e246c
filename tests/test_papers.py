"""The paper material (`gearjax.papers`) sits on top of the core: nothing in the core imports it."""

import ast
from pathlib import Path

import gearjax

PACKAGE = Path(gearjax.__file__).resolve().parent
#: May import the papers besides the package itself: the public API and the command line
#: (presentation: every module of `gearjax.cli`).
ALLOWED = {"__init__.py"}
ALLOWED_PACKAGES = {"papers", "cli"}


def imported_modules(source: str, package: str) -> set[str]:
    """Absolute names of the modules (and imported names) in `source`, a module of the
    dotted `package`; relative imports are resolved against it."""
    parts = package.split(".")
    names = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = parts[: len(parts) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            names.add(module)
            names.update(f"{module}.{alias.name}" for alias in node.names)
    return names


def imports_papers(source: str, package: str) -> bool:
    return any(n == "gearjax.papers" or n.startswith("gearjax.papers.") for n in imported_modules(source, package))


def test_the_scan_resolves_relative_imports():
    """Else the next test would prove nothing."""
    assert imports_papers("from ..papers.seed001 import paper_optimum\n", "gearjax.impact")
    assert imports_papers("from . import papers\n", "gearjax")
    assert imports_papers("import gearjax.papers.double_arc as d\n", "gearjax.tca")
    assert not imports_papers("from .papers import x\n", "gearjax.impact")  # gearjax.impact.papers
    assert not imports_papers("from ..impact.energy import impact_force\n", "gearjax.geometry")


def test_the_core_does_not_import_the_papers():
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE)
        if relative.parts[0] in ALLOWED_PACKAGES or str(relative) in ALLOWED:
            continue
        package = ".".join(("gearjax", *relative.parts[:-1]))
        if imports_papers(path.read_text(encoding="utf-8"), package):
            offenders.append(str(relative))
    assert offenders == []
