"""The built book, opened in headless Chromium as a reader would open it: from disk, offline.

The book is built once per session (or an existing `make book` output is reused when it is
newer than every source it was built from). Each page must load without console errors and
without fetching anything from the network, code cells must show outputs, formulas must be
MathML, 3D scenes must draw into a WebGL canvas and Soar code must be highlighted.
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import urlparse

import pytest

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.xdist_group("book")]

ROOT = Path(__file__).resolve().parents[2]
BOOK = ROOT / "book"
PAGES = sorted(p.stem for p in BOOK.glob("*.md"))


class Visit:
    """A page opened from disk, with its console errors and attempted network requests."""

    def __init__(self, browser, path: Path) -> None:
        self.page = browser.new_page(viewport={"width": 1280, "height": 900})
        self.errors: list[str] = []
        self.external: list[str] = []
        self.page.on("console", self._console)
        self.page.on("pageerror", lambda err: self.errors.append(f"page error: {err}"))
        self.page.route("**/*", self._route)
        self.page.goto(path.as_uri(), wait_until="load")

    def _console(self, message) -> None:
        if message.type == "error":
            self.errors.append(f"console: {message.text}")

    def _route(self, route) -> None:
        scheme = urlparse(route.request.url).scheme
        if scheme in ("file", "data", "blob", "about"):
            route.continue_()
        else:
            self.external.append(route.request.url)
            route.abort()

    def close(self) -> None:
        self.page.close()


@pytest.fixture
def visit(browser):
    opened: list[Visit] = []

    def open_page(path: Path) -> Visit:
        page = Visit(browser, path)
        opened.append(page)
        return page

    yield open_page
    for page in opened:
        page.close()


@pytest.mark.parametrize("name", PAGES)
def test_page_loads_offline_without_errors(book_html: Path, visit, name: str) -> None:
    page = visit(book_html / f"{name}.html")
    page.page.wait_for_timeout(500)
    assert page.page.locator("article h1").count() >= 1, f"{name}: no title"
    assert not page.errors, f"{name}: {page.errors}"
    assert not page.external, f"{name} tried to fetch from the network: {page.external}"


@pytest.mark.parametrize("name", [n for n in PAGES if n != "index"])
def test_code_cells_show_their_outputs(book_html: Path, visit, name: str) -> None:
    page = visit(book_html / f"{name}.html").page
    cells = page.locator("div.cell")
    assert cells.count() > 0, f"{name}: no code cell in the page"
    outputs = page.locator("div.cell div.cell_output")
    assert outputs.count() > 0, f"{name}: no cell output in the page"
    text = page.locator("div.cell_output").all_inner_texts()
    assert not [t for t in text if "Traceback (most recent call last)" in t], name


def test_formulas_are_mathml(book_html: Path, visit) -> None:
    page = visit(book_html / "architecture.html").page
    assert page.locator("div.math math").count() >= 1
    assert page.locator("span.math math").count() >= 3
    box = page.locator("div.math math").first.bounding_box()
    assert box and box["height"] > 20, "the display formula was not laid out as MathML"


def test_figures_are_embedded_images(book_html: Path, visit) -> None:
    page = visit(book_html / "architecture.html").page
    images = page.locator("div.cell_output img")
    assert images.count() >= 1
    width = images.first.evaluate("img => img.naturalWidth")
    assert width > 200


def scene_pages(book_html: Path) -> list[Path]:
    return [p for p in sorted(book_html.glob("*.html")) if "sann-scene-frame" in p.read_text()]


def test_meshcat_scenes_draw_into_a_canvas(book_html: Path, visit) -> None:
    pages = scene_pages(book_html)
    if not any(p.stem == "block-world" for p in (BOOK.glob("*.md"))):
        pytest.skip("no chapter with 3D scenes yet")
    assert pages, "the block-world chapter shows no 3D scene"
    for path in pages:
        page = visit(path)
        frames = page.page.locator("iframe.sann-scene-frame")
        assert frames.count() >= 1
        for i in range(frames.count()):
            frame = frames.nth(i)
            frame.scroll_into_view_if_needed()
            inner = frame.content_frame
            inner.locator("canvas").first.wait_for(timeout=15_000)
            size = inner.locator("canvas").first.evaluate("c => [c.width, c.height]")
            assert size[0] > 100 and size[1] > 100, f"{path.name} scene {i}: canvas {size}"
            shot = frame.screenshot()
            assert _distinct_colours(shot) > 20, f"{path.name} scene {i} looks blank"
        assert not page.errors, f"{path.name}: {page.errors}"
        assert not page.external, f"{path.name}: {page.external}"


def _distinct_colours(png: bytes) -> int:
    """Number of distinct colours in a PNG screenshot (a blank canvas has one or two)."""
    import io

    from PIL import Image

    image = Image.open(io.BytesIO(png)).convert("RGB").resize((160, 120))
    return len(set(image.getdata()))


def test_soar_code_is_highlighted(book_html: Path, visit) -> None:
    if not (BOOK / "soar-in-practice.md").exists():
        pytest.skip("the Soar chapter is not written yet")
    page = visit(book_html / "soar-in-practice.html").page
    blocks = page.locator("div.highlight-soar, div.highlight-soar-cell")
    assert blocks.count() >= 1, "no Soar-highlighted code block"
    tokens = blocks.first.locator("pre span[class]")
    kinds = set(tokens.evaluate_all("spans => spans.map(s => s.className)"))
    assert len(kinds) >= 4, f"Soar code has too few token kinds: {kinds}"
