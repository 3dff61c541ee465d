"""The book is built once per test session (or `make book`'s output reused when it is newer
than every source): the chapter tests read the notebooks that build executed, the browser tests
open its HTML. Executing every chapter twice would double the suite's longest part."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BOOK = ROOT / "book"

#: What the book is built from: a newer file here makes an existing build stale.
SOURCES = [
    (BOOK, "*.md"), (BOOK, "*.py"), (BOOK / "_static", "**/*"), (ROOT, "package-lock.json"),
    (ROOT / "sann", "**/*.py"),
    (ROOT / "rules", "**/*.soar"), (ROOT / "grammars", "*.lark"),
]


def newest_source() -> float:
    times = [p.stat().st_mtime for base, pattern in SOURCES for p in base.glob(pattern)
             if p.is_file()]
    return max(times)


def chapter_names() -> list[str]:
    return sorted(p.stem for p in BOOK.glob("*.md"))


@pytest.fixture(scope="session")
def book_html(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The built HTML: `make book`'s output if fresh, else a build made for this session."""
    existing = BOOK / "_build" / "html"
    index = existing / "index.html"
    executed = existing.parent / "jupyter_execute"
    fresh = index.exists() and all((existing / f"{c}.html").exists() for c in chapter_names())
    fresh = fresh and executed.is_dir()
    if fresh and index.stat().st_mtime > newest_source():
        return existing
    out = tmp_path_factory.mktemp("book")
    sphinx = Path(sys.executable).with_name("sphinx-build")
    cmd = [str(sphinx), "-W", "--keep-going", "-q", "-b", "html", "-d", str(out / "doctrees"),
           str(BOOK), str(out / "html")]
    env = {k: v for k, v in os.environ.items() if k != "JPY_SESSION_NAME"}
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT, timeout=1800)
    assert done.returncode == 0, f"the book build failed:\n{done.stdout}\n{done.stderr}"
    return out / "html"


