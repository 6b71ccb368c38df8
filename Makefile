# cnclab: the two commands are `make reproduce` and `make test`; each sets up .venv itself.
SHELL := /bin/bash
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.cnclab-installed
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
# bytecode caching on, whatever the environment says (PYTHONDONTWRITEBYTECODE is set on some CI
# machines, this one included): `make test` starts ~80 Python processes (xdist workers, notebook
# kernels, the README's and the fuzz tests' CLI runs), each importing cnclab 0.9 s faster from .pyc,
# and pytest keeps its assertion rewrites (collection 21.7 -> 10.9 s). Measured on one idle machine:
# `make test` 434 -> 397 s, 805 -> 725 CPU s. The .pyc files go to __pycache__/ (git-ignored).
export PYTHONDONTWRITEBYTECODE :=

.PHONY: reproduce test test-slow lab venv claims bench strip clean help browser-test site gcode-check tp-check

help:
	@echo "make reproduce   execute every notebook, write build/ (figures, HTML, claims report)"
	@echo "make test        unit + claims tests and every notebook in fast mode (CNCLAB_FAST=1)"
	@echo "make test-slow   the tests marked slow (skipped by make test; CI runs both)"
	@echo "make lab         open the collection in JupyterLab at notebooks/00_index.ipynb"
	@echo "make bench       run benchmarks/ and print their tables"
	@echo "make claims      print the claims ledger with freshly computed values"
	@echo "make site        build the offline site build/site/index.html from what build/ holds"
	@echo "make browser-test  JupyterLab explorer + offline site in headless Chromium (screens in build/screens)"
	@echo "make gcode-check run every written NC program through LinuxCNC's rs274 (installs it if missing)"
	@echo "make tp-check    time the tests/fixtures/linuxcnc programs with LinuxCNC's planner, headless (rewrites tp_times.json)"

venv: $(STAMP)

$(STAMP): environment.txt pyproject.toml
	@echo ">> setting up $(VENV) with $(PYTHON) from environment.txt (exact pins)"
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r environment.txt
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e .
	$(PY) -m ipykernel install --sys-prefix --name python3 --display-name "Python 3 (cnclab)" >/dev/null
	@touch $(STAMP)
	@echo ">> $(VENV) ready"

# JOBS=N notebooks at once (default: one per core); FORCE=1 ignores build/cache and executed copies
reproduce: $(STAMP)
	$(if $(FORCE),CNCLAB_NO_CACHE=1 )$(PY) -m cnclab reproduce --jobs $(or $(REPRO_JOBS),$(JOBS)) $(if $(FORCE),--force)

# --dist loadgroup: tests marked @pytest.mark.xdist_group(name) run in one worker (they share a plan
# or a fixture); every other test is handed out one at a time, longest first (tests/conftest.py)
test: $(STAMP)
	$(PY) -m cnclab warm
	CNCLAB_FAST=1 $(PY) -m pytest -n $(JOBS) --dist loadgroup --durations=15 tests

# the tests marked `slow` (skipped by `make test`), in fast mode; CI runs it after `make test`
test-slow: $(STAMP)
	CNCLAB_FAST=1 CNCLAB_SLOW=1 $(PY) -m pytest -n $(JOBS) --dist loadgroup --durations=10 -m slow tests

# JupyterLab on the collection, opened at the index notebook (Ctrl-C twice to stop)
lab: $(STAMP)
	$(VENV)/bin/jupyter lab notebooks/00_index.ipynb

site: $(STAMP)
	$(PY) -m cnclab site

# Real-browser tests (tests_browser/, not collected by `make test`): Debian chromium + chromedriver.
browser-test: $(STAMP)
	@if ! command -v chromium >/dev/null || ! command -v chromedriver >/dev/null; then \
		echo ">> installing chromium and chromium-driver (Debian)"; \
		apt-get update && apt-get install -y --no-install-recommends chromium chromium-driver; \
	fi
	CNCLAB_FAST=1 $(PY) -m pytest -p no:randomly -n 0 -v tests_browser

# every program `python -m cnclab programs` writes (fast mode when build/gcode is missing) through
# LinuxCNC's rs274: accepted, feed length/time within 0.1 %, safe rapids, spindle on before cutting
gcode-check: $(STAMP)
	@command -v rs274 >/dev/null || (apt-get update && apt-get install -y --no-install-recommends linuxcnc-uspace)
	@test -f build/gcode/manifest.json || CNCLAB_FAST=1 $(PY) -m cnclab programs || true  # failures are in the manifest
	$(PY) -m cnclab.nc.gcode_check build/gcode

tp-check: $(STAMP)
	@command -v linuxcnc >/dev/null || (apt-get update && apt-get install -y --no-install-recommends linuxcnc-uspace)
	$(PY) benchmarks/linuxcnc_tp.py

claims: $(STAMP)
	$(PY) -m cnclab claims

bench: $(STAMP)
	@for b in benchmarks/bench_*.py; do echo ">> $$b"; $(PY) $$b || exit 1; done

strip: $(STAMP)
	$(PY) -m cnclab nb strip

clean:
	rm -rf build .pytest_cache
