"""Every notebook runs top to bottom (so none can rot)."""

from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

NOTEBOOKS = sorted((Path(__file__).resolve().parent.parent / "notebooks").glob("*.ipynb"))


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_executes(path, tmp_path):
    # The kernels inherit the run's persistent compilation cache (`conftest.py`): notebook 06
    # loads the GA batch and `simulate` programs that `test_optimize.py` compiled, or the
    # reverse. Its gradient program is never in the cache (`gearjax.cache`: loading it
    # crashed the kernel with jaxlib 0.10.2), so the kernel compiles that one itself.
    nb = nbformat.read(path, as_version=4)
    NotebookClient(nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors
