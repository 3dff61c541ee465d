"""Whether two chunks are the same rule up to variable names (conditions and actions in any
order): how a chunk of this engine is compared with the kernel's, whose printer groups a
chunk's actions by identifier and orders its conditions its own way."""

from __future__ import annotations

from ..production import Production, _match_elements, duplicate_key


def same_chunk(a: Production, b: Production) -> bool:
    if duplicate_key(a)[0] != duplicate_key(b)[0]:
        return False
    mapping: dict[str, str] = {}
    reverse: dict[str, str] = {}
    if not _match_elements(list(a.conditions), list(b.conditions), mapping, reverse):
        return False
    return _match_elements(list(a.actions), list(b.actions), mapping, reverse)
