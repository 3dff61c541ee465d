"""The book's execution cache (sann.bookcache) on a tiny throwaway book.

Each chapter appends its name to ``runs.log`` when it executes (a file it writes, so not one
of its inputs): the tests read that log to see which chapters a build executed.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import nbformat
import pytest
from jupyter_cache import get_cache

from sann import bookcache

pytestmark = pytest.mark.xdist_group("bookcache")

FRONT = """---
jupytext:
  text_representation:
    extension: .md
    format_name: myst
kernelspec:
  display_name: Python 3
  language: python
  name: python3
---
"""

CONF = """
from pathlib import Path
extensions = ["myst_nb", "sann.bookcache"]
exclude_patterns = ["_build"]
nb_execution_mode = "cache"
nb_execution_cache_path = str(Path(__file__).parent / "_build" / ".jupyter_cache")
nb_execution_raise_on_error = True
nb_kernel_rgx_aliases = {".*": "python3"}
sann_bookcache_roots = [".."]
"""


def chapter(name: str, code: str, prose: str = "Some prose.") -> str:
    log = f'with open("../runs.log", "a") as f:\n    f.write("{name}\\n")\n'
    return (f"{FRONT}\n# Chapter {name}\n\n{prose}\n\n```{{code-cell}} ipython3\n"
            f"{log}{textwrap.dedent(code).strip()}\n```\n")


@pytest.fixture
def book(tmp_path: Path) -> Path:
    """rules/a.soar is read by chapter a; helper.py is imported by chapter b; c reads nothing
    of the project; d reads rules/d.soar in a forked child process only."""
    (tmp_path / "rules").mkdir()
    (tmp_path / "rules" / "a.soar").write_text("sp {a (state <s>) --> (<s> ^a 1)}\n")
    (tmp_path / "rules" / "d.soar").write_text("sp {d (state <s>) --> (<s> ^d 1)}\n")
    (tmp_path / "helper.py").write_text("VALUE = 1\n")
    src = tmp_path / "book"
    src.mkdir()
    (src / "conf.py").write_text(CONF)
    (src / "index.md").write_text("# Tiny\n\n```{toctree}\na\nb\nc\nd\n```\n")
    (src / "a.md").write_text(chapter("a", 'print(open("../rules/a.soar").read())'))
    (src / "b.md").write_text(chapter("b", """
        import sys
        sys.path.insert(0, "..")
        import helper
        print("helper value", helper.VALUE)
        """))
    (src / "c.md").write_text(chapter("c", 'print("c only computes", 6 * 7)'))
    (src / "d.md").write_text(chapter("d", """
        import os
        pid = os.fork()
        if pid == 0:
            open("../rules/d.soar").read()
            os._exit(0)
        os.waitpid(pid, 0)
        print("the child read d.soar")
        """))
    return tmp_path


def build(book: Path, **variables: str) -> subprocess.CompletedProcess:
    sphinx = Path(sys.executable).with_name("sphinx-build")
    env = {k: v for k, v in os.environ.items() if k != "JPY_SESSION_NAME"} | variables
    env["PYTHONPATH"] = os.pathsep.join([str(bookcache.ROOT), env.get("PYTHONPATH", "")])
    return subprocess.run(
        [str(sphinx), "-q", "-b", "html", str(book / "book"), str(book / "book/_build/html")],
        capture_output=True, text=True, env=env, cwd=book, timeout=600)


def runs(book: Path) -> list[str]:
    """The chapters executed since the last call, sorted."""
    log = book / "runs.log"
    if not log.exists():
        return []
    names = sorted(log.read_text().split())
    log.unlink()
    return names


def html(book: Path, name: str) -> str:
    return (book / "book" / "_build" / "html" / f"{name}.html").read_text()


def built(book: Path, **variables: str) -> list[str]:
    done = build(book, **variables)
    assert done.returncode == 0, done.stdout + done.stderr
    return runs(book)


def test_each_build_executes_exactly_the_chapters_whose_inputs_changed(book: Path) -> None:
    """One book through a series of edits (each build costs a Sphinx start and kernels)."""
    assert built(book) == ["a", "b", "c", "d"]
    assert "sp {a" in html(book, "a")
    records = list((book / "book/_build/.jupyter_cache" / bookcache.RECORDS).glob("*.json"))
    assert len(records) == 4
    for record in records:  # the kernel's CPU seconds: at least its start (imports)
        data = json.loads(record.read_text())
        assert 0.05 < data["execution_cpu_seconds"] < 60, data
    executed = nbformat.read(book / "book" / "_build" / "jupyter_execute" / "a.ipynb", 4)
    assert "sp {a" in executed.cells[-1].outputs[0]["text"]
    # nothing changed: nothing is executed
    assert built(book) == []
    # a prose edit is rendered without executing
    a = book / "book" / "a.md"
    a.write_text(a.read_text().replace("Some prose.", "Edited prose."))
    assert built(book) == []
    assert "Edited prose." in html(book, "a")
    # a rule file: exactly the chapter that read it (in the kernel, or in a forked child)
    (book / "rules" / "a.soar").write_text("sp {a-edited (state <s>) --> (<s> ^a 2)}\n")
    (book / "rules" / "d.soar").write_text("sp {d-edited (state <s>) --> (<s> ^d 2)}\n")
    assert built(book) == ["a", "d"]
    assert "sp {a-edited" in html(book, "a")
    # an imported module
    (book / "helper.py").write_text("VALUE = 2\n")
    assert built(book) == ["b"]
    assert "helper value 2" in html(book, "b")
    # the same content with a new mtime is no change
    os.utime(book / "rules" / "a.soar", (1, 1))
    assert built(book) == []
    # an entry without a record of its inputs (a build stopped between the two writes)
    cache_path = book / "book" / "_build" / ".jupyter_cache"
    entry = next(r for r in get_cache(str(cache_path)).list_cache_records()
                 if Path(r.uri).stem == "c")
    bookcache.record_path(cache_path, entry.hashkey).unlink()
    # ... and a changed environment (a SANN_* variable the kernel inherits)
    assert built(book, SANN_BOOKCACHE_TEST="1") == ["a", "b", "c", "d"]


def test_a_failed_execution_leaves_no_cache_entry(book: Path) -> None:
    c = book / "book" / "c.md"
    c.write_text(chapter("c", 'raise ValueError("boom")'))
    done = build(book)
    assert done.returncode != 0
    assert "boom" in done.stdout + done.stderr
    assert runs(book) == ["a", "b", "c", "d"]
    cache = get_cache(str(book / "book" / "_build" / ".jupyter_cache"))
    assert sorted(Path(r.uri).stem for r in cache.list_cache_records()) == ["a", "b", "d"]
    c.write_text(chapter("c", 'print("c fixed")'))
    assert built(book) == ["c"]
    assert "c fixed" in html(book, "c")


LIVE_CONF = """
import sys
from pathlib import Path
sys.path.insert(0, str(Path(__file__).parent))
extensions = ["live_ext"]
exclude_patterns = ["_build"]
html_static_path = ["_static"]


def setup(app):
    from sann.soar.lexer import SoarLexer
    app.add_lexer("soar", SoarLexer)
"""


@pytest.fixture
def live_book(tmp_path: Path) -> Path:
    """A book of two pages, ``a`` with a live Soar block and ``b`` without, built with a copy
    of book/live_ext.py and book/_static/live beside its conf.py; the rest of the repository
    (the engine it packs, Pyodide's node_modules) is linked in."""
    import importlib.util
    import shutil

    spec = importlib.util.spec_from_file_location("live_ext", bookcache.ROOT / "book/live_ext.py")
    live_ext = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(live_ext)
    live_ext._npm_ci()  # the build copies Pyodide from the repository's node_modules
    for name in ("sann", "grammars", "node_modules", "package.json", "package-lock.json"):
        (tmp_path / name).symlink_to(bookcache.ROOT / name)
    (tmp_path / "rules").mkdir()
    (tmp_path / "rules" / "a.soar").write_text("sp {a (state <s>) --> (<s> ^a 1)}\n")
    src = tmp_path / "book"
    shutil.copytree(bookcache.ROOT / "book" / "_static" / "live", src / "_static" / "live")
    shutil.copy(bookcache.ROOT / "book" / "live_ext.py", src / "live_ext.py")
    (src / "conf.py").write_text(LIVE_CONF)
    (src / "index.rst").write_text("Tiny\n====\n\n.. toctree::\n\n   a\n   b\n")
    (src / "a.rst").write_text("A\n=\n\n.. literalinclude:: ../rules/a.soar\n"
                               "   :language: soar\n")
    (src / "b.rst").write_text("B\n=\n\nNo Soar here.\n")
    return tmp_path


def written(book: Path) -> dict[str, int]:
    """When each page's HTML was written (ns)."""
    return {name: (book / "book/_build/html" / f"{name}.html").stat().st_mtime_ns
            for name in ("a", "b")}


def test_a_live_ext_or_live_script_change_rewrites_the_pages(live_book: Path) -> None:
    built(live_book)
    assert "sann-live-meta" in html(live_book, "a")
    assert "sann-live-meta" not in html(live_book, "b")
    first = written(live_book)
    built(live_book)
    assert written(live_book) == first  # nothing changed: no page written
    # the extension changes the metadata it writes: the page with live cells is read again
    ext = live_book / "book" / "live_ext.py"
    code = ext.read_text()
    marked = "meta.update(index=index, shipped=text, page=app.env.docname)"
    assert marked in code
    ext.write_text(code.replace(marked, marked[:-1] + ", edition=2)"))
    built(live_book)
    assert "&quot;edition&quot;: 2" in html(live_book, "a")
    second = written(live_book)
    assert all(second[n] > first[n] for n in first), "not every page was written again"
    # a script every page loads: every page written again, with the script's new checksum
    old = {n: re.search(r"live/live\.js\?v=(\w+)", html(live_book, n)).group(1) for n in first}
    script = live_book / "book" / "_static" / "live" / "live.js"
    script.write_text(script.read_text() + "\n// edited\n")
    built(live_book)
    new = {n: re.search(r"live/live\.js\?v=(\w+)", html(live_book, n)).group(1) for n in first}
    assert all(new[n] != old[n] for n in first), (old, new)
    third = written(live_book)
    built(live_book)
    assert written(live_book) == third
