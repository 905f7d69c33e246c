"""The package's layout stays readable (`docs/architecture.md`): a few top-level modules,
no import cycle, small modules and functions, and no project history in the code.

Static checks on the source (nothing is imported or compiled).
"""

import ast
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "gearjax"
SOURCES = sorted(PACKAGE.rglob("*.py"))
#: the limits `docs/architecture.md` states
TOP_LEVEL_MODULES, MODULE_LINES, FUNCTION_LINES = 10, 400, 60


def _name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_name(p): p for p in SOURCES}


def _imports(name: str) -> set[str]:
    """The package's modules that module `name` imports anywhere: at its top level, inside
    functions and under `TYPE_CHECKING` (a deferred import still ties the two modules
    together, so it may close no cycle either)."""
    path = MODULES[name]
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name in MODULES}
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")[: len(package.split(".")) - node.level + 1] if node.level else []
            target = ".".join(base + ([node.module] if node.module else []))
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found |= {sub} if sub in MODULES else ({target} if target in MODULES else set())
    return found - {name}


def _cycle() -> list[str] | None:
    """One import cycle among the package's modules, or None."""
    graph = {name: _imports(name) for name in MODULES}
    state: dict[str, int] = {}  # 1 on the current path, 2 done

    def visit(name, path):
        state[name] = 1
        for nxt in sorted(graph[name]):
            if state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            if nxt not in state and (found := visit(nxt, path + [nxt])):
                return found
        state[name] = 2
        return None

    for name in sorted(graph):
        if name not in state and (found := visit(name, [name])):
            return found
    return None


def test_no_import_cycle():
    assert _cycle() is None


def test_an_import_cycle_would_be_found(monkeypatch):
    real = _imports
    monkeypatch.setitem(globals(), "_imports", lambda name: real(name) | ({"gearjax.pipeline"} if name == "gearjax.accuracy" else set()))
    assert _cycle() is not None  # pipeline imports accuracy (through the stages)


def test_few_top_level_modules():
    top = sorted(p.name for p in PACKAGE.glob("*.py") if p.name != "__init__.py")
    assert len(top) <= TOP_LEVEL_MODULES, top


@pytest.mark.parametrize("path", SOURCES, ids=[_name(p) for p in SOURCES])
def test_small_modules_and_functions(path):
    """At most 400 lines per module; at most 60 lines per function body, its docstring
    not counted."""
    text = path.read_text()
    assert len(text.splitlines()) <= MODULE_LINES
    long = []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body[1:] if ast.get_docstring(node) is not None and len(node.body) > 1 else node.body
            if node.end_lineno - body[0].lineno + 1 > FUNCTION_LINES:
                long.append(f"{node.name} (line {node.lineno})")
    assert long == []


#: issue references ("issue 12", "#12") and ISO dates: history belongs in git and docs/decisions/
HISTORY = re.compile(r"\bissues? ?#?\d+|(?<![\w&])#\d{1,4}\b|\b20\d\d-\d\d-\d\d\b", re.IGNORECASE)


@pytest.mark.parametrize("path", SOURCES, ids=[_name(p) for p in SOURCES])
def test_no_project_history_in_the_code(path):
    found = [line.strip() for line in path.read_text().splitlines() if HISTORY.search(line)]
    assert found == []


def test_the_history_pattern_finds_what_it_should():
    assert HISTORY.search("see issue #12") and HISTORY.search("(#36)") and HISTORY.search("measured 2026-11-27")
    assert not HISTORY.search("color = '#1f77b4'") and not HISTORY.search("x[#]")
