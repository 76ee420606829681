# Two commands do everything on a fresh machine:
#   make test   create .venv if missing, install granstokes, run pytest
#   make demo   create .venv if missing, install granstokes, run the demo and write its report
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
DEMO   ?= demo-out

.PHONY: test demo bench mutants clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[test]'
	$(BIN)/python -m granstokes.continuum.warmup
	touch $@

# the suite on every core (pytest-xdist), each test file on one worker: its module fixtures built once
test: $(STAMP)
	$(BIN)/python -m pytest -q -n auto --dist loadfile

demo: $(STAMP)
	$(BIN)/granstokes demo --out $(DEMO)

bench: $(STAMP)
	$(BIN)/python bench/work_precision.py
	$(BIN)/granstokes stability --out bench/stability
	$(BIN)/python bench/dem_throughput.py
	$(BIN)/python bench/cg_rate.py
	$(BIN)/python bench/dem_cost_noise.py

# mutation testing of the comparison's statistics and conventions (mutmut, run in build/mutants/: see docs/testing.md);
# every mutant by default; MUTANTS_DIGITS=147 runs the 30% numbered *1, *4 or *7
MUTANTS_DIGITS ?= 0123456789
mutants: $(STAMP)
	$(BIN)/python -m pip install -q -e '.[test,mutants]'
	$(BIN)/python bench/mutants.py --digits $(MUTANTS_DIGITS)

clean:
	rm -rf $(VENV) $(DEMO) *.egg-info build/mutants
