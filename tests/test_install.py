"""A non-editable install (``pip install .``) carries its data: run from outside the
repository, it parses the grammar and runs a shipped rule file as the repository's sources do.

The new environment gets this environment's packages (lark, pip, setuptools) through a path
file naming its site-packages: ``venv --system-site-packages`` would give the base
interpreter's, and this environment's own ``.pth`` files (the editable install of this
repository among them) are not run from a plain path entry, so ``import sann`` can only find
the installed copy.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: What ``pip install .`` reads: the package, its build files, and the rules sann/rules links to.
SOURCES = ("sann", "rules", "pyproject.toml", "setup.py", "README.md")
SKIPPED = shutil.ignore_patterns("__pycache__", "*.so", "_engine.sha256", "*.egg-info", "build")


def _run(args: list[str], cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PIP_NO_INDEX"] = "1"  # offline: nothing may be downloaded
    return subprocess.run(args, cwd=cwd, env=env, text=True, capture_output=True,
                          timeout=timeout)


def _copy_sources(target: Path) -> Path:
    """The repository's files that ``pip install .`` reads, symlinks kept as links."""
    for name in SOURCES:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, target / name, symlinks=True, ignore=SKIPPED)
        else:
            shutil.copy2(source, target / name)
    return target


def _venv(target: Path) -> Path:
    """A virtual environment that sees this one's packages; its python."""
    done = _run([sys.executable, "-m", "venv", "--without-pip", str(target)], cwd=target.parent)
    assert done.returncode == 0, done.stderr
    python = target / "bin" / "python"
    purelib = _run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                   cwd=target.parent).stdout.strip()
    Path(purelib, "parent-environment.pth").write_text(sysconfig.get_path("purelib") + "\n")
    return python


@pytest.mark.slow
def test_an_installed_package_runs_water_jug_outside_the_repository(tmp_path: Path) -> None:
    source = _copy_sources(tmp_path / "source")
    python = _venv(tmp_path / "venv")
    install = _run([str(python), "-m", "pip", "install", "--quiet", "--no-deps",
                    "--no-build-isolation", str(source)], cwd=tmp_path)
    assert install.returncode == 0, install.stdout + install.stderr
    shutil.rmtree(source)  # nothing may still read the copy it was installed from

    outside = tmp_path / "elsewhere"
    outside.mkdir()
    where = _run([str(python), "-c", "import sann, sann.soar.parsing.parser as p; "
                  "print(sann.RULES); print(p.__file__)"], cwd=outside)
    assert where.returncode == 0, where.stderr
    rules, parser = (Path(line) for line in where.stdout.split())
    site = Path(_run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                     cwd=outside).stdout.strip())
    assert rules.is_relative_to(site) and parser.is_relative_to(site)
    assert not rules.is_symlink() and (rules / "default" / "selection.soar").is_file()
    grammar = parser.with_name("soar.lark")
    assert grammar.is_file() and not grammar.is_symlink()

    command = ["-m", "sann.soar", str(rules / "water-jug.soar"), "--seed", "1", "--stats"]
    installed = _run([str(python), *command], cwd=outside)
    assert installed.returncode == 0, installed.stderr
    here = _run([sys.executable, *command[:2], str(ROOT / "rules" / "water-jug.soar"),
                 *command[3:]], cwd=ROOT)
    assert here.returncode == 0, here.stderr
    assert installed.stdout == here.stdout
    assert "9 decisions" in installed.stdout
