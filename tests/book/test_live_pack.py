"""The engine archive the live book's page runs (book/live_ext.py packs it at build time):
everything the page imports is in it, taken from the package's own sources."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _live_ext():
    spec = importlib.util.spec_from_file_location("live_ext", ROOT / "book" / "live_ext.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_archive_runs_the_engine_alone(tmp_path: Path) -> None:
    """Unpacked, with no site-packages (python -I -S), the archive runs a cell and a check."""
    archive = tmp_path / "sann-live.zip"
    _live_ext().pack_engine(archive)
    with zipfile.ZipFile(archive) as packed:
        names = set(packed.namelist())
        packed.extractall(tmp_path / "fs")
    assert {"sann/live.py", "sann/soar/agent.py", "sann/soar/parsing/soar.lark",
            "sann/rules/water-jug.soar", "lark/__init__.py", "mypy_extensions.py"} <= names
    assert not [n for n in names if n.endswith((".so", ".pyc"))]
    script = (
        "import json, sys; sys.path.insert(0, sys.argv[1]);"
        "import sann.live as live, sann.exercises as ex;"
        "text = open(sys.argv[1] + '/sann/rules/water-jug.soar').read();"
        "run = live.run_cell({'text': text, 'file': 'water-jug.soar', 'shipped': text});"
        "print(json.dumps([run['halted'], run['stats']['decisions'], live.__file__,"
        " ex.check('greedy-empty', '')['passed']]))"
    )
    done = subprocess.run([sys.executable, "-I", "-S", "-c", script, str(tmp_path / "fs")],
                          capture_output=True, text=True, timeout=300,
                          env={"SANN_INTERPRETED": "1"})
    assert done.returncode == 0, done.stderr
    halted, decisions, where, passed = json.loads(done.stdout.strip().splitlines()[-1])
    assert halted and decisions == 9 and not passed
    assert where.startswith(str(tmp_path / "fs"))


def test_the_archive_holds_the_package_sources() -> None:
    files = {name: source for source, name in _live_ext().engine_files()}
    for name in ("sann/soar/matching/rete.py", "sann/exercises.py", "sann/rules/hanoi.soar"):
        assert files[name] == ROOT / name


def test_the_metadata_depends_on_the_project_modules_loaded() -> None:
    """What a page with a computed scene or exercise notes as its dependencies: the project's
    module sources loaded, none of the installed packages."""
    import sann.exercises  # noqa: F401  (the exercises' metadata comes from it)

    found = _live_ext().project_modules()
    assert ROOT / "sann" / "exercises.py" in found
    assert ROOT / "sann" / "soar" / "agent.py" in found  # compiled or not: its source
    assert all(p.suffix == ".py" and p.is_relative_to(ROOT) for p in found)
    assert not any(".venv" in p.parts or "site-packages" in p.parts for p in found)
