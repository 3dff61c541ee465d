"""The engine's type hints hold: mypy finds no error in sann/soar with the project's settings.

mypyc compiles the engine only when they hold (`make engine`), and pyproject.toml switches
error codes off only in the modules it names; this catches a wrong hint before a build does.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_mypy_accepts_the_engine_hints() -> None:
    run = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-incremental", "--cache-dir=/dev/null", "sann/soar"],
        cwd=ROOT, text=True, capture_output=True, timeout=600,
    )
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-2000:]
    assert "Success: no issues found" in run.stdout
