# handbench: two commands do all set-up on a fresh machine.
#   make serve   -> creates .venv if missing, installs, runs the design explorer
#   make test    -> creates .venv if missing, installs test extras (+ Debian chromium as root),
#                   then lint, format check, type check, all tests (browser tests included)
#   make test-fast -> lint and the fast tests only (the edit loop; CI runs make test)
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
CHROMIUM := /usr/bin/chromium
HOST ?= 127.0.0.1
PORT ?= 8080

.PHONY: serve test test-fast lint typecheck pytest chromium setup sweep bench clean

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	@touch $(STAMP)

# setup also warms numba's on-disk cache of the compiled kernels, engine and force closure
# (their first call compiles for about a minute; every later process loads the machine code
# in under a second), and caches the built-in objects' palm stages, which every design
# shares (docs/cost-model.md; about 10 s once, then a second to check)
setup: $(STAMP)
	$(PY) -m app.quality.warm
	$(PY) -m app.runs.palm_cache

chromium:
	@if [ -x $(CHROMIUM) ]; then :; \
	elif [ "$$(id -u)" = "0" ]; then \
	  echo "installing Debian chromium for the browser tests"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null) \
	    || { echo "could not install chromium with apt-get"; exit 1; }; \
	else \
	  echo "browser tests need Debian's chromium at $(CHROMIUM): run 'sudo apt-get install chromium'"; \
	  echo "(without it the browser tests are skipped with this message)"; \
	fi

serve: setup
	$(VENV)/bin/handbench serve --host $(HOST) --port $(PORT)

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

typecheck: $(STAMP)
	$(VENV)/bin/pyright

# (warm first: tests that time worker pools must not time numba compiling in every worker)
pytest: $(STAMP) chromium
	$(PY) -m app.quality.warm
	$(PY) -m pytest -q

test: lint typecheck pytest

# the edit loop: no browser, Ray, process pool or subprocess tests (under a minute)
FAST := not (browser or ray or pool or subprocess or slow)
test-fast: $(STAMP)
	$(VENV)/bin/ruff check .
	$(PY) -m pytest -q -m "$(FAST)"

sweep: setup
	$(VENV)/bin/handbench sweep --out out/sweep

bench: $(STAMP)
	$(PY) benchmarks/bench_hand_rebuild.py

clean:
	rm -rf build out .pytest_cache .ruff_cache
