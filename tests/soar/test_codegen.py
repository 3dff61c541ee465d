"""Generated code: compiled once per source, and specialized by the interpreter."""

from __future__ import annotations

import dis
import sys

import pytest

from sann.soar.codegen import compiled, define

SOURCE = ["def read(x):", "    return A + B + x"]


def _global_reads(function: object) -> list[str]:
    code = function.__code__  # type: ignore[attr-defined]
    return [i.opname for i in dis.get_instructions(code, adaptive=True)
            if i.opname.startswith("LOAD_GLOBAL")]


def _general_dict() -> dict[str, object]:
    """String keys in a dict of CPython's general kind (what a mypyc dict display of more
    than five items builds): a non-string key once in it leaves it general."""
    namespace: dict[object, object] = {0: None}
    namespace.update(A=1, B=2)
    del namespace[0]
    return namespace  # type: ignore[return-value]


def test_define_returns_the_function_and_leaves_the_namespace_without_it() -> None:
    namespace = _general_dict()
    read = define(SOURCE, namespace, "read", "<test>")
    assert read(3) == 6
    assert "read" not in namespace
    namespace["A"] = 10  # the function reads the namespace it was defined in
    assert read(3) == 15


@pytest.mark.skipif(sys.version_info[:2] != (3, 11), reason="CPython 3.11's opcode names")
def test_global_reads_are_specialized_in_any_namespace() -> None:
    read = define(SOURCE, _general_dict(), "read", "<test>")
    for _ in range(20):
        read(1)
    assert _global_reads(read) == ["LOAD_GLOBAL_MODULE", "LOAD_GLOBAL_MODULE"]


@pytest.mark.skipif(sys.version_info[:2] != (3, 11), reason="CPython 3.11's opcode names")
def test_functions_from_one_source_keep_their_own_specializations() -> None:
    """Two namespaces, one compiled source: each function's bytecode is its own, so
    calling them in turn does not undo the other's specialization."""
    first = define(SOURCE, {"A": 1, "B": 2}, "read", "<test-shared>")
    second = define(SOURCE, {"B": 2, "A": 1, "C": 3}, "read", "<test-shared>")
    assert compiled.cache_info().currsize >= 1
    assert first.__code__ is not second.__code__
    for _ in range(20):
        first(1)
        second(1)
    assert _global_reads(first) == _global_reads(second) == ["LOAD_GLOBAL_MODULE"] * 2
