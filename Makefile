# The README's two commands: `make reproduce` (main job) and `make test`.
# Each creates/updates the project's own virtual environment first, then warms numba's cache (the
# one every entry point of .venv uses: make, `crfmap`, pytest and the Jupyter kernel).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
CORES  ?= 2
export MPLBACKEND := Agg
export NUMBA_CACHE_DIR := $(CURDIR)/.venv/numba-cache

.PHONY: all test kernel-coverage reproduce sweep slurm-sweep dry-run notebooks paper bench venv warm lab clean

all: test

venv: $(STAMP)

$(STAMP): pyproject.toml study/pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	# first what the numba warm-up imports; it then compiles on the core pip leaves idle while pip installs the rest
	# (best effort: if it fails, `make warm` compiles what it missed). Not --no-compile: where PYTHONDONTWRITEBYTECODE
	# is set (containers, CI) nothing would ever write the bytecode, and every process would compile its imports
	$(BIN)/python -m pip install --quiet $$($(BIN)/python study/crfstudy/repro/warmup.py --requirements)
	PYTHONPATH=lib:study nice -n 10 $(BIN)/python -m crfstudy.repro.warmup --jobs $(CORES) > $(VENV)/early-warmup.log 2>&1 & early=$$!; \
	  $(BIN)/python -m pip install --quiet -e ".[study,ros,test]" -e study; status=$$?; \
	  if [ $$status != 0 ]; then kill $$early 2>/dev/null; fi; \
	  wait $$early || echo "note: the numba warm-up during the install stopped early ($(VENV)/early-warmup.log)"; \
	  exit $$status
	# the Jupyter kernel and the venv's interpreter use the numba cache the make targets warm
	$(BIN)/python -m ipykernel install --sys-prefix --name python3 --env NUMBA_CACHE_DIR "$(NUMBA_CACHE_DIR)" >/dev/null
	echo "import os; os.environ.setdefault('NUMBA_CACHE_DIR', '$(NUMBA_CACHE_DIR)')" > \
	  "$$($(BIN)/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')/crfmap_numba_cache.pth"
	# notebook outputs never reach git (nbstripout filter; only in a real clone, not a worktree);
	# --keep-id: the committed cell ids stay, so installing the filter does not rewrite every notebook
	if [ -d .git ]; then $(BIN)/nbstripout --install --attributes .gitattributes && \
	  git config filter.nbstripout.clean '"$(CURDIR)/$(BIN)/python" -m nbstripout --keep-id' && \
	  git config diff.ipynb.textconv '"$(CURDIR)/$(BIN)/python" -m nbstripout --keep-id -t'; fi
	touch $(STAMP)

warm: $(STAMP)
	$(BIN)/python -m crfstudy.repro.warmup --jobs $(CORES)

# two pytest runs, both always run (make test fails if either does): everything but the notebooks as one process
# (the hostile catalogue's terminal summary included), then the notebooks' quick runs in parallel, CORES at once
test: warm
	$(BIN)/ruff check lib study tests notebooks
	status=0; \
	$(BIN)/python -m pytest -q --ignore=tests/test_notebooks.py || status=$$?; \
	$(BIN)/python -m pytest -q -n $(CORES) tests/test_notebooks.py || status=$$?; \
	exit $$status

# the kernel tests with numba's JIT off, so coverage sees the kernels' lines as Python (about 10 min; not in CI;
# tests/crf/conftest.py skips, naming them, those over 20 s of CPU as plain Python)
kernel-coverage: $(STAMP)
	NUMBA_DISABLE_JIT=1 $(BIN)/python -m pytest -q -rs -p no:cacheprovider tests/crf --cov=lib/crfmap/crf --cov-report=term

# the clock starts before the venv and the warm-up, so the record is what `make reproduce` costs
reproduce:
	@echo $$(date +%s) > .reproduce-started
	@test -e $(STAMP) || touch .reproduce-new-venv
	$(MAKE) --no-print-directory warm
	$(BIN)/python -m crfstudy.repro.reproduce --cores $(CORES) --started-at "$$(cat .reproduce-started)" \
	  $$(test -e .reproduce-new-venv && echo --new-venv)
	@rm -f .reproduce-started .reproduce-new-venv

# make sweep SWEEP=04_noise   (workflow/sweeps/04_noise.yaml -> out/runs/04_noise/; MAX_POINTS=N raises the
# limit of 200 points). Without SWEEP it would be the whole reproduction: refused before anything runs.
sweep:
	@test -n "$(strip $(SWEEP))" || { echo "make sweep: give SWEEP=name (a file of workflow/sweeps/) or SWEEP=path.yaml" >&2; exit 2; }
	$(MAKE) --no-print-directory warm
	$(BIN)/python -m crfstudy.repro.reproduce --cores $(CORES) --sweep $(SWEEP) $(if $(MAX_POINTS),--max-points $(MAX_POINTS))

# make slurm-sweep [SWEEP=02_noise_quick]: the SLURM profile for real, on a one-node cluster of this machine (needs
# root, Debian's slurm-wlm and munge): the cluster starts in a temporary folder, every point of the sweep runs as a
# SLURM job through workflow/profiles/slurm, the outputs are checked, the cluster stops (crfstudy.repro.local_slurm)
slurm-sweep: warm
	$(BIN)/python -m crfstudy.repro.local_slurm sweep $(or $(strip $(SWEEP)),02_noise_quick) --cores $(CORES)

dry-run: $(STAMP)
	$(BIN)/python -m crfstudy.repro.reproduce --dry-run

lab: warm
	$(BIN)/jupyter lab notebooks/$(if $(filter 0,$(shell id -u)), --allow-root)

bench: $(STAMP)
	$(BIN)/crfmap bench

clean:
	rm -rf out figures/*.png figures/*.pdf paper/generated/* .snakemake
