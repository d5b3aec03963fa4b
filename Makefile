# Two entry points for a fresh machine: `make run` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
# `make run` needs only the core; `make test` (CI) installs every extra so all tests run.
CORE_STAMP := $(VENV)/.installed-core
FULL_STAMP := $(VENV)/.installed-all

.PHONY: run test lint bench clean install

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

# pip shows its progress on the long steps (a full install takes several minutes).
$(CORE_STAMP): $(BIN)/python pyproject.toml
	$(BIN)/pip install -e .
	touch $(CORE_STAMP)

# torch is pinned first so no extra (train, rllib) pulls another version; the build (CPU or CUDA)
# is whichever pip's index offers (README, Install).
# The rllib extra pins gymnasium==1.2.2 (Ray RLlib's exact pin), so the tests run on that.
$(FULL_STAMP): $(BIN)/python pyproject.toml
	$(BIN)/pip install torch==2.13.0
	$(BIN)/pip install -e '.[train,dev,multiagent,rllib]'
	touch $(CORE_STAMP) $(FULL_STAMP)

install: $(FULL_STAMP)

run: $(CORE_STAMP)
	$(BIN)/flowrun baseline configs/sugiyama.yaml

test: $(FULL_STAMP)
	$(BIN)/ruff check flowrun tests bench examples
	$(BIN)/mypy
	$(BIN)/lint-imports
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --quiet
	$(BIN)/python -m pytest -q --durations=15

bench: $(FULL_STAMP)
	$(BIN)/python bench/ring.py

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache .grimp_cache .import_linter_cache site
