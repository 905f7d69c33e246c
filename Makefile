# Set-up on a fresh machine needs only Python (python3 on PATH): >= 3.10 for the library and
# `make demo`, >= 3.11 for `make test` (its pinned tools need it).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin

.PHONY: demo test bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# Creates the environment, installs gearjax and runs the built-in default scene.
demo: $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[plot]"
	$(BIN)/gearjax run

# Installs the test dependencies and runs the whole suite (notebooks included).
test: $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[dev,plot]"
	$(BIN)/python -m pytest -q -n 2 --dist loadfile --no-loadscope-reorder --durations=30

# Benchmarks are not tests: they time things and write benchmarks/results/*.json.
bench: $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[plot]"
	$(BIN)/python benchmarks/tca.py

clean:
	rm -rf $(VENV) .pytest_cache build dist *.egg-info
