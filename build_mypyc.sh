#!/bin/bash
# Experiment (branch mypyc): compile the hot modules of sann/soar with mypyc, as native
# extension modules beside their .py (Python imports the .so first; `clean` = delete them).
#   MYPYC=/path/to/mypyc PYTHON=.venv/bin/python ./build_mypyc.sh
# mypyc comes from the `mypy` package (any venv of the same Python 3.11); needs gcc and the
# Python headers.  About 1.5 minutes on one core (gcc -O3 on ~200k lines of C).
set -e
cd "$(dirname "$0")"
MYPYC=${MYPYC:-mypyc}
PYTHON=${PYTHON:-.venv/bin/python}
# build/: setuptools would reuse objects of another MYPYC_OPT_LEVEL
rm -rf build sann/soar/*.so ./*__mypyc*.so
"$MYPYC" --config-file mypyc.ini --python-executable "$PYTHON" \
    sann/soar/memory.py sann/soar/rete.py sann/soar/preferences.py sann/soar/instantiation.py \
    sann/soar/decide.py sann/soar/goals.py sann/soar/agent.py
