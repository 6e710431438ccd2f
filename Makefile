PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
DEMO ?= evaluate.py
PYTEST_ARGS ?=
# `make test` leaves out the tests marked slow (the long adversarial runs); `make test-slow`
# runs only those. CI runs both. Each runs on one pytest-xdist worker per core (PYTEST_WORKERS=0:
# in one process), hands idle workers the tests left on busy ones (worksteal), and lists its 20
# slowest tests; tests/conftest.py prints the run's wall time beside its budget.
PYTEST_MARK ?= not slow
PYTEST_WORKERS ?= auto
PYTEST_RUN = $(BIN)/python -m pytest -q -n $(PYTEST_WORKERS) --dist worksteal --durations=20

.PHONY: install test test-slow demo bench lint docs schema clean

install: $(STAMP)

$(STAMP): pyproject.toml setup.py constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -c constraints.txt -e ".[dev,render,drifters,experiments,rl,jax,drifters-check,patrol-check,distributed,docs]"
	touch $@

test: $(STAMP)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PYTEST_RUN) -m "$(PYTEST_MARK)" $(PYTEST_ARGS)

test-slow: $(STAMP)
	SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy $(PYTEST_RUN) -m slow $(PYTEST_ARGS)

# The main job: evaluate.py on the default config, configs/eval_default.yaml
# (`make demo DEMO="-m bounce_gym.demo"` runs the short simulator demo instead).
demo: $(STAMP)
	$(BIN)/python $(DEMO)

bench: $(STAMP)
	$(BIN)/python -m benchmarks.run

# The docs site into site/ (mkdocs.yml); --strict: any warning (a broken link, a docstring that
# does not render) fails the build.
docs: $(STAMP)
	SDL_VIDEODRIVER=dummy NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

# The JSON Schemas of the configurations (configs/schema/), regenerated from their models after a
# change to a configuration key (a test fails while a shipped schema is stale).
schema: $(STAMP)
	$(BIN)/bounce-gym schema --write

# ruff, the import layers (pyproject [tool.importlinter]) and mypy on the public API
# (pyproject [tool.mypy])
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/lint-imports
	$(BIN)/mypy

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache .mypy_cache .hypothesis build dist site *.egg-info
	find . -name __pycache__ -type d -prune -exec rm -rf {} +
