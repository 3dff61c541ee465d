# SANN: `make book` builds the executable book, `make test` runs the suite.
SHELL := /bin/bash
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
BOOK_HTML := book/_build/html/index.html

.PHONY: book test lab lint bench clean

$(STAMP): environment.txt pyproject.toml
	test -x $(PY) || python3.11 -m venv $(VENV) || python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r environment.txt
	$(PY) -m pip install --quiet --no-deps --no-build-isolation -e .
	$(PY) -c "import sys, torch; v = torch.__version__; sys.exit(0 if v.endswith('+cpu') else f'torch {v} is not the +cpu build: pip pulled a CUDA build')"
	touch $@

book: $(STAMP)
	rm -rf book/_build/html
	$(VENV)/bin/sphinx-build -W --keep-going -b html book book/_build/html
	@echo "The book is at $(abspath $(BOOK_HTML))"

# Headless Chromium for the browser tests comes from Debian (never a downloaded browser).
/usr/bin/chromium:
	apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium

test: $(STAMP) /usr/bin/chromium
	$(PY) -m pytest -n 2 --dist loadgroup --durations=10 tests

lab: $(STAMP)
	$(VENV)/bin/jupyter lab --allow-root --notebook-dir=book

lint: $(STAMP)
	$(VENV)/bin/ruff check .

bench: $(STAMP)
	$(PY) benchmarks/engine.py
	$(PY) benchmarks/blocks.py
	$(PY) benchmarks/vision.py

clean:
	rm -rf book/_build .sann-cache
