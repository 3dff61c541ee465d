"""`make test` runs `pytest -n 2 --dist loadgroup`: tests marked with one `xdist_group` must
share a worker, or the book (built once per worker session) is built twice in parallel and
the suite takes minutes longer. pytest 9.2 silently broke this with pytest-xdist 3.8."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

CONFTEST = '''
import os, pytest
@pytest.fixture(scope="session")
def built(tmp_path_factory):
    marker = os.environ["GROUP_MARKERS"]
    open(os.path.join(marker, os.environ.get("PYTEST_XDIST_WORKER", "main")), "w").close()
'''
GROUPED = '''
import pytest
pytestmark = pytest.mark.xdist_group("book")
@pytest.mark.parametrize("i", range(8))
def test_grouped(i, built):
    pass
'''
FREE = '''
import time
def test_free():
    time.sleep(0.5)
'''


def test_grouped_tests_share_one_worker(tmp_path: Path) -> None:
    suite = tmp_path / "suite"
    suite.mkdir()
    (suite / "conftest.py").write_text(CONFTEST)
    (suite / "test_a.py").write_text(GROUPED)
    (suite / "test_b.py").write_text(GROUPED.replace("test_grouped", "test_grouped_too"))
    (suite / "test_c.py").write_text(FREE)
    markers = tmp_path / "markers"
    markers.mkdir()
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-n", "2", "--dist", "loadgroup",
         "-p", "no:cacheprovider", "-p", "no:randomly", str(suite)],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
        env={"GROUP_MARKERS": str(markers), "PATH": "/usr/bin:/bin"},
    )
    assert done.returncode == 0, done.stdout + done.stderr
    workers = sorted(p.name for p in markers.iterdir())
    assert len(workers) == 1, f"the group's session fixture ran on {workers}"
