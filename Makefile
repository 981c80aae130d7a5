# Two commands for a fresh machine (README.md):
#   make book   build every figure, table, the ledger and the HTML book at full thesis fidelity
#   make pdf    the whole book as one PDF (book/_build/latex/asoc-companion.pdf)
#   make test   run the tests (unit, doctests, papermill at ci fidelity, nbval, the book in Chromium,
#               the wheel in a fresh venv, the kill test) on both cores, as the farthest emulated
#               CPU computes (the committed outputs come from the machine's own kernels, so nbval
#               compares two CPUs)
# Both create or refresh .venv from environment.txt themselves. `make book` is incremental:
# a notebook is re-executed only when its cells, its parameters, a module it imports
# (directly or transitively), environment.txt or the values it quotes changed, or its
# committed outputs are incomplete (figures/values/manifest.json); `make -B book` rebuilds
# everything, independent notebooks in parallel on all cores.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
# `make -B` / `--always-make`: pass --force to reproduce and --all to jupyter-book
ALWAYS := $(findstring B,$(firstword -$(MAKEFLAGS)))
# pytest workers (pytest-xdist); tests of one notebook share a worker (--dist loadgroup). Each
# worker and the kernels it starts compute on one BLAS thread: JOBS workers fill JOBS cores, and
# OpenBLAS threads that wait for a busy core cost more than they gain (measured: 572 s with two
# threads per worker, 505 s with one)
JOBS   ?= 2
ONE_THREAD := OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
# Emulating other x86-64 CPUs (book/architecture.md, "Portability and tolerances"): OpenBLAS kernels of another core
# type, and NumPy's own SIMD dispatch with the AVX-512 (X86_V4) or also the AVX2 (X86_V3)
# groups switched off. test-portable runs every corner; make test runs the farthest one, and
# test-native the machine's own kernels.
CORETYPES    ?= Sandybridge Prescott Haswell
FAR_CORETYPE ?= Prescott
FAR_DISABLED ?= X86_V3 X86_V4
# what runs on an emulated CPU: every numerical test and every notebook at ci fidelity
# (not the book build, the wheel or the kill test, which do not depend on the CPU's kernels)
PORTABLE_TESTS := -q -p no:cacheprovider -n $(JOBS) --dist loadgroup -m "not book and not packaging" \
                  --ignore=tests/companion/test_crash_safety.py

# Debian's TeX Live for the PDF: XeLaTeX, the LaTeX packages Sphinx's writer loads, latexmk,
# the FreeFont family it typesets with, and poppler-utils (the PDF test reads the result)
TEX_PACKAGES := texlive-xetex texlive-latex-extra texlive-science texlive-fonts-recommended latexmk \
                fonts-freefont-otf poppler-utils

.PHONY: lint venv figures ledger book html pdf test test-native test-portable bench clean chromium tex

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

# The PDF from the committed notebooks (nothing is re-executed), like `make html`
pdf: venv tex
	$(PY) -m asoc_companion.book
	$(PY) -m asoc_companion.printing $(if $(ALWAYS),--all)

chromium:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null; }

tex:
	@command -v xelatex >/dev/null && command -v latexmk >/dev/null && command -v pdftotext >/dev/null && \
	  fc-list | grep -q FreeSerif || \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
	    $(TEX_PACKAGES) >/dev/null; }

# The whole suite once, on the farthest corner of the emulation matrix: the oldest OpenBLAS
# kernels and NumPy without its AVX2 and AVX-512 code paths (as fast as the native kernels on
# these small matrices). Results must not depend on the last bits of a CPU.
test: venv chromium tex lint
	$(ONE_THREAD) OPENBLAS_CORETYPE=$(FAR_CORETYPE) NPY_DISABLE_CPU_FEATURES="$(FAR_DISABLED)" \
	  $(PY) -m pytest -n $(JOBS) --dist loadgroup

# The linter (configured in pyproject.toml): fails on a finding.
lint: venv
	$(VENV)/bin/ruff check --no-cache src tests

# The same suite with this machine's own kernels.
test-native: venv chromium tex
	$(ONE_THREAD) $(PY) -m pytest -n $(JOBS) --dist loadgroup

# Every corner: each OpenBLAS core type with NumPy's X86_V4 off, and with X86_V3 and X86_V4 off.
test-portable: venv
	@set -e; for core in $(CORETYPES); do for disabled in "X86_V4" "X86_V3 X86_V4"; do \
	  echo "== OPENBLAS_CORETYPE=$$core NPY_DISABLE_CPU_FEATURES=\"$$disabled\""; \
	  $(ONE_THREAD) OPENBLAS_CORETYPE=$$core NPY_DISABLE_CPU_FEATURES="$$disabled" \
	    $(PY) -m pytest $(PORTABLE_TESTS); \
	done; done

# The benchmark suite (pytest-benchmark, one process): medians against targets, in-process ratios.
bench: venv
	$(PY) -m pytest tests/benchmarks --benchmark-only -p no:cacheprovider -q

clean:
	rm -rf book/_build book/_static/mathjax
