# SANN: `make book` builds the executable book, `make test` runs the suite.
SHELL := /bin/bash
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
BOOK_HTML := book/_build/html/index.html
# The engine's modules that mypyc compiles: sann/soar/compiled.py's MODULES, the one list (any
# python3 reads it: the venv may not exist yet).
ENGINE := $(shell python3 sann/soar/compiled.py --sources)
COMPILED := sann/soar/_engine.sha256
# Removes the extension modules a build left beside the sources (and the group's library).
RM_ENGINE_SO := find sann/soar -name '*.so' -delete

.PHONY: book test engine lab lint bench clean

# The interpreter: Debian's python3.11 where it is (built with profile-guided and link-time
# optimization, it runs the engine about 7% faster than a plain build such as pyenv's),
# else the first python3.11 on the PATH.
DEBIAN_PYTHON := /usr/bin/python3.11

$(STAMP): environment.txt pyproject.toml
	test -x $(PY) || { test -x $(DEBIAN_PYTHON) && $(DEBIAN_PYTHON) -m venv --clear $(VENV); } \
	  || python3.11 -m venv --clear $(VENV) || python3 -m venv --clear $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r environment.txt
	$(PY) -m pip install --quiet --no-deps --no-build-isolation -e .
	$(PY) -c "import sys, torch; v = torch.__version__; sys.exit(0 if v.endswith('+cpu') else f'torch {v} is not the +cpu build: pip pulled a CUDA build')"
	touch $@

# The compiled engine: about two minutes of gcc, redone when an engine module changes. A failed
# build leaves no extension module behind (the engine then runs from its sources, slower).
$(COMPILED): $(STAMP) $(ENGINE) setup.py sann/soar/compiled.py
	rm -rf build $(COMPILED)
	$(RM_ENGINE_SO)
	$(PY) setup.py --quiet build_ext --inplace > build.log 2>&1 \
	  || { $(RM_ENGINE_SO); tail -30 build.log; echo "compiling the engine failed (build.log)"; exit 1; }
	rm -rf build build.log

engine: $(COMPILED)

# Chapters are executed only when a file they read changed (sann.bookcache: the execution cache
# and the doctrees stay in book/_build). A failed build forgets its doctrees, so that the next
# build reads the failing chapter again instead of passing on the stored one.
book: $(STAMP) $(COMPILED)
	rm -rf book/_build/html
	$(VENV)/bin/sphinx-build -W --keep-going -b html -d book/_build/doctrees book book/_build/html \
	  || { rm -rf book/_build/doctrees; exit 1; }
	@echo "The book is at $(abspath $(BOOK_HTML))"

# Headless Chromium for the browser tests comes from Debian (never a downloaded browser).
/usr/bin/chromium:
	apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium

test: $(STAMP) $(COMPILED) /usr/bin/chromium
	$(PY) -m pytest -n 2 --dist loadgroup --durations=10 tests

# The built book on 127.0.0.1, where its Soar cells run (a page opened from disk runs none).
.PHONY: serve
serve: $(STAMP)
	@test -f $(BOOK_HTML) || { echo "no built book: run make book first"; exit 1; }
	$(PY) -m sann.serve book/_build/html --port $${PORT:-8000}

lab: $(STAMP)
	$(VENV)/bin/jupyter lab --allow-root --notebook-dir=book

lint: $(STAMP)
	$(VENV)/bin/ruff check .

bench: $(STAMP) $(COMPILED)
	$(PY) benchmarks/engine.py
	$(PY) benchmarks/parsing.py
	$(PY) benchmarks/blocks.py
	$(PY) benchmarks/vision.py

# The book's caches: executed chapters (book/_build/.jupyter_cache) and datasets (.sann-cache).
clean:
	rm -rf book/_build .sann-cache build build.log $(COMPILED)
	$(RM_ENGINE_SO)
