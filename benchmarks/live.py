"""Live-book benchmark: the engine in the page (Pyodide in headless Chromium) against the same
interpreted engine in CPython, in one run.

Usage::

    .venv/bin/python benchmarks/live.py [BUILT_BOOK_DIR] [--repeat 3]

The built book (default book/_build/html, from `make book`) is served on 127.0.0.1 and opened
in Debian's Chromium with every other request blocked. It prints:

(a) the first run of the water-jug cell of *Soar in practice* after the page loaded (Python
    starts in the page: Pyodide, the packed engine, the grammar), and a rerun of the cell,
    both as the reader waits for them (button press to output shown), and their ratio;
(b) rules/hanoi.soar run to halt (2,060 decisions) in the page's worker and in this process
    with the interpreted engine (SANN_INTERPRETED=1, as in the page): decisions per second,
    best of --repeat runs each, and the ratio page/CPython.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from urllib.parse import urlparse

os.environ["SANN_INTERPRETED"] = "1"  # the page runs the engine's sources: compare alike
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sann import live  # noqa: E402
from sann.serve import serve_in_thread  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]


def _blocked_elsewhere(route) -> None:
    if urlparse(route.request.url).hostname == "127.0.0.1":
        route.continue_()
    else:
        route.abort()


def timed_run(page, cell) -> float:
    """Seconds from pressing Run to the output of this run being shown."""
    runs = int(cell.get_attribute("data-runs") or 0)
    start = time.perf_counter()
    cell.get_by_role("button", name="Run", exact=True).click()
    page.wait_for_function("([c, n]) => Number(c.dataset.runs || 0) > n",
                           arg=[cell.element_handle(), runs], timeout=600_000)
    return time.perf_counter() - start


def page_hanoi(page, repeat: int) -> tuple[float, int]:
    rates = []
    for _ in range(repeat):
        answer = page.evaluate("() => window.SannLive.request('hanoi', {})")
        assert answer["halted"], answer
        rates.append(answer["rate"])
    return max(rates), answer["decisions"]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("book", nargs="?", type=Path, default=ROOT / "book" / "_build" / "html")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    if not (args.book / "_static" / "live" / "sann-live.zip").is_file():
        raise SystemExit(f"{args.book}: no live book there (make book)")
    from playwright.sync_api import sync_playwright

    httpd, url = serve_in_thread(args.book)
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path="/usr/bin/chromium",
                                             args=CHROMIUM_ARGS)
        page = browser.new_page()
        page.route("**/*", _blocked_elsewhere)
        page.goto(f"{url}soar-in-practice.html", wait_until="load")
        cell = page.locator(".sann-live", has_text="water-jug*detect*goal*achieved").first
        first = timed_run(page, cell)
        rerun = min(timed_run(page, cell) for _ in range(args.repeat))
        in_page, decisions = page_hanoi(page, args.repeat)
        browser.close()
    httpd.shutdown()
    in_cpython = max(live.hanoi_rate()["rate"] for _ in range(args.repeat))
    print(f"(a) water-jug cell: first run after page load {first:.1f} s, rerun {rerun:.2f} s "
          f"(best of {args.repeat}); first/rerun {first / rerun:.0f}x")
    print(f"(b) hanoi, {decisions} decisions to halt, best of {args.repeat}: in the page "
          f"{in_page:.0f} decisions/s, CPython {sys.version.split()[0]} interpreted "
          f"{in_cpython:.0f} decisions/s; page/CPython {in_page / in_cpython:.2f}")


if __name__ == "__main__":
    main()
