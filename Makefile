# Set-up and the two everyday commands. Needs only Python 3.11+ on the PATH.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
# The real datasets' folder; empty: $REFORM_SIM_DATASETS, else ../shared/datasets when it exists,
# else the datasets fetched with `reform-sim datasets fetch`, else simulation only.
DATASETS ?=

.PHONY: demo test lint bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# The motion kernel (numba) is compiled into its cache as the last step of the install, once,
# rather than by the first simulation (about 13 s), and by each process that starts before the
# cache is written (the test suite's workers, a generate run's).
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	$(BIN)/python -c "from sim.episode import simulate_episode; simulate_episode('mingle', seed=0, duration=1.0)"
	touch $@

# dante: DANTE's tests run on PyTorch, the version the extra pins, installed first and alone: pip
# then takes a CPU build lying in its find-links (hundreds of MB), which the rest accepts; asked
# for in one call with the rest, it took a CUDA build from the index (gigabytes of downloads)
TORCH := $(shell sed -n 's/.*"\(torch==[^"]*\)".*/\1/p' pyproject.toml)
$(VENV)/.installed-test: $(VENV)/.installed
	$(BIN)/python -m pip install --quiet "$(TORCH)"
	$(BIN)/python -m pip install --quiet -e ".[test,dante]"
	touch $@

## demo: install, then run the main job on the embedded default
# --data only for a folder that exists: a DATASETS naming nothing (a clone with no
# ../shared beside it) is said, and the demo looks for the datasets itself.
demo: $(VENV)/.installed
	$(if $(DATASETS),$(if $(wildcard $(DATASETS)),,@echo "make demo: DATASETS=$(DATASETS) is not a folder here; the demo looks for the datasets itself" >&2))
	$(BIN)/reform-sim demo $(if $(wildcard $(DATASETS)),--data $(DATASETS))

## test: install with the test extras, then run the whole test suite
# TEST_JOBS: pytest-xdist's workers (auto: one a core, at most four; 0: the suite in one process)
TEST_JOBS ?= auto
test: $(VENV)/.installed-test
	REFORM_SIM_DATASETS=$${REFORM_SIM_DATASETS:-$(DATASETS)} $(BIN)/python -m pytest -n $(TEST_JOBS) --maxprocesses 4 $(PYTEST_ARGS)

lint: $(VENV)/.installed-test
	$(BIN)/ruff check reform sim scenarios tests benchmarks

## bench: every benchmark in full (figures beside a same-run baseline); stops at the first failure
# BENCH_ARGS go to every script: `make bench BENCH_ARGS=--quick` is each one's smoke run.
BENCH_ARGS ?=
bench: $(VENV)/.installed-test
	@for script in benchmarks/bench_*.py; do \
		echo "== $$script"; \
		REFORM_SIM_DATASETS=$${REFORM_SIM_DATASETS:-$(DATASETS)} $(BIN)/python $$script $(BENCH_ARGS) \
			|| { status=$$?; echo "make bench: $$script failed (exit status $$status)" >&2; exit 1; }; \
	done

clean:
	rm -rf $(VENV) build *.egg-info
