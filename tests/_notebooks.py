"""Running a notebook's code cells inside the test process.

`test_notebooks.py` runs each notebook in its own Jupyter kernel, a process that traces
and compiles, or loads from the run's compilation cache, every program it calls. A
notebook whose programs are those of one test file runs instead inside that file's
process (`HOSTS`), where they are already traced and compiled: notebook 06 computes the
gradients of `test_optimize.py`'s objective, a program that is never in the cache
(`gearjax.runtime.cache`), so a kernel compiled it a second time (about 4 minutes on 2 cores);
notebook 05 runs `test_impact.py`'s scenes, notebook 02 the double-circular-arc impact program
of `test_point_impact.py`, notebook 08 the Pareto front program of `test_pareto.py`. The cells run in order in one namespace, as
a kernel runs them, with `GEARJAX_NOTEBOOK_QUICK=1` (the notebook's coarse grid, no
convergence check); a cell with IPython syntax (magics, shell escapes) is refused, since
plain Python would not run it as IPython does.
"""

from __future__ import annotations

import os
from pathlib import Path

import nbformat

NOTEBOOK_DIR = Path(__file__).resolve().parent.parent / "notebooks"
#: set to 1, a notebook runs on its coarse grid and skips its convergence check
QUICK = "GEARJAX_NOTEBOOK_QUICK"

#: notebook -> the test file that runs it in its own process (and shares its programs)
HOSTS = {"02_double_circular_arc.ipynb": "test_point_impact.py", "05_mesh_in_impact.ipynb": "test_impact.py",
         "06_optimisation.ipynb": "test_optimize.py", "08_pareto.ipynb": "test_pareto.py"}


def execute_in_process(name: str) -> dict:
    """Run the code cells of `notebooks/<name>` top to bottom; return their namespace.

    An exception in a cell propagates with the cell's number in its traceback (the cell
    is compiled under the file name `<name>[cell k]`). Figures are closed afterwards."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    nb = nbformat.read(NOTEBOOK_DIR / name, as_version=4)
    namespace: dict = {"__name__": "__main__"}
    quick = os.environ.get(QUICK)
    os.environ[QUICK] = "1"  # the notebook's coarse grid, as in a kernel (`test_notebooks.py`)
    try:
        for k, cell in enumerate(c for c in nb.cells if c.cell_type == "code"):
            lines = cell.source.splitlines()
            ipython = [line for line in lines if line.lstrip().startswith(("%", "!"))]
            if ipython:
                raise ValueError(f"{name} cell {k}: IPython syntax cannot run in process: {ipython[0]!r}")
            exec(compile(cell.source, f"{name}[cell {k}]", "exec"), namespace)
    finally:
        plt.close("all")
        if quick is None:
            del os.environ[QUICK]
        else:
            os.environ[QUICK] = quick
    return namespace
