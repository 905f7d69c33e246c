"""Every notebook runs top to bottom (so none can rot): in a Jupyter kernel here, or in
the process of the test file that shares its programs (`_notebooks.HOSTS`), on its coarse
grid (`GEARJAX_NOTEBOOK_QUICK=1`); and every stored notebook holds the outputs of a full
run (`tools/run_notebooks.py`)."""

import importlib.util
from pathlib import Path

import nbformat
import pytest
from _notebooks import HOSTS, NOTEBOOK_DIR, QUICK
from nbclient import NotebookClient

ALL = sorted(NOTEBOOK_DIR.glob("*.ipynb"))
NOTEBOOKS = [p for p in ALL if p.name not in HOSTS]


def test_every_notebook_is_run_by_a_test():
    """A hosted notebook exists, and its host file has the test that runs it."""
    assert set(HOSTS) <= {p.name for p in ALL}
    for name, host in HOSTS.items():
        text = (Path(__file__).parent / host).read_text()
        assert f'execute_in_process("{name}")' in text, f"{host} does not run {name}"


def _run_notebooks_tool():
    spec = importlib.util.spec_from_file_location("run_notebooks", NOTEBOOK_DIR.parent / "tools" / "run_notebooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("path", ALL, ids=[p.name for p in ALL])
def test_every_stored_notebook_holds_a_full_run_with_a_figure(path):
    """Every code cell ran without error, at least one figure, and the outputs are those
    of a full run (`make notebooks`), not of the coarse grid the suite runs."""
    assert _run_notebooks_tool().problems(nbformat.read(path, as_version=4)) == []


def test_the_stored_output_check_finds_what_is_missing():
    tool = _run_notebooks_tool()
    nb = nbformat.read(ALL[0], as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
    assert tool.problems(nb) == ["a code cell has not run", "no figure", "the outputs are not those of a full run"]


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_executes(path, tmp_path, monkeypatch):
    monkeypatch.setenv(QUICK, "1")  # the kernel inherits it: the coarse grid, no convergence check
    # The kernels inherit the run's persistent compilation cache (`conftest.py`): a program
    # that a test file compiled is loaded, not compiled again, or the reverse.
    nb = nbformat.read(path, as_version=4)
    NotebookClient(nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors
