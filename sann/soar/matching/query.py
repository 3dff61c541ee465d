"""The query a query NCC node runs: one match of a conjunctive negation's inner conditions,
searched for over their alpha memories (generated nested loops, or their plain twin)."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import NamedTuple

from sann.soar.codegen import define, plain
from sann.soar.matching.alpha import AlphaMemory
from sann.soar.matching.symbols import same_symbol
from sann.soar.matching.templates import CHECK_NAMES, bucket_lines, check_lines
from sann.soar.matching.tokens import FLOAT, GET, hash_key
from sann.soar.memory import WME

#: One match of the inner conditions: the owner's values extended by what the inner
#: positive conditions bind, and the WMEs they matched; None when there is none.
Solver = Callable[[tuple, WME | None], tuple[tuple, tuple] | None]


class InnerCondition(NamedTuple):
    """One inner condition of a query NCC node, in join order."""

    #: the WMEs of its alpha memory
    wmes: dict
    #: the alpha memory's hash index on the field joined on (None: not hashed)
    index: dict | None
    #: the position of the value that field must equal (-1: not hashed)
    position: int
    #: reads the field joined on (None: not hashed)
    getter: Callable[[WME], object] | None
    #: its other tests against the values bound so far (``compile_check``)
    check: Callable | None
    #: the fields whose values it binds (none for a negated condition)
    fields: tuple[str, ...]
    negated: bool
    #: all its equality tests against values bound before it, as (field, position)
    equalities: tuple[tuple[str, int], ...]


def compile_query(levels: list[InnerCondition], seed: int, width: int) -> Solver:
    """A search for one match of a query NCC's inner conditions as nested loops, one per
    condition (a negated one as ``for ... break / else``), with condition ``seed`` (if
    any) matching only the WME passed in: the search runs for every parent token that
    could change, so its loops are unrolled into straight-line code once rather than
    walked level by level at each search (``plain_solve`` is that walk).  The owner's
    ``width`` values are read from ``values``; what the inner conditions bind is kept in
    locals, and the values tuple is built only for the match returned."""
    if plain():
        return partial(plain_solve, tuple(levels), seed)
    namespace: dict[str, object] = {**CHECK_NAMES, "FLOAT": FLOAT}
    lines = ["def solve(values, seed):"]
    depth = 1
    matched: list[str] = []
    names: dict[int, str] = {}  # value position bound inside -> local name

    def value(pos: int) -> str:
        return names.get(pos, f"values[{pos}]")

    for k, level in enumerate(levels):
        pad = "    " * depth
        namespace.update({f"alpha_wmes_{k}": level.wmes, f"alpha_index_{k}": level.index,
                          f"get_field_{k}": level.getter})
        pos = level.position
        lines += bucket_lines(k, pad, value(pos) if pos >= 0 else None, k == seed)
        lines.append(f"{pad}for wme_{k} in candidates_{k}:")
        inner = pad + "    "
        if level.check is not None:
            lines += check_lines(level.check.specs,  # type: ignore[attr-defined]
                                 "values", f"wme_{k}", "continue", inner, value)
        if level.negated:  # the levels below are the body of the else: no WME matched
            lines += [f"{inner}break", f"{pad}else:"]
        else:
            for field in level.fields:
                name = names[width + len(names)] = f"value_{width + len(names)}"
                lines.append(f"{inner}{name} = wme_{k}.{field}")
            matched.append(f"wme_{k}")
        depth += 1
    pad = "    " * depth
    bound = "".join(f"{names[p]}, " for p in sorted(names))
    lines.append(f"{pad}return {f'values + ({bound})' if bound else 'values'},"
                 f" ({''.join(w + ', ' for w in matched)})")
    lines.append("    return None")
    return define(lines, namespace, "solve", "rete:query")


def plain_solve(levels: tuple[InnerCondition, ...], seed: int, values: tuple,
                seed_wme: WME | None) -> tuple[tuple, tuple] | None:
    """Plain Python: what ``compile_query`` generates, as a depth-first walk."""
    return _search(levels, seed, seed_wme, 0, values, [])


def _search(levels: tuple[InnerCondition, ...], seed: int, seed_wme: WME | None, k: int,
            values: tuple, matched: list[WME]) -> tuple[tuple, tuple] | None:
    """The search from inner condition ``k`` on, ``values`` extended by what the conditions
    before it bound and ``matched`` their WMEs."""
    if k == len(levels):
        return values, tuple(matched)
    level = levels[k]
    pos = level.position
    if k == seed:
        fits = pos < 0 or same_symbol(values[pos], level.getter(seed_wme))  # type: ignore[misc, arg-type]
        candidates: object = (seed_wme,) if fits else ()
    elif pos < 0:
        candidates = level.wmes
    else:
        candidates = level.index.get(hash_key(values[pos]), ())  # type: ignore[union-attr]
    check = level.check
    if level.negated:
        for wme in candidates:  # type: ignore[attr-defined]
            if check is None or check(values, wme):
                return None
        return _search(levels, seed, seed_wme, k + 1, values, matched)
    for wme in candidates:  # type: ignore[attr-defined]
        if check is not None and not check(values, wme):
            continue
        matched.append(wme)
        found = _search(levels, seed, seed_wme, k + 1,
                        values + tuple(getattr(wme, field) for field in level.fields), matched)
        if found is not None:
            return found
        matched.pop()
    return None


def seed_filters(levels: list[InnerCondition], width: int, amems: list[AlphaMemory],
                 owner_tests: list[list[tuple[Callable, int]]]
                 ) -> list[list[tuple[Callable, dict]]]:
    """Semi-join filters for the WMEs that enter a query NCC's inner conditions.

    A WME entering inner condition k is tried against every unblocked owner token that
    could use it, a search each; when k tests no owner value, that is every owner.  But
    when k tests a field against a variable that another positive inner condition j binds
    (or j tests a field against one that k binds), no inner match can use the WME unless
    some WME of j's alpha memory has the same value in the corresponding field: one hash
    lookup rules out a search per owner (in the block planner, every output command and
    operator name entering ``(<above> ^name <m>)`` and ``(<il> ^block <above>)``).
    Conditions that test an owner value already narrow their candidates by hash and get no
    filter."""
    bound_at: dict[int, tuple[int, str]] = {}
    position = width
    for j, level in enumerate(levels):
        for field in level.fields:
            bound_at[position] = (j, field)
            position += 1
    filters: list[list[tuple[Callable, dict]]] = [[] for _ in levels]
    for k, level in enumerate(levels):
        if level.negated:  # a negated condition needs no match
            continue
        for field, p in level.equalities:
            if p in bound_at and bound_at[p][0] != k:
                j, bound_field = bound_at[p]
                if not owner_tests[k]:
                    filters[k].append((GET[field], amems[j].index(bound_field)))
                if not owner_tests[j]:
                    filters[j].append((GET[bound_field], amems[k].index(field)))
    return filters
