# The two things a newcomer does: `make paper` (the main job) and `make test`.
VENV   ?= .venv
PY     := $(VENV)/bin/python
OUT    ?= report
PAPER_FLAGS ?= --quick

.PHONY: setup setup-test paper test test-fast lint netlists clean

$(VENV)/.installed: pyproject.toml
	scripts/install-system.sh
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test,lint]'
	touch $@

setup: $(VENV)/.installed

setup-test: setup
	scripts/install-system.sh --test

# The stick board (issue 13) first, so that the paper report links it (board/index.html).
# --sweeps: the "What experiments measure" chapter's two sweep curves (issue 23); each
# point is its own circuit run (quick size), stored like every other run.
SWEEP_FLAGS ?= --sweeps
paper: setup
	$(VENV)/bin/analogue board stick $(PAPER_FLAGS) --out $(OUT)/board
	$(VENV)/bin/analogue paper $(PAPER_FLAGS) $(SWEEP_FLAGS) --out $(OUT)

test: setup-test
	$(PY) -m pytest -n 2 --dist loadgroup -q

# The edit loop: everything not marked slow (no long ngspice or statistical runs).
test-fast: setup-test
	$(PY) -m pytest -n 2 --dist loadgroup -q -m "not slow"

# ruff (pyflakes, pycodestyle, bugbear, pyupgrade) and mypy (strict on theory/ and
# estimators/, basic elsewhere): configured in pyproject.toml.
lint: setup
	$(PY) -m ruff check analogue tests benchmarks scripts setup.py
	$(PY) -m mypy

netlists: setup
	$(VENV)/bin/analogue netlist

clean:
	rm -rf $(VENV) runs report test-artifacts
