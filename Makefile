# Two commands for a fresh machine (README.md):
#   make book   build every figure, table, the ledger and the HTML book at full thesis fidelity
#   make test   run the tests (unit, papermill at ci fidelity, nbval, the book in Chromium),
#               then the notebook tests again under another CPU's BLAS kernels (test-portable)
# Both create or refresh .venv from environment.txt themselves. `make book` is incremental:
# a notebook is re-executed only when it, its parameters, src/asoc or environment.txt
# changed (figures/values/manifest.json); `make -B book` rebuilds everything.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
# `make -B` / `--always-make`: pass --force to reproduce and --all to jupyter-book
ALWAYS := $(findstring B,$(firstword -$(MAKEFLAGS)))
# another CPU's BLAS kernels for test-portable (OpenBLAS; Haswell, Sandybridge, Prescott, ...)
PORTABLE_CORETYPE ?= Sandybridge

.PHONY: venv figures ledger book html test test-portable bench clean chromium

venv: $(STAMP)

$(STAMP): environment.txt pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r environment.txt
	$(PY) -m pip install --quiet --no-deps --no-build-isolation -e .
	touch $(STAMP)

figures: venv
	$(PY) -m asoc_companion reproduce --fidelity full $(if $(ALWAYS),--force)

ledger: venv
	$(PY) -m asoc_companion ledger

html: venv
	$(PY) -m asoc_companion.book
	$(VENV)/bin/jupyter-book build book --quiet $(if $(ALWAYS),--all)

book: figures html
	@echo "The book is at book/_build/html/index.html"

chromium:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null; }

test: venv chromium
	$(PY) -m pytest
	$(MAKE) --no-print-directory test-portable

# The notebook comparisons and nbval once more under other BLAS kernels: results must not
# depend on the last bits of a CPU's floating-point kernels (DESIGN.md, "Portability").
test-portable: venv
	OPENBLAS_CORETYPE=$(PORTABLE_CORETYPE) $(PY) -m pytest -q -m notebook tests/test_notebooks.py tests/test_nbval.py

bench: venv
	$(PY) -m asoc_companion.bench

clean:
	rm -rf book/_build book/_static/mathjax
