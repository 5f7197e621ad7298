# Two commands on a fresh machine (Python 3.11 + pip): `make demo`, `make test`.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
OUT ?= toolpoint-out

.PHONY: demo test test-slow lint browser bench docs readme-check clean

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/toolpoint reproduce --out $(OUT)

# ruff (pyflakes + pycodestyle), the one-way import layers (import-linter), then the fast tier of the tests and
# doctests on both cores; `make test-slow` runs the slow tier (statistical and end-to-end checks; CI runs both).
# pytest keeps its rewritten test modules in __pycache__ even where PYTHONDONTWRITEBYTECODE is set: rewriting the
# asserts is ~6.5 s of each worker's ~13 s collection, saved on every run after the first. The fast tier's workers
# each start on one half of the tests and steal from the other's: a module's tests stay on one worker, and with them
# its cached records and fixtures (2026-12-07, 2-core VM: 199 s → 175–182 s, 374 → 329–342 s of CPU)
PYTEST := PYTHONDONTWRITEBYTECODE= $(PY) -m pytest
test: lint browser
	$(PYTEST) -q -n 2 --dist worksteal -m "not slow"

test-slow: $(STAMP) browser
	$(PYTEST) -q -n 2 --maxschedchunk 1 -m slow

# The report's browser test needs Chromium (Debian's package); installed here when this user may.
browser:
	@command -v chromium >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; \
	  else echo "note: Chromium is not installed and cannot be installed here; the browser test will be skipped"; fi; }

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks
	$(VENV)/bin/lint-imports

bench: $(STAMP)
	$(PY) -m pip install --quiet -e ".[test,bench]"
	for b in benchmarks/bench_*.py; do echo "== $$b"; OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 $(PY) $$b || exit 1; done

# The HTML documentation (Sphinx + numpydoc API reference, the design notes, a gallery that runs the tour's
# examples) → docs/_build/html; warnings are errors.
docs: $(STAMP)
	$(PY) -m pip install --quiet -e ".[test,docs]"
	$(VENV)/bin/sphinx-build -W --keep-going -q -b html docs docs/_build/html
	@echo "documentation: docs/_build/html/index.html"

# Rerun the README's campaign figures and fail when one drifts (Table 1: tests/test_readme.py, slow tier)
readme-check: $(STAMP)
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 $(PY) benchmarks/readme_check.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache docs/_build docs/api/generated docs/gallery
