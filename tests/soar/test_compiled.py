"""The compiled engine (mypyc, built by ``make``) and its fallback to the sources."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from sann.soar import compiled

ROOT = Path(__file__).resolve().parents[2]
BUILT = bool(compiled.extension_modules())


def _python(code: str, cwd: Path = ROOT, **env: str) -> subprocess.CompletedProcess[str]:
    """Run ``code`` in a new interpreter, the compiled engine allowed unless ``env`` asks
    otherwise (this suite may itself run with SANN_INTERPRETED=1)."""
    base = {k: v for k, v in os.environ.items() if k != "SANN_INTERPRETED"}
    return subprocess.run([sys.executable, "-W", "always", "-c", code], cwd=cwd, text=True,
                          capture_output=True, env={**base, **env}, timeout=300)


def _fake_tree(tmp_path: Path) -> Path:
    for name in compiled.MODULES:
        source = compiled.source_file(name, tmp_path)
        source.parent.mkdir(parents=True, exist_ok=True)
        source.write_text(f"NAME = {name!r}\n")
    return tmp_path


def test_manifest_round_trip_and_stale_sources(tmp_path: Path) -> None:
    tree = _fake_tree(tmp_path)
    manifest = tree / "_engine.sha256"
    assert compiled.stale_modules(tree, manifest) == list(compiled.MODULES)  # no build yet
    compiled.write_manifest(compiled.source_hashes(tree), manifest)
    assert compiled.read_manifest(manifest) == compiled.source_hashes(tree)
    assert compiled.stale_modules(tree, manifest) == []
    edited = compiled.MODULES[1]
    compiled.source_file(edited, tree).write_text("NAME = 'edited'\n")
    assert compiled.stale_modules(tree, manifest) == [edited]
    assert not list(tree.glob("*.partial"))


def test_make_test_runs_the_compiled_engine() -> None:
    """``make test`` compiles the engine first, and the suite must run what ships."""
    if not BUILT:
        pytest.skip("no compiled engine here (`make engine` builds it)")
    if os.environ.get("SANN_INTERPRETED"):
        pytest.skip("the interpreted engine was asked for")
    assert compiled.stale_modules() == []
    assert compiled.is_compiled()


@pytest.mark.skipif(not BUILT, reason="no compiled engine here")
def test_interpreted_on_request() -> None:
    code = ("from sann.soar import compiled, agent; from sann.soar.matching import rete; "
            "print(compiled.is_compiled(), agent.__file__.endswith('.py'), "
            "rete.__file__.endswith('.py'))")
    run = _python(code, SANN_INTERPRETED="1")
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == ["False", "True", "True"]
    assert "RuntimeWarning" not in run.stderr


@pytest.mark.skipif(not BUILT, reason="no compiled engine here")
def test_edited_module_runs_as_edited_not_compiled(tmp_path: Path) -> None:
    """A copy of the package, built, with decision/decide.py edited after the build: the engine
    runs from the sources (the edit shows), with a warning naming the module."""
    shutil.copytree(ROOT / "sann", tmp_path / "sann",
                    ignore=shutil.ignore_patterns("__pycache__"))
    decide = tmp_path / "sann" / "soar" / "decision" / "decide.py"
    decide.write_text(decide.read_text() + "\nEDITED = True\n")
    code = ("from sann.soar import compiled; from sann.soar.decision import decide; "
            "print(compiled.is_compiled(), getattr(decide, 'EDITED', False), decide.__file__)")
    run = _python(code, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    is_compiled, edited, path = run.stdout.split()
    assert (is_compiled, edited) == ("False", "True")
    assert Path(path).is_relative_to(tmp_path)
    assert re.search(r"the compiled engine is older than [^:]*\bdecide\.py", run.stderr)


@pytest.mark.slow
@pytest.mark.skipif(not BUILT, reason="without a build the whole suite runs interpreted")
def test_interpreted_engine_passes_the_differential_agents() -> None:
    """The sources stay a working engine (a stale build runs them): the agents of the
    differential suite and the random agents, interpreted, against the kernel."""
    run = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider",
         "tests/soar/differential", "tests/soar/test_world_agents.py"],
        cwd=ROOT, text=True, capture_output=True, timeout=1200,
        env={**os.environ, "SANN_INTERPRETED": "1"})
    assert run.returncode == 0, run.stdout[-3000:]
    assert " passed" in run.stdout


def test_makefile_and_setup_read_the_one_list_of_modules() -> None:
    """``compiled.py --sources`` (what the Makefile's prerequisites are) names each module of
    MODULES by its source file, dotted names as subpackage paths."""
    run = subprocess.run([sys.executable, "sann/soar/compiled.py", "--sources"], cwd=ROOT,
                         text=True, capture_output=True, timeout=60)
    assert run.returncode == 0, run.stderr
    listed = run.stdout.split()
    assert listed == [compiled.source_file(name).relative_to(ROOT).as_posix()
                      for name in compiled.MODULES]
    assert all((ROOT / path).is_file() for path in listed)
    assert compiled.source_file("matching.rete", Path("/x")) == Path("/x/matching/rete.py")


def test_a_dotted_module_is_found_in_its_subpackage(tmp_path: Path, monkeypatch) -> None:
    """A subpackage's module ("parsing.parser") has its source, its extension file and its
    source-first import where its dotted name says."""
    monkeypatch.setattr(compiled, "MODULES", ("memory", "parsing.parser"))
    stem = tmp_path / "parsing" / "parser"
    stem.parent.mkdir()
    stem.with_suffix(".py").write_text("")
    built = stem.with_name("parser" + compiled.importlib.machinery.EXTENSION_SUFFIXES[0])
    built.write_text("")
    assert compiled.extension_modules(tmp_path) == [built]
    spec = compiled._SourceFinder().find_spec("sann.soar.parsing.parser")
    assert spec is not None and spec.origin == str(compiled.HERE / "parsing" / "parser.py")
    assert compiled._SourceFinder().find_spec("sann.soar.parser") is None
    assert compiled._SourceFinder().find_spec("sann.soar.parsing.errors") is None
