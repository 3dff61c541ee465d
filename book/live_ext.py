"""Sphinx extension of the live book: every Soar code block of the rendered book runs in the
page (book/_static/live/: the cell UI, and a Web Worker running the engine on Pyodide).

At build time it
- marks each Soar block (a literal include of a ``rules/`` file, a ``%%soar`` cell, a
  ``{live-exercise}``) with what a run needs: the file the text comes from, the shipped text,
  the rule files a ``%%soar`` cell's agent sourced first (the code cell's ``live-preload``
  metadata), the exercise checked;
- installs the pinned Pyodide from the npm registry (``npm ci`` on package-lock.json when
  node_modules is missing or older than the lock), and copies its runtime into ``_static``;
- packs the engine the page runs from the package's own sources (``sann/soar``,
  ``sann/live.py``, ``sann/exercises.py``) with their data (the grammar, ``sann/rules``) and
  the pure-Python dependencies as installed in this environment (lark, mypy_extensions), so
  the page runs the very code the build ran, offline.

Sphinx keeps the doctrees of unchanged pages, and a page's cell metadata is in its doctree:
each page with live cells depends on this file (and on the modules its exercises and scenes
were computed with), so a change to them makes Sphinx read the page again. Every page loads
the scripts of ``_static/live`` (their URLs carry a checksum), so a change to one of them, or
to this file, rewrites every page.
"""

from __future__ import annotations

import hashlib
import html
import importlib.metadata
import json
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from typing import Any

from docutils import nodes
from docutils.parsers.rst import Directive, directives

ROOT = Path(__file__).resolve().parents[1]
STATIC = "live"
#: The page's scripts and styles (copied by Sphinx from html_static_path).
ASSETS = Path(__file__).resolve().parent / "_static" / STATIC
#: The runtime files of the Pyodide npm package the worker loads.
PYODIDE_FILES = ("pyodide.mjs", "pyodide.asm.mjs", "pyodide.asm.wasm", "python_stdlib.zip",
                 "pyodide-lock.json", "package.json")
#: The pure-Python distributions the engine imports, packed from this environment.
DEPENDENCIES = ("lark", "mypy_extensions")


# ----------------------------------------------------------------------- the doctree

_inputs: dict[str, tuple[list, str]] = {}


def _blocks_input() -> tuple[list, str]:
    """The planning chapter's ten-block C3 scene (seed 4), as its driver writes it."""
    from sann.live import input_tree
    from sann.tasks.blocks import features, generate_scene
    from sann.tasks.planning import Planner, PlannerConfig

    with Planner(PlannerConfig(engine="sann")) as planner:
        planner.plan(features(generate_scene("C3", 10, 4)))
        tree = input_tree(planner.agent)
    return tree, "the planning chapter's ten-block C3 scene (seed 4) is on the input-link"


def _cups_input() -> tuple[list, str]:
    from sann.exercises import small_pile

    return small_pile(), "the exercises' four-cup pile (A and B on C, D on A) is on the input-link"


#: Rule files that plan what a Python driver puts on the input-link: a live cell of theirs runs
#: with one scene of the book there, recorded from the driver at build time.
SCENES = {"blocks.soar": _blocks_input, "cups.soar": _cups_input}


def scene_input(name: str | None) -> tuple[list, str] | None:
    if name not in SCENES:
        return None
    if name not in _inputs:
        _inputs[name] = SCENES[name]()
    return _inputs[name]



def project_modules() -> list[Path]:
    """The source files of the project's modules loaded in this process (a compiled module's
    ``.py`` beside it): what metadata computed by the package (a scene, an exercise) may
    have used. More than it used, which only costs a page read again for nothing."""
    found = set()
    for module in list(sys.modules.values()):
        file = getattr(module, "__file__", None)
        if not file:
            continue
        path = Path(file).resolve()
        if not path.is_relative_to(ROOT) or ".venv" in path.relative_to(ROOT).parts:
            continue
        source = path if path.suffix == ".py" else path.with_name(path.name.split(".")[0] + ".py")
        if source.exists():
            found.add(source)
    return sorted(found)


def assets_digest() -> str:
    """A digest of what every page loads from this extension: its scripts and styles, and
    this file (which says which scripts a page loads)."""
    digest = hashlib.sha256(Path(__file__).resolve().read_bytes())
    for path in sorted(ASSETS.iterdir()):
        if path.is_file():
            digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def _meta_node(meta: dict[str, Any]) -> nodes.raw:
    data = html.escape(json.dumps(meta), quote=True)
    return nodes.raw("", f'<div class="sann-live-meta" hidden data-live="{data}"></div>',
                     format="html")


def _cell_metadata(block: nodes.Element) -> dict[str, Any]:
    parent = block.parent
    while parent is not None and not hasattr(parent, "get"):
        parent = parent.parent
    while parent is not None:
        if parent.get("nb_element") == "cell_code":
            return dict(parent.get("cell_metadata") or {})
        parent = parent.parent
    return {}


def _as_list(value: object) -> list[str]:
    if value is None:
        return []
    return [value] if isinstance(value, str) else [str(v) for v in value]


def mark_soar_blocks(app, doctree: nodes.document) -> None:
    """Put a metadata element before every Soar block: the page's script makes it live."""
    index = 0
    agents: dict[str, list[int]] = {}
    computed = False  # metadata from the package's code: a scene or an exercise
    for block in list(doctree.findall(nodes.literal_block)):
        text = block.astext()
        meta: dict[str, Any] | None = None
        if block.get("sann_exercise"):
            meta = {"kind": "exercise", "exercise": block["sann_exercise"],
                    "preload": block["sann_preload"]}
            computed = True
        elif text.startswith("%%soar"):
            agent = (text.split(None, 2)[1:2] or ["soar"])[0]
            agent = agent if not agent.startswith("-") else "soar"
            meta = {"kind": "magic", "agent": agent,
                    "preload": _as_list(_cell_metadata(block).get("live-preload")),
                    "before": list(agents.get(agent, []))}
            agents.setdefault(agent, []).append(index)
        elif block.get("language") in ("soar", "soar-cell"):
            source = Path(block.get("source", ""))
            rules = ROOT / "rules"
            name = source.relative_to(rules).as_posix() if source.is_relative_to(rules) else None
            meta = {"kind": "file", "file": name}
            scene = scene_input(name)
            if scene is not None:
                meta["input"], meta["input_note"] = scene
                computed = True
        if meta is None:
            continue
        meta.update(index=index, shipped=text, page=app.env.docname)
        block.parent.insert(block.parent.index(block), _meta_node(meta))
        index += 1
    if index:
        for path in [Path(__file__).resolve(), *(project_modules() if computed else [])]:
            app.env.note_dependency(str(path))


def rewrite_on_new_assets(app, env) -> list[str]:
    """Every page, when the scripts every page loads changed since the last build."""
    digest = assets_digest()
    if getattr(env, "sann_live_assets", None) == digest:
        return []
    env.sann_live_assets = digest
    return sorted(env.found_docs)


class LiveExercise(Directive):
    """``{live-exercise} NAME``: the starting cell of an exercise of sann/exercises.py, shown
    as Soar and checked in the page after each run (the test suite runs the same checks)."""

    required_arguments = 1
    has_content = False
    option_spec = {"caption": directives.unchanged}

    def run(self) -> list[nodes.Node]:
        from sann.exercises import EXERCISES

        name = self.arguments[0]
        if name not in EXERCISES:
            raise self.error(f"no exercise {name!r} in sann/exercises.py")
        exercise = EXERCISES[name]
        block = nodes.literal_block(exercise.start, exercise.start, language="soar")
        block["sann_exercise"] = name
        block["sann_preload"] = list(exercise.preload)
        return [block]


# ----------------------------------------------------------------------- the runtime


def _npm_ci() -> Path:
    """node_modules/pyodide, installed by ``npm ci`` from the lock file when needed."""
    modules = ROOT / "node_modules"
    installed = modules / ".package-lock.json"
    lock = ROOT / "package-lock.json"
    if not installed.exists() or installed.stat().st_mtime < lock.stat().st_mtime:
        npm = shutil.which("npm")
        if npm is None:
            raise RuntimeError("the live book needs npm (Node.js) to install Pyodide: "
                               "apt-get install npm")
        done = subprocess.run([npm, "ci", "--no-audit", "--no-fund"], cwd=ROOT,
                              capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"npm ci failed:\n{done.stdout}\n{done.stderr}")
    return modules / "pyodide"


def _distribution_files(name: str) -> list[tuple[Path, str]]:
    """(installed file, path in the archive) of a distribution's importable files."""
    dist = importlib.metadata.distribution(name)
    files = []
    for entry in dist.files or []:
        path = entry.as_posix()
        if ".dist-info/" in path or path.endswith((".pyc", ".so")) or "__pycache__" in path:
            continue
        if path.startswith(".."):
            continue
        files.append((Path(dist.locate_file(entry)), path))
    return files


def engine_files() -> list[tuple[Path, str]]:
    """Everything the page's Python imports, as (source, path in the archive)."""
    files = [(ROOT / "sann" / "__init__.py", "sann/__init__.py"),
             (ROOT / "sann" / "live.py", "sann/live.py"),
             (ROOT / "sann" / "exercises.py", "sann/exercises.py")]
    soar = ROOT / "sann" / "soar"
    files += [(p, f"sann/soar/{p.relative_to(soar).as_posix()}")
              for pattern in ("**/*.py", "**/*.lark") for p in sorted(soar.glob(pattern))
              if "__pycache__" not in p.parts]
    rules = ROOT / "sann" / "rules"
    files += [(p, f"sann/rules/{p.relative_to(rules).as_posix()}")
              for p in sorted(rules.glob("**/*.soar"))]
    for name in DEPENDENCIES:
        files += _distribution_files(name)
    return files


def pack_engine(target: Path) -> None:
    """The engine archive the worker unpacks into Pyodide's file system."""
    target.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as archive:
        for source, name in engine_files():
            archive.write(source, name)


def copy_runtime(app, exception) -> None:
    if exception is not None or app.builder.format != "html":
        return
    static = Path(app.outdir) / "_static" / STATIC
    pyodide = _npm_ci()
    (static / "pyodide").mkdir(parents=True, exist_ok=True)
    for name in PYODIDE_FILES:
        shutil.copyfile(pyodide / name, static / "pyodide" / name)
    pack_engine(static / "sann-live.zip")


def setup(app) -> dict[str, Any]:
    for script in ("soar-mode.js", "graph.js", "live.js"):
        app.add_js_file(f"{STATIC}/{script}", defer="defer")
    app.add_css_file(f"{STATIC}/live.css")
    app.add_directive("live-exercise", LiveExercise)
    app.connect("doctree-read", mark_soar_blocks, priority=600)
    app.connect("env-get-updated", rewrite_on_new_assets)
    app.connect("build-finished", copy_runtime)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
