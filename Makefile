# The README's two commands: `make reproduce` (main job) and `make test`.
# Each creates/updates the project's own virtual environment first.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
export MPLBACKEND := Agg
export NUMBA_CACHE_DIR := $(CURDIR)/.venv/numba-cache

.PHONY: all test reproduce notebooks paper bench venv clean

all: test

venv: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test]"
	$(BIN)/python -m ipykernel install --sys-prefix --name python3 >/dev/null
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/python -m pytest -q

reproduce: $(STAMP)
	$(BIN)/python -m crfmap.repro.reproduce

bench: $(STAMP)
	$(BIN)/crfmap bench

clean:
	rm -rf out figures/*.png figures/*.pdf paper/generated/*
