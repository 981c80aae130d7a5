# Two commands for a fresh machine (README.md):
#   make book   build every figure, table, the ledger and the HTML book at full thesis fidelity
#   make test   run the tests (unit, papermill at ci fidelity, nbval, the book in Chromium)
# Both create or refresh .venv from environment.txt themselves.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: venv figures ledger book html test bench clean chromium

venv: $(STAMP)

$(STAMP): environment.txt pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r environment.txt
	$(PY) -m pip install --quiet --no-deps --no-build-isolation -e .
	touch $(STAMP)

figures: venv
	$(PY) -m asoc reproduce --fidelity full

ledger: venv
	$(PY) -m asoc ledger

html: venv
	$(PY) -m asoc.repro.book
	$(VENV)/bin/jupyter-book build book --quiet

book: figures html
	@echo "The book is at book/_build/html/index.html"

chromium:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null; }

test: venv chromium
	$(PY) -m pytest

bench: venv
	$(PY) -m asoc.bench

clean:
	rm -rf book/_build book/_static/mathjax
