"""The book is built once per test session exactly as `make book` builds it: into
book/_build/html, with the same doctrees and the same execution cache (sann.bookcache). After
`make book` nothing is executed again and the build takes seconds; a source, rule file or
module changed since is rebuilt (the chapters that read it are executed again), never served
stale. The chapter tests read the notebooks that build executed, the browser tests open its
HTML."""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BOOK = ROOT / "book"
BUILD = BOOK / "_build"


def chapter_names() -> list[str]:
    return sorted(p.stem for p in BOOK.glob("*.md"))


@pytest.fixture(scope="session")
def book_html() -> Path:
    """The built HTML (book/_build/html), brought up to date under a lock."""
    BUILD.mkdir(exist_ok=True)
    sphinx = Path(sys.executable).with_name("sphinx-build")
    cmd = [str(sphinx), "-W", "--keep-going", "-q", "-b", "html", "-d", str(BUILD / "doctrees"),
           str(BOOK), str(BUILD / "html")]
    env = {k: v for k, v in os.environ.items() if k != "JPY_SESSION_NAME"}
    with open(BUILD / ".build.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        shutil.rmtree(BUILD / "html", ignore_errors=True)  # every page written again, as make does
        done = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT,
                              timeout=3600)
        if done.returncode != 0:  # a failed chapter must be read (and fail) again next time
            shutil.rmtree(BUILD / "doctrees", ignore_errors=True)
    assert done.returncode == 0, f"the book build failed:\n{done.stdout}\n{done.stderr}"
    return BUILD / "html"


CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]


@pytest.fixture(scope="session")
def browser():
    """Debian's headless Chromium, one per test process: Playwright's sync API runs one
    event loop per thread, so a second ``sync_playwright()`` beside it would fail."""
    if not CHROMIUM.exists():
        pytest.fail("Chromium is missing: `make test` installs it from Debian (apt chromium)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        yield chromium
        chromium.close()
