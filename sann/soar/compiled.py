"""The compiled engine, and when not to use it.

``make`` compiles the engine's hot modules with mypyc (``setup.py build_ext --inplace``) into
C extension modules beside their sources; Python imports an extension module before the
``.py`` of the same name. An edited source would then be shadowed by its older extension
module, so the build records the hashes of the sources it compiled (``MANIFEST``), and when
a source no longer matches them the whole engine is imported from source, with a warning
(the compiled modules call each other directly, so they go together or not at all).
``SANN_INTERPRETED=1`` asks for the sources on purpose (tests of the interpreted engine,
debugging with pdb).

Only the standard library here: setup.py and the Makefile load this file before the package
is importable.
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import os
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType

PACKAGE = "sann.soar"
HERE = Path(__file__).resolve().parent
#: The modules mypyc compiles: the decision cycle, matching and memory (not the parser, the
#: printer or the commands, whose speed does not matter, nor the code generator). The only list
#: of them: setup.py compiles these and the Makefile rebuilds when one changes (``--sources``).
#: A name is relative to this package, dotted for a subpackage's module ("matching.rete").
MODULES = (
    "memory",
    "preferences",
    "instantiation",
    "goals",
    "decision.preference_semantics",
    "decision.agent_state",
    "decision.working_memory",
    "decision.firing_order",
    "decision.matches",
    "decision.results",
    "decision.firing",
    "decision.wm_phase",
    "decision.substates",
    "decision.decide",
    "decision.cycle",
    "agent",
    "matching.symbols",
    "matching.variables",
    "matching.matches",
    "matching.oracle",
    "matching.tokens",
    "matching.plan",
    "matching.templates",
    "matching.alpha",
    "matching.nodes",
    "matching.query",
    "matching.query_ncc",
    "matching.runs",
    "matching.production_node",
    "matching.join_order",
    "matching.build",
    "matching.rete",
    "matching.kernel_prefix",
    "matching.kernel_order",
)
#: The shared library of the compiled modules is ``sann/soar/_engine__mypyc.*.so``.
GROUP = f"{PACKAGE}._engine"
MANIFEST = HERE / "_engine.sha256"


def source_file(name: str, directory: Path = HERE) -> Path:
    """The source of the compiled module ``name`` ("matching.rete" is matching/rete.py)."""
    return directory.joinpath(*name.split(".")).with_suffix(".py")


def source_hashes(directory: Path = HERE) -> dict[str, str]:
    """SHA-256 of each compiled module's source, by module name."""
    return {
        name: hashlib.sha256(source_file(name, directory).read_bytes()).hexdigest()
        for name in MODULES
    }


def write_manifest(hashes: dict[str, str], path: Path = MANIFEST) -> None:
    """Record the hashes of the sources just compiled (written whole or not at all)."""
    partial = path.with_suffix(".partial")
    partial.write_text("".join(f"{digest}  {name}\n" for name, digest in hashes.items()))
    partial.replace(path)


def read_manifest(path: Path = MANIFEST) -> dict[str, str]:
    """The hashes a build recorded, by module name (empty when there is no build)."""
    if not path.exists():
        return {}
    hashes = {}
    for line in path.read_text().splitlines():
        digest, _, filename = line.partition("  ")
        hashes[filename.removesuffix(".py")] = digest
    return hashes


def extension_modules(directory: Path = HERE) -> list[Path]:
    """The compiled modules' extension files present beside the sources."""
    suffixes = importlib.machinery.EXTENSION_SUFFIXES
    stems = [source_file(name, directory).with_suffix("") for name in MODULES]
    return [stem.with_name(stem.name + suffix) for stem in stems for suffix in suffixes
            if stem.with_name(stem.name + suffix).exists()]


def stale_modules(directory: Path = HERE, manifest: Path = MANIFEST) -> list[str]:
    """Modules whose source is not the one their extension module was compiled from."""
    recorded = read_manifest(manifest)
    current = source_hashes(directory)
    return [name for name in MODULES if recorded.get(name) != current[name]]


class _SourceFinder:
    """Finds the compiled modules' ``.py`` files, ahead of their extension modules."""

    def find_spec(self, fullname: str, path: Sequence[str] | None = None,
                  target: ModuleType | None = None) -> importlib.machinery.ModuleSpec | None:
        package, _, name = fullname.partition(f"{PACKAGE}.")
        if package or name not in MODULES:
            return None
        return importlib.util.spec_from_file_location(fullname, source_file(name))


def choose_engine() -> None:
    """Before the engine's modules are imported: use the sources when there is no build to
    use, when they were edited since the build, or when asked to."""
    if not extension_modules():
        return
    if os.environ.get("SANN_INTERPRETED", "") not in ("", "0"):
        reason = None
    elif stale := stale_modules():
        older = ", ".join(source_file(n).relative_to(HERE).as_posix() for n in stale)
        reason = (f"the compiled engine is older than {older}: "
                  "running the sources instead (slower); `make` recompiles it")
    else:
        return
    if not any(isinstance(finder, _SourceFinder) for finder in sys.meta_path):
        sys.meta_path.insert(0, _SourceFinder())
    if reason:
        warnings.warn(reason, RuntimeWarning, stacklevel=2)


def _print_sources() -> None:
    """``python sann/soar/compiled.py --sources``: the compiled modules' source files, relative
    to the working directory, for the Makefile (which runs before the package is importable)."""
    print(" ".join(os.path.relpath(source_file(name)) for name in MODULES))


def is_compiled() -> bool:
    """Whether the engine running in this process is the compiled one."""
    from . import memory

    return not str(memory.__file__).endswith(".py")


if __name__ == "__main__":
    if sys.argv[1:] != ["--sources"]:
        sys.exit("usage: python sann/soar/compiled.py --sources")
    _print_sources()
