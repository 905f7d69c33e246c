"""Every notebook runs top to bottom (so none can rot): in a Jupyter kernel here, or in
the process of the test file that shares its programs (`_notebooks.HOSTS`)."""

from pathlib import Path

import nbformat
import pytest
from _notebooks import HOSTS, NOTEBOOK_DIR
from nbclient import NotebookClient

ALL = sorted(NOTEBOOK_DIR.glob("*.ipynb"))
NOTEBOOKS = [p for p in ALL if p.name not in HOSTS]


def test_every_notebook_is_run_by_a_test():
    """A hosted notebook exists, and its host file has the test that runs it."""
    assert set(HOSTS) <= {p.name for p in ALL}
    for name, host in HOSTS.items():
        text = (Path(__file__).parent / host).read_text()
        assert f'execute_in_process("{name}")' in text, f"{host} does not run {name}"


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_executes(path, tmp_path):
    # The kernels inherit the run's persistent compilation cache (`conftest.py`): a program
    # that a test file compiled is loaded, not compiled again, or the reverse.
    nb = nbformat.read(path, as_version=4)
    NotebookClient(nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors
