# Set-up on a fresh machine needs only Python. The environment is made from the newest
# Python >= 3.12 found (on PATH, then pyenv's installed versions), which gets a current JAX;
# with only an older one (>= 3.10 for the library and `make demo`, >= 3.11 for `make test`)
# it gets jax 0.10.2 and says what that costs. `make PYTHON=/path/to/python ...` picks one.
PYTHON ?=
VENV   := .venv
BIN    := $(VENV)/bin

.PHONY: demo test docs notebooks bench clean

# Creates the environment, installs gearjax and runs the built-in default scene.
demo:
	sh tools/setup_env.sh $(VENV) plot $(PYTHON)
	$(BIN)/gearjax run

# Installs the test dependencies and runs the whole suite (notebooks included).
test:
	sh tools/setup_env.sh $(VENV) dev,plot $(PYTHON)
	$(BIN)/python -m pytest -q -n 2 --dist loadfile --no-loadscope-reorder --durations=30

# Builds the documentation site into site/ (mkdocs-material, API reference from the
# docstrings); --strict: a broken link or a docstring the reference cannot read fails it.
docs:
	sh tools/setup_env.sh $(VENV) docs $(PYTHON)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

# Runs every notebook and stores its outputs (figures, printed results and the convergence
# check) in the file: minutes per notebook.
notebooks:
	sh tools/setup_env.sh $(VENV) dev,plot $(PYTHON)
	$(BIN)/python tools/run_notebooks.py

# Benchmarks are not tests: they time things and write benchmarks/results/*.json.
bench:
	sh tools/setup_env.sh $(VENV) bench $(PYTHON)
	$(BIN)/python benchmarks/tca.py

clean:
	rm -rf $(VENV) .pytest_cache build dist site *.egg-info
