"""Run the notebooks and store their outputs (text and figures) in the files.

    python tools/run_notebooks.py                 # every notebook, full run
    python tools/run_notebooks.py 04_ltca 05      # the notebooks whose names start so
    python tools/run_notebooks.py --check         # only check what is stored

The notebooks are their own source: edit them in Jupyter, then run this to store their
outputs. A full run computes every result at the accuracy its notebook states and ends with
that notebook's convergence check against a finer setting; it takes minutes per notebook
(`make notebooks` runs them all). Each notebook is written as soon as it has run, so an
interrupted run keeps what it finished; a notebook with an error is not written, and the
command exits with status 1 naming it.

`--check` reads the stored notebooks only: every code cell ran, no cell raised, at least
one figure, and the outputs come from a full run (the accuracy cell printed the setting of
the check, which a run with `GEARJAX_NOTEBOOK_QUICK=1` does not). The test suite runs the
same check (`tests/test_notebooks.py`).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import nbformat

NOTEBOOK_DIR = Path(__file__).resolve().parent.parent / "notebooks"
#: what the accuracy cell of a full run prints (and a quick run does not)
FULL_RUN_MARK = "; check: "


def problems(nb) -> list[str]:
    """What is wrong with the stored outputs of a notebook (empty when nothing is)."""
    code = [c for c in nb.cells if c.cell_type == "code"]
    outputs = [o for c in code for o in c.get("outputs", [])]
    found = []
    if any(c.get("execution_count") is None for c in code):
        found.append("a code cell has not run")
    if any(o.get("output_type") == "error" for o in outputs):
        found.append("a cell raised an error")
    if not any("image/png" in o.get("data", {}) for o in outputs):
        found.append("no figure")
    text = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    if FULL_RUN_MARK not in text:
        found.append("the outputs are not those of a full run")
    return found


def run(path: Path, timeout: float) -> None:
    """Execute `path` in a fresh kernel (its cells' working directory: the notebooks folder)
    and write it back with its outputs."""
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    env_quick = os.environ.pop("GEARJAX_NOTEBOOK_QUICK", None)  # a full run, whatever the shell says
    try:
        NotebookClient(nb, timeout=timeout, kernel_name="python3",
                       resources={"metadata": {"path": str(path.parent)}}).execute()
    finally:
        if env_quick is not None:
            os.environ["GEARJAX_NOTEBOOK_QUICK"] = env_quick
    nbformat.write(nb, path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="*", help="notebooks whose file names start with these (default: all)")
    parser.add_argument("--check", action="store_true", help="check the stored outputs, run nothing")
    parser.add_argument("--timeout", type=float, default=3600.0, help="seconds per cell (default 3600)")
    args = parser.parse_args(argv)
    paths = sorted(p for p in NOTEBOOK_DIR.glob("*.ipynb")
                   if not args.names or any(p.name.startswith(n) for n in args.names))
    if not paths:
        print(f"run_notebooks: no notebook in {NOTEBOOK_DIR} matches {args.names}", file=sys.stderr)
        return 2
    failed = []
    for path in paths:
        if not args.check:
            start = time.perf_counter()
            try:
                run(path, args.timeout)
            except Exception as err:  # noqa: BLE001 - report the notebook, go on with the next
                print(f"{path.name}: failed ({type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''})")
                failed.append(path.name)
                continue
            print(f"{path.name}: ran in {time.perf_counter() - start:.0f} s")
        found = problems(nbformat.read(path, as_version=4))
        if found:
            failed.append(path.name)
        print(f"{path.name}: {'; '.join(found) if found else 'outputs complete'}")
    if failed:
        print(f"run_notebooks: {len(failed)} notebook(s) need attention: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
