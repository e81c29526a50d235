# The two quick-start commands: `make demo` and `make test`. Each creates or reuses .venv and
# installs everything from this repository's own files (pyproject.toml + constraints.txt).
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
OUT ?= out
# the documentation site: strict (a broken link, page, anchor or reference fails; not with
# --quiet, which hides the warnings strict mode counts); quiet about the
# MkDocs 2 notices its plugins print
MKDOCS := NO_MKDOCS_2_WARNING=1 DISABLE_MKDOCS_2_WARNING=true $(VENV)/bin/mkdocs

.PHONY: demo test test-suite test-checks test-slow wheel-check lint format bench figures docs clean

$(STAMP): pyproject.toml constraints.txt
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -c constraints.txt "torch==2.13.0"
	$(PY) -m pip install -q -c constraints.txt -e ".[dev]"
	@# the HTML map report's browser test (tests/mission/test_report.py) needs chromium
	@if ! command -v chromium >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1 \
	    && [ "$$(id -u)" = 0 ]; then \
	  echo "installing chromium (apt-get) for the HTML report test"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium \
	    >/dev/null || echo "chromium not installed: the HTML report browser test will skip"; \
	fi
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/poc-env demo --out $(OUT)/demo

test: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	@# two lanes side by side: the suite on its two workers, and the single-threaded checks
	@# (types, the strict docs build, the wheel install) that would otherwise leave a core idle
	@# for about two minutes; each lane's output is printed whole when it ends
	$(MAKE) --no-print-directory -j2 --output-sync=target test-suite test-checks

test-suite: $(STAMP)
	OMP_NUM_THREADS=1 $(PY) -m pytest -q -n 2 -m "not slow"

test-checks: $(STAMP)
	$(VENV)/bin/mypy
	$(MKDOCS) build --strict
	PYTHON=$(PY) .ci/wheel-check

# the documentation site into site/ (pages from docs/, figures from results/, the API reference
# from the docstrings); `make docs SERVE=1` serves it at http://127.0.0.1:8000 instead
docs: $(STAMP)
	$(MKDOCS) $(if $(SERVE),serve,build --strict)

# the wheel, installed without extras in a fresh venv outside the checkout (part of `make test`)
wheel-check: $(STAMP)
	PYTHON=$(PY) .ci/wheel-check

test-slow: $(STAMP)
	OMP_NUM_THREADS=1 $(PY) -m pytest -q -m slow

lint: $(STAMP)
	$(VENV)/bin/ruff check . && $(VENV)/bin/ruff format --check . && $(VENV)/bin/mypy

format: $(STAMP)
	$(VENV)/bin/ruff format . && $(VENV)/bin/ruff check --fix .

figures: $(STAMP)
	$(VENV)/bin/poc-env figures --out results/img

clean:
	rm -rf $(VENV) $(OUT) site .pytest_cache .ruff_cache
