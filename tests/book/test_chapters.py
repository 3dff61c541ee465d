"""Every chapter of the book runs from top to bottom without an error.

The chapters are jupytext MyST notebooks executed by myst-nb when the book is built (once per
test session, see conftest.py); a failing cell fails that build with its traceback, and each
chapter's executed notebook is checked here.
"""

from __future__ import annotations

from pathlib import Path

import jupytext
import nbformat
import pytest

pytestmark = pytest.mark.xdist_group("book")

BOOK = Path(__file__).resolve().parents[2] / "book"


def is_notebook(path: Path) -> bool:
    """A chapter is a notebook when its front matter names a kernel (plain pages do not)."""
    text = path.read_text(encoding="utf-8")
    if not text.startswith("---\n"):
        return False
    front = text[4 : text.find("\n---", 4)]
    return "kernelspec:" in front


CHAPTERS = sorted(p for p in BOOK.glob("*.md") if is_notebook(p))


def test_the_book_has_notebook_chapters() -> None:
    assert CHAPTERS, f"no executable chapters found in {BOOK}"
    assert (BOOK / "index.md").exists()


def test_every_chapter_is_in_the_table_of_contents() -> None:
    index = (BOOK / "index.md").read_text(encoding="utf-8")
    toc = index[index.index("```{toctree}") :]
    missing = [p.stem for p in BOOK.glob("*.md") if p.stem != "index" and p.stem not in toc]
    assert not missing, f"chapters not in index.md's toctree: {missing}"


@pytest.mark.parametrize("chapter", CHAPTERS, ids=[p.stem for p in CHAPTERS])
def test_chapter_executes(chapter: Path, book_html: Path) -> None:
    """The book build executed the chapter (myst-nb stops the build on a failing cell); its
    executed notebook must have outputs and no error output."""
    executed = book_html.parent / "jupyter_execute" / f"{chapter.stem}.ipynb"
    assert executed.exists(), f"{chapter.name} was not executed by the book build"
    notebook = nbformat.read(executed, as_version=4)
    code_cells = [c for c in notebook.cells if c.cell_type == "code"]
    assert code_cells, f"{chapter.name} has no code cell"
    assert len(code_cells) == len([c for c in jupytext.read(chapter).cells
                                   if c.cell_type == "code"]), "stale executed notebook"
    outputs = [o for c in code_cells for o in c.get("outputs", [])]
    assert outputs, f"{chapter.name}: no cell produced any output"
    errors = [o for o in outputs if o.get("output_type") == "error"]
    assert not errors, f"{chapter.name}: error outputs {errors}"
    nbformat.validate(notebook)


@pytest.mark.parametrize("chapter", CHAPTERS, ids=[p.stem for p in CHAPTERS])
def test_page_shows_no_kernel_halt_messages(chapter: Path, book_html: Path) -> None:
    """Agents that plan thousands of scenes halt thousands of times: the kernel's status lines
    ('System halted.', 'Interrupt received.') must not reach the reader."""
    page = (book_html / f"{chapter.stem}.html").read_text(encoding="utf-8")
    found = {status: page.count(status) for status in ("System halted", "Interrupt received")}
    assert not any(found.values()), f"{chapter.stem}.html shows {found}"
