"""The live book in headless Chromium: Soar cells run in the page, served from 127.0.0.1 with
every other request blocked, as a reader with no network would open `make serve`'s book.

The DOM contract the tests rely on: a live cell is an element with class ``sann-live``, holding
an editor with class ``sann-live-editor`` (shown by the cell's *Edit* button; Playwright's
``fill()`` sets its text), a button whose text is ``Run`` and an output element with class
``sann-live-output``.
"""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import urlparse

import pytest

from sann.serve import serve_in_thread

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.xdist_group("book")]

ROOT = Path(__file__).resolve().parents[2]
SOLUTIONS = Path(__file__).resolve().parent / "solutions"
#: The first run of a page starts Python in it: tens of seconds on a loaded 2-core machine.
FIRST_RUN_MS = 240_000
WATER_JUG = (ROOT / "rules" / "water-jug.soar").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def served(book_html: Path):
    httpd, url = serve_in_thread(book_html)
    yield url
    httpd.shutdown()
    httpd.server_close()


class LivePage:
    """A served page with its console errors and the requests blocked for leaving 127.0.0.1."""

    def __init__(self, browser, url: str) -> None:
        self.context = browser.new_context(viewport={"width": 1280, "height": 900})
        # Several pages of the module stay open, two or three with Python running in them:
        # on a loaded 2-core machine a click can wait for a busy renderer past 30 s.
        self.context.set_default_timeout(120_000)
        self.page = self.context.new_page()
        self.errors: list[str] = []
        self.external: list[str] = []
        self.page.on("console", lambda m: m.type == "error" and self.errors.append(m.text))
        self.page.on("pageerror", lambda err: self.errors.append(f"page error: {err}"))
        self.page.route("**/*", self._route)
        self.page.goto(url, wait_until="load")

    def _route(self, route) -> None:
        if urlparse(route.request.url).hostname == "127.0.0.1":
            route.continue_()
        else:
            self.external.append(route.request.url)
            route.abort()

    def cell(self, predicate: str):
        """The live cell whose text (shipped code included) matches ``predicate``."""
        return self.page.locator(".sann-live", has_text=re.compile(predicate)).first

    def check_clean(self) -> None:
        assert not self.errors, self.errors
        assert not self.external, f"requests left 127.0.0.1: {self.external}"


@pytest.fixture(scope="module")
def pages(browser, served):
    """One page per chapter for the module: Python starts once per chapter, not per test."""
    opened: dict[str, LivePage] = {}

    def open_page(name: str) -> LivePage:
        if name not in opened:
            opened[name] = LivePage(browser, f"{served}{name}.html")
        return opened[name]

    yield open_page
    for page in opened.values():
        page.context.close()


def run(cell, timeout: int = FIRST_RUN_MS) -> str:
    """Press Run and wait for this run's output; the output's text."""
    runs = int(cell.get_attribute("data-runs") or 0)
    cell.get_by_role("button", name="Run", exact=True).click()
    cell.page.wait_for_function(
        "([c, n]) => Number(c.dataset.runs || 0) > n", arg=[cell.element_handle(), runs],
        timeout=timeout)
    return cell.locator(".sann-live-output").inner_text()


def edit(cell, text: str) -> None:
    cell.get_by_role("button", name="Edit", exact=True).click()
    cell.locator(".sann-live-editor").fill(text)


def water_jug_cell(page: LivePage):
    return page.cell(r"water-jug\*detect\*goal\*achieved")


def test_every_soar_block_is_live(pages) -> None:
    for name, least in (("soar-in-practice", 3), ("planning", 4), ("cups", 4),
                        ("exercises", 3)):
        page = pages(name)
        cells = page.page.locator(".sann-live")
        assert cells.count() >= least, name
        for i in range(cells.count()):
            cell = cells.nth(i)
            assert cell.get_by_role("button", name="Run", exact=True).count() == 1
            assert cell.locator(".sann-live-editor").count() == 1
            assert cell.locator(".sann-live-output").count() == 1


def test_a_shipped_cell_runs_in_the_page(pages) -> None:
    page = pages("soar-in-practice")
    cell = water_jug_cell(page)
    output = run(cell)
    assert "The problem has been solved." in output
    assert "O: O24 (pour)" in output  # the decision trace, at the default level 1
    assert re.search(r"\b9 decisions\b", output)
    assert "halted" in output
    page.check_clean()


def test_an_edited_rule_changes_the_output(pages) -> None:
    page = pages("soar-in-practice")
    cell = water_jug_cell(page)
    without_goal = re.sub(r"(?s)sp \{water-jug\*detect\*goal\*achieved.*?\}\n", "", WATER_JUG)
    assert without_goal != WATER_JUG
    edit(cell, without_goal)
    cell.locator(".sann-live-limit").fill("25")
    output = run(cell)
    assert "The problem has been solved." not in output
    assert "25-decision limit" in output
    assert "Stopped at the decision limit (25)" in output
    page.check_clean()


#: A runaway: one operator per decision, each counting one further, never halting.
COUNT_FOREVER = """sp {count*init
   (state <s> ^superstate nil -^count)
-->
   (<s> ^count 0)}

sp {count*propose
   (state <s> ^superstate nil ^count <c>)
-->
   (<s> ^operator <o> + =)
   (<o> ^name count ^value <c>)}

sp {count*apply
   (state <s> ^operator <o> ^count <c>)
   (<o> ^name count ^value <c>)
-->
   (<s> ^count <c> - (+ <c> 1))}
"""


def test_stop_ends_a_runaway_run_and_the_next_run_starts_a_new_worker(pages) -> None:
    page = pages("soar-in-practice")
    cell = water_jug_cell(page)
    cell.get_by_role("button", name="Reset", exact=True).click()
    assert "The problem has been solved." in run(cell)  # Python is up in the page's worker
    (worker,) = page.page.workers
    stop = cell.get_by_role("button", name="Stop", exact=True)
    assert stop.is_disabled()  # nothing to stop
    edit(cell, COUNT_FOREVER)
    cell.locator(".sann-live-limit").fill("100000000")  # hours of decisions in the page
    cell.get_by_role("button", name="Run", exact=True).click()
    page.page.wait_for_timeout(1_500)
    assert cell.locator(".sann-live-output .sann-live-stopped").count() == 0
    stop.click()
    stopped = cell.locator(".sann-live-output .sann-live-stopped")
    stopped.wait_for(timeout=30_000)
    assert re.search(r"Stopped after \d+\.\d s: the run did not finish", stopped.inner_text())
    assert "next Run starts a new worker" in stopped.inner_text()
    for _ in range(100):  # Playwright hears of the worker's end a little later
        if worker not in page.page.workers:
            break
        page.page.wait_for_timeout(100)
    assert worker not in page.page.workers, "the stopped worker is still alive"
    assert stop.is_disabled()
    cell.get_by_role("button", name="Reset", exact=True).click()
    output = run(cell)
    assert "The problem has been solved." in output and "halted" in output
    assert "Python started in" in cell.locator(".sann-live-status").inner_text()
    (fresh,) = page.page.workers
    assert fresh is not worker
    page.check_clean()


def test_a_syntax_error_shows_line_and_column(pages) -> None:
    page = pages("soar-in-practice")
    cell = water_jug_cell(page)
    lines = WATER_JUG.splitlines(keepends=True)
    row = next(i for i, line in enumerate(lines) if line.startswith("sp {water-jug*propose*fill"))
    lines[row + 1] = lines[row + 1].replace("^name water-jug", "^name water-jug )) oops", 1)
    edit(cell, "".join(lines))
    output = run(cell)
    error = cell.locator(".sann-live-error")
    assert error.count() == 1
    where = re.search(r"rules/water-jug\.soar:(\d+):(\d+):", output)
    assert where, output
    line, column = int(where.group(1)), int(where.group(2))
    assert line == row + 2
    assert f"line {line} of this cell, column {column}" in output
    assert re.search(r"\n\s+\^", output), "no caret under the line"
    caret = cell.locator(".sann-live-editor").evaluate("e => e.selectionStart")
    assert caret == sum(len(x) for x in lines[: line - 1]) + column - 1
    page.check_clean()


def test_stepping_one_decision_updates_the_graph(pages) -> None:
    page = pages("soar-in-practice")
    cell = water_jug_cell(page)
    cell.get_by_role("button", name="Reset", exact=True).click()
    cell.get_by_role("button", name="Step decision", exact=True).click()
    graph = cell.locator(".sann-live-wm svg")
    graph.wait_for(timeout=FIRST_RUN_MS)
    view = cell.locator(".sann-live-stepview")
    assert "operator O1 (initialize-water-jug) selected" in view.inner_text()
    before = set(graph.locator("g[data-timetag]").evaluate_all(
        "gs => gs.map(g => g.dataset.timetag)"))
    assert graph.locator(".sann-live-node").count() > 5
    cell.get_by_role("button", name="Step decision", exact=True).click()
    page.page.wait_for_function(
        "v => v.innerText.includes('Decision 2')", arg=view.element_handle(), timeout=60_000)
    after = set(graph.locator("g[data-timetag]").evaluate_all(
        "gs => gs.map(g => g.dataset.timetag)"))
    assert after != before
    assert graph.locator(".sann-live-new").count() > 0, "new WMEs are not marked"
    text = view.inner_text()
    assert "(fill) selected" in text
    assert graph.locator(".sann-live-node[data-id='J1']").count() == 1  # the jugs appeared
    page.check_clean()


def test_an_exercise_check_goes_from_not_yet_to_passes(pages) -> None:
    page = pages("exercises")
    cell = page.page.locator(".sann-live[data-exercise='greedy-empty']")
    run(cell)
    check = cell.locator(".sann-live-check")
    assert check.get_attribute("data-passed") == "false"
    assert "not yet" in check.inner_text()
    edit(cell, (SOLUTIONS / "greedy-empty.soar").read_text(encoding="utf-8"))
    run(cell)
    assert check.get_attribute("data-passed") == "true"
    assert "passes" in check.inner_text()
    assert "tie impasse at decision" in check.inner_text()
    page.check_clean()


def test_a_magic_cell_shows_what_the_notebook_shows(pages) -> None:
    page = pages("soar-in-practice")
    cell = page.cell(r"water-jug\*monitor\*state")
    notebook = cell.locator("xpath=ancestor::div[contains(concat(' ', @class, ' '), ' cell ')]"
                            "[1]//div[contains(@class, 'cell_output')]").inner_text()
    output = run(cell)
    expected = [line.strip() for line in notebook.splitlines() if line.strip()]
    shown = [line.strip() for line in output.splitlines() if line.strip()]
    assert expected and shown[: len(expected)] == expected
    page.check_clean()


def test_edits_survive_a_reload_and_reset_restores(browser, served) -> None:
    from playwright.sync_api import expect

    page = LivePage(browser, f"{served}soar-in-practice.html")
    try:
        cell = water_jug_cell(page)
        edit(cell, WATER_JUG.replace("# Water jug:", "# My water jug:", 1))
        saved = page.page.evaluate(
            "() => Object.keys(localStorage).filter(k => k.startsWith('sann-live:')).length")
        assert saved == 1
        page.page.reload(wait_until="load")
        editor = water_jug_cell(page).locator(".sann-live-editor")
        expect(editor).to_be_visible()
        expect(editor).to_have_value(re.compile(r"^# My water jug:"))
        water_jug_cell(page).get_by_role("button", name="Reset", exact=True).click()
        page.page.reload(wait_until="load")
        expect(water_jug_cell(page).locator("div.highlight-soar")).to_be_visible()
        expect(water_jug_cell(page).locator(".sann-live-editor")).to_be_hidden()
        page.check_clean()
    finally:
        page.context.close()


def test_a_fragment_runs_in_its_file_on_the_chapter_scene(pages) -> None:
    page = pages("planning")
    cell = page.cell(r"blocks\*propose\*plan-target")
    assert "C3 scene" in cell.locator(".sann-live-bar").inner_text()
    output = run(cell)
    assert "(plan-target)" in output and "(operator tie)" in output and "(finish)" in output
    assert "halted" in output
    cell.get_by_role("button", name="output-link", exact=True).click()
    cell.locator(".sann-live-query").first.wait_for(timeout=60_000)
    assert "^sequence" in cell.locator(".sann-live-query").first.inner_text()
    page.check_clean()
