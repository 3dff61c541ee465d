"""Whether two chunks are the same rule up to variable names (conditions, the conditions
inside a conjunctive negation, and actions in any order): how a chunk of this engine is
compared with the kernel's, whose printer groups a chunk's actions by identifier and orders
its conditions its own way."""

from __future__ import annotations

from dataclasses import replace

from ..production import ConjunctiveNegation, Production, _match_elements, duplicate_key, shape


def same_chunk(a: Production, b: Production) -> bool:
    a, b = _canonical(a), _canonical(b)
    if duplicate_key(a)[0] != duplicate_key(b)[0]:
        return False
    mapping: dict[str, str] = {}
    reverse: dict[str, str] = {}
    if not _match_elements(list(a.conditions), list(b.conditions), mapping, reverse):
        return False
    return _match_elements(list(a.actions), list(b.actions), mapping, reverse)


def _canonical(production: Production) -> Production:
    """The production with each conjunctive negation's conditions in one order."""
    conditions = tuple(
        ConjunctiveNegation(tuple(sorted(c.conditions, key=lambda x: repr(shape(x)))))
        if isinstance(c, ConjunctiveNegation) else c
        for c in production.conditions)
    return replace(production, conditions=conditions)
