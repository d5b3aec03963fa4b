# Two entry points for a fresh machine: `make run` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test lint bench clean install

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

# torch is pinned first so the train extra never pulls a multi-GB CUDA build.
$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/pip install --quiet torch==2.13.0
	$(BIN)/pip install --quiet -e '.[train,dev,multiagent]'
	touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	$(BIN)/flowrun baseline configs/sugiyama.yaml

test: $(STAMP)
	$(BIN)/ruff check flowrun tests bench examples
	$(BIN)/mypy
	$(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/python bench/ring.py

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache
