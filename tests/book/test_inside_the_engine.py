"""The chapter "Inside the engine" names the engine's functions and shows its source files:
every name it writes as code (``decision.cycle.run_phase``, relative to ``sann.soar``)
exists, and every file it links or includes is there, with the function it includes."""

from __future__ import annotations

import ast
import importlib
import re
from pathlib import Path

BOOK = Path(__file__).resolve().parents[2] / "book"
CHAPTER = BOOK / "inside-the-engine.md"
PACKAGES = ("decision", "matching", "parsing", "rhs", "chunking", "instantiation",
            "preferences", "memory", "goals", "codegen", "agent", "text")
NAME = re.compile(rf"`((?:{'|'.join(PACKAGES)})(?:\.\w+)+)`")


def resolve(dotted: str) -> object:
    """The object ``sann.soar.<dotted>``: the longest prefix that is a module, then
    attributes."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            found: object = importlib.import_module("sann.soar." + ".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for attribute in parts[cut:]:
            found = getattr(found, attribute)
        return found
    raise ModuleNotFoundError(dotted)


def test_every_function_the_chapter_names_exists() -> None:
    text = CHAPTER.read_text(encoding="utf-8")
    names = sorted(set(NAME.findall(text)))
    assert len(names) >= 30, names  # the chapter names the cycle's functions as code
    missing = []
    for name in names:
        try:
            resolve(name)
        except (ModuleNotFoundError, AttributeError):
            missing.append(name)
    assert not missing, f"named in {CHAPTER.name} but not in sann.soar: {missing}"


def test_every_linked_file_and_included_function_exists() -> None:
    text = CHAPTER.read_text(encoding="utf-8")
    links = re.findall(r"\{download\}`[^<`]*<([^>]+)>`", text)
    includes = re.findall(r"```\{literalinclude\} (\S+)\n:pyobject: (\w+)", text)
    assert links and includes
    for link in links:
        assert (BOOK / link).resolve().is_file(), link
    for path, function in includes:
        tree = ast.parse((BOOK / path).read_text(encoding="utf-8"))
        defined = {node.name for node in tree.body if isinstance(node, ast.FunctionDef)}
        assert function in defined, f"{path} has no function {function}"


def test_a_wrong_name_is_caught() -> None:
    assert resolve("decision.cycle.run_phase") is not None
    for wrong in ("decision.cycle.no_such_phase", "decision.nowhere.run_phase"):
        try:
            resolve(wrong)
        except (ModuleNotFoundError, AttributeError):
            continue
        raise AssertionError(f"{wrong} resolved")
