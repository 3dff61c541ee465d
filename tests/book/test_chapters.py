"""Every chapter of the book runs from top to bottom without an error.

The chapters are jupytext MyST notebooks; each is converted to a notebook and executed by
nbclient in the book's folder, as myst-nb does when `make book` builds them. A failing cell
fails its chapter's test with the cell's source and traceback in the message.
"""

from __future__ import annotations

from pathlib import Path

import jupytext
import nbclient
import nbformat
import pytest

BOOK = Path(__file__).resolve().parents[2] / "book"
CELL_TIMEOUT_S = 600


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
def test_chapter_executes(chapter: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    notebook = jupytext.read(chapter)
    code_cells = [c for c in notebook.cells if c.cell_type == "code"]
    assert code_cells, f"{chapter.name} has no code cell"
    # As in the book build: static 3D scenes, no progress bars, the kernel started in book/.
    monkeypatch.setenv("SANN_VIEWER", "static")
    monkeypatch.setenv("TQDM_DISABLE", "1")
    monkeypatch.delenv("JPY_SESSION_NAME", raising=False)
    client = nbclient.NotebookClient(
        notebook,
        timeout=CELL_TIMEOUT_S,
        kernel_name="python3",
        resources={"metadata": {"path": str(BOOK)}},
    )
    try:
        client.execute()
    except nbclient.exceptions.CellExecutionError as err:
        pytest.fail(f"{chapter.name}: a cell failed\n{err}", pytrace=False)
    outputs = [o for c in code_cells for o in c.get("outputs", [])]
    assert outputs, f"{chapter.name}: no cell produced any output"
    errors = [o for o in outputs if o.get("output_type") == "error"]
    assert not errors, f"{chapter.name}: error outputs {errors}"
    nbformat.validate(notebook)

