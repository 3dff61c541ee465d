"""Sphinx configuration of the SANN book: MyST notebooks executed by myst-nb at build time.

The build must work offline from a fresh clone, and `sphinx-build -W` turns every warning into
a failure, so nothing here fetches anything and a failing cell fails the build.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import shutil
import sys
from pathlib import Path

from docutils import nodes

BOOK = Path(__file__).resolve().parent

project = "SANN — Soar-improved neural networks"
author = "The SANN authors"
copyright = "2026, the SANN authors"
language = "en"

extensions = ["myst_nb"]
# Formulas become MathML while the book is built (latex2mathml), so reading it needs no MathJax
# from a CDN: browsers render MathML natively.
html_math_renderer = "mathml"
exclude_patterns = ["_build", "**.ipynb_checkpoints", "README.md"]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}

# --- the live book: every Soar block runs in the page (book/live_ext.py) -----------------------
sys.path.insert(0, str(BOOK))
extensions.append("live_ext")

# --- MyST ---------------------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# --- execution ---------------------------------------------------------------------------------
# sann.bookcache executes the chapters before Sphinx reads them (SANN_BOOK_JOBS at a time,
# default 2) with a recorder of the project files each one reads; jupyter-cache keeps the
# executed notebooks, and an entry whose recorded inputs (rule files, grammars, sann modules,
# .sann-cache data, the installed packages) changed is executed again. SANN_BOOK_EXECUTION=force
# re-executes every chapter with myst-nb instead.
extensions.append("sann.bookcache")
nb_execution_mode = os.environ.get("SANN_BOOK_EXECUTION", "cache")
nb_execution_cache_path = str(BOOK / "_build" / ".jupyter_cache")
sann_bookcache_roots = [str(BOOK.parent)]
# Started first on a build that has no measured times yet (a fresh clone): the longest chapter,
# so that the other slot executes the rest meanwhile. Later builds order by measured times.
sann_bookcache_first = ["networks", "cups"]
# Per cell: on a first build (no dataset cache) the networks chapter's experiment cell plans
# some 12,600 scenes; on a loaded 2-core machine the chapter took 885 s, near the old 900.
nb_execution_timeout = 1800
nb_execution_raise_on_error = True  # a failing cell fails the build
nb_execution_show_tb = True
nb_execution_allow_errors = False
nb_merge_streams = True
nb_kernel_rgx_aliases = {".*": "python3"}
nb_ipywidgets_js = {}  # no widget manager from a CDN: the book is read offline

# Chapters executed by myst-nb show 3D scenes as srcdoc iframes that load one shared copy of
# meshcat's viewer script (see sann.viz.embed and _copy_meshcat_js below). The kernel inherits
# this process's environment.
os.environ["SANN_MESHCAT_JS"] = "_static/meshcat/main.min.js"
os.environ["SANN_VIEWER"] = "static"
os.environ.setdefault("TQDM_DISABLE", "1")

# --- HTML ---------------------------------------------------------------------------------------
html_theme = "sphinx_book_theme"
html_title = "SANN"
html_static_path = ["_static"]
html_css_files = ["sann.css"]
html_context = {"default_mode": "light"}
html_last_updated_fmt = None
html_theme_options = {
    "home_page_in_toc": True,
    "show_toc_level": 2,
    "use_download_button": True,
    "use_fullscreen_button": False,
    "use_repository_button": False,
    "navigation_with_keys": False,
}
pygments_style = "default"


def _copy_meshcat_js(app, exception) -> None:
    """Put meshcat's viewer script (from the installed package) under _static/meshcat."""
    if exception is not None or app.builder.format != "html":
        return
    from sann.viz.embed import viewer_js_path

    target = Path(app.outdir) / "_static" / "meshcat"
    target.mkdir(parents=True, exist_ok=True)
    source = viewer_js_path()
    shutil.copyfile(source, target / "main.min.js")
    licence = source.with_name("main.min.js.LICENSE.txt")
    if licence.exists():
        shutil.copyfile(licence, target / "main.min.js.LICENSE.txt")


def _soar_cells(app, doctree) -> None:
    """Highlight ``%%soar`` notebook cells as Soar rather than as Python."""
    if "soar" not in _lexers:
        return
    for block in doctree.findall(nodes.literal_block):
        if block.astext().startswith("%%soar"):
            block["language"] = "soar-cell"


_lexers: dict[str, object] = {}


def _register_lexers(app) -> None:
    """Register the Soar Pygments lexer once the package provides it.

    The module is looked up rather than imported in a try/except, so a lexer that exists but
    fails to import fails the build instead of silently leaving Soar code unhighlighted.
    """
    if importlib.util.find_spec("sann.soar.lexer") is None:
        return
    lexer_module = importlib.import_module("sann.soar.lexer")
    soar = lexer_module.SoarLexer
    from pygments.lexer import inherit
    from pygments.token import Comment

    class SoarCellLexer(soar):  # a notebook cell: the %%soar magic line, then Soar
        name = "Soar notebook cell"
        aliases = ["soar-cell"]
        tokens = {"root": [(r"\A%%soar[^\n]*\n", Comment.Preproc), inherit]}

    app.add_lexer("soar", soar)
    app.add_lexer("soar-cell", SoarCellLexer)
    _lexers["soar"] = soar


def _mathml(latex: str, display: str) -> str:
    from latex2mathml.converter import convert

    return convert(latex.strip(), display=display)


def _visit_inline_math(self, node) -> None:
    self.body.append(f'<span class="math notranslate">{_mathml(node.astext(), "inline")}</span>')
    raise nodes.SkipNode


def _visit_block_math(self, node) -> None:
    number = ""
    if node.get("number"):
        number = f'<span class="eqno">({node["number"]})</span>'
    anchor = f' id="{node["ids"][0]}"' if node.get("ids") else ""
    self.body.append(
        f'<div class="math notranslate mathml-block"{anchor}>{number}'
        f'{_mathml(node.astext(), "block")}</div>'
    )
    raise nodes.SkipNode


def setup(app) -> None:
    app.add_html_math_renderer(
        "mathml", inline_renderers=(_visit_inline_math, None),
        block_renderers=(_visit_block_math, None),
    )
    _register_lexers(app)
    app.connect("doctree-read", _soar_cells)
    app.connect("build-finished", _copy_meshcat_js)
