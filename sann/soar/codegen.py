"""Running generated Python source: the Rete's node functions and the compiled RHS actions.

The source is built from the engine's own plans (never from rule text as code) and names the
data it works on only through the namespace it is run in, so equal sources can share one
compiled code object: a second agent built from the same rules (a notebook re-run, a test)
compiles nothing.

Each distinct source gets a file name of its own, ``<sann-KIND:N>`` (``KIND`` says what made
it: ``rete:join``, ``rete:query-ncc``...), whose lines are put in :mod:`linecache`: a
traceback through generated code shows its lines, ``inspect.getsource`` returns them and a
debugger can step through them.

Every generated function has a plain Python twin (ordinary methods of the same node doing
the same work in the same order), which runs instead when ``SANN_PLAIN=1`` is set in the
environment (read once, at import) or after ``use_plain(True)``: the property tests compare
the two.
"""

from __future__ import annotations

import itertools
import linecache
import os
from collections.abc import Callable
from functools import lru_cache
from types import CodeType

_PLAIN = [os.environ.get("SANN_PLAIN", "") not in ("", "0")]
_SERIALS = itertools.count(1)


def plain() -> bool:
    """Whether nodes made from now on run their plain Python twins instead of generated code."""
    return _PLAIN[0]


def use_plain(flag: bool) -> bool:
    """Make the nodes generated from now on plain (``True``) or generated; return the previous
    setting.  For tests: nodes already made keep what they run."""
    previous = _PLAIN[0]
    _PLAIN[0] = flag
    return previous


@lru_cache(maxsize=4096)
def compiled(source: str, kind: str) -> CodeType:
    """``compile(source, ...)`` once per distinct pair, under a file name of its own whose
    lines :mod:`linecache` holds."""
    filename = f"<sann-{kind.strip('<>')}:{next(_SERIALS)}>"
    # No modification time: linecache.checkcache keeps the entry (there is no file to check).
    linecache.cache[filename] = (len(source), None, source.splitlines(keepends=True), filename)
    return compile(source, filename, "exec")


def define(lines: list[str], namespace: dict[str, object], name: str,
           kind: str = "rete") -> Callable:
    """Run the source ``lines`` in ``namespace`` and return the function ``name`` it defines;
    ``kind`` names what made it (in its file name).

    The function is taken out of its own globals: one that named itself there would be a
    reference cycle, left to the cyclic garbage collector when the code is regenerated."""
    _string_keyed(namespace)
    exec(_fresh(compiled("\n".join(lines) + "\n", kind)), namespace)  # noqa: S102 -- our own plans only
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
