"""Running generated Python source: the Rete's node functions and the compiled RHS actions.

The source is built from the engine's own plans (never from rule text as code) and names the
data it works on only through the namespace it is run in, so equal sources can share one
compiled code object: a second agent built from the same rules (a notebook re-run, a test)
compiles nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache
from types import CodeType


@lru_cache(maxsize=4096)
def compiled(source: str, filename: str) -> CodeType:
    """``compile(source, filename, "exec")``, once per distinct pair."""
    return compile(source, filename, "exec")


def define(lines: list[str], namespace: dict[str, object], name: str,
           filename: str = "<rete>") -> Callable:
    """Run the source ``lines`` in ``namespace`` and return the function ``name`` it defines.

    The function is taken out of its own globals: one that named itself there would be a
    reference cycle, left to the cyclic garbage collector when the code is regenerated."""
    _string_keyed(namespace)
    exec(_fresh(compiled("\n".join(lines), filename)), namespace)  # noqa: S102 -- our own plans only
    return namespace.pop(name)  # type: ignore[return-value]


def _string_keyed(namespace: dict[str, object]) -> None:
    """Make ``namespace`` a dict of CPython's string-keys kind, in place.

    Only such a globals dict lets the interpreter specialize the generated code's global
    reads (``LOAD_GLOBAL_MODULE``, a version check and an index); any other kind leaves
    every read to the generic lookup, several times slower.  A dict display of more than
    five items in mypyc-compiled code is built presized, which is the general kind."""
    items = list(namespace.items())
    namespace.clear()
    namespace.update(items)


def _fresh(code: CodeType) -> CodeType:
    """A copy of the module ``code`` whose functions have bytecode of their own.

    The interpreter specializes a function's bytecode in place, for the globals it last ran
    with; equal sources share one compiled code object, so the functions of two nodes made
    from it would undo each other's specializations on every call."""
    consts = tuple(c.replace() if isinstance(c, CodeType) else c for c in code.co_consts)
    return code.replace(co_consts=consts)
