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
    exec(compiled("\n".join(lines), filename), namespace)  # noqa: S102 -- our own plans only
    return namespace.pop(name)  # type: ignore[return-value]
