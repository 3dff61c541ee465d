"""Tokens of the kernel's beta memories, found on demand by a search over working memory.

The kernel-order model (kernel_order.py) keeps no tokens; when the agent needs to know
whether a kernel beta memory holds a token (a join relinked when its memory got one) it asks
``prefix_token``, which finds one partial match of the conditions above the join.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from sann.soar.matching.oracle import final_tests_hold, still_hold, wme_fits
from sann.soar.matching.variables import condition_fields, equality_vars, relational_vars
from sann.soar.memory import WME, Symbol
from sann.soar.production import (
    Condition,
    ConditionElement,
    ConjunctiveNegation,
)

#: The WMEs that may match a condition given the bindings so far (a superset: those of its
#: bound identifier and constant attribute, say), for the searches below.
Candidates = Callable[[Condition, dict[str, Symbol]], Iterable[WME]]


def prefix_token(ordered: list, count: int, candidates: Candidates,
                 order: tuple[int, ...]) -> tuple | None:
    """A token of the kernel's beta memory above its ``count``-th condition (in
    ``ordered``, the kernel's order: ``reorder.KCond``s), as the WMEs of the positive
    conditions whose written indexes are ``order``, or None when the memory is empty.
    The negations and conjunctive negations right above the join are not tested: the
    kernel's negative and NCC nodes, which are then the join's parent, keep the tokens
    they block in their memory too.

    A depth-first search that stops at the first token, each condition looking only at
    the WMEs ``candidates`` gives it (those of its bound identifier): its cost is that of
    finding one partial match, not of listing all of them (a prefix of several
    multi-valued attributes of the state has thousands)."""
    while count and (ordered[count - 1].negated or ordered[count - 1].is_ncc):
        count -= 1  # a negative or NCC node holds its blocked tokens too (no beta memory)
    chosen: list[tuple[int, Condition, WME]] = []
    if not _prefix_search(ordered, 0, count, {}, chosen, _rechecks(ordered), candidates):
        return None
    by_index: dict[int, WME] = {}
    for index, _, wme in chosen:
        by_index.setdefault(index, wme)
    return tuple([by_index.get(j) for j in order])


def _prefix_search(ordered: list, k: int, count: int, bindings: dict[str, Symbol],
                   chosen: list[tuple[int, Condition, WME]], rechecks: list[tuple[int, ...]],
                   candidates: Candidates) -> bool:
    """``prefix_token``'s search from condition ``k`` on, ``chosen`` the WMEs so far (a
    function of its own: a nested one calling itself is a reference cycle, left to the
    cyclic collector at every call)."""
    if k == count:
        return True
    kcond = ordered[k]
    element = kcond.element
    if kcond.negated or kcond.is_ncc:
        inner = element.conditions if kcond.is_ncc else (_positive(element),)
        return (not _exists(inner, bindings, candidates)
                and _prefix_search(ordered, k + 1, count, bindings, chosen, rechecks,
                                   candidates))
    earlier = rechecks[k]
    for wme in candidates(element, bindings):
        extended = wme_fits(element, wme, bindings)
        if extended is None or (earlier and not still_hold(
                tuple((chosen[j][1], chosen[j][2]) for j in earlier), extended)):
            continue
        chosen.append((kcond.index, element, wme))
        if _prefix_search(ordered, k + 1, count, extended, chosen, rechecks, candidates):
            return True
        chosen.pop()
    return False


def _rechecks(ordered: list) -> list[tuple[int, ...]]:
    """Per condition of ``ordered``, the positive conditions before it (as places in the
    search's list of chosen WMEs) whose relational tests wait for a variable it binds
    first: they are tested again when it joins, as the kernel's Rete moves them."""
    hit = _RECHECKS.get(id(ordered))
    if hit is not None and hit[0] is ordered:  # (the order they are of, the rechecks)
        return hit[1]
    bound: set[str] = set()
    waiting: list[set[str]] = []  # per positive condition so far: its relational variables
    rechecks: list[tuple[int, ...]] = []
    for kcond in ordered:
        if kcond.negated or kcond.is_ncc:
            rechecks.append(())
            continue
        fields = condition_fields(kcond.element)
        new = {name for test in fields for name in equality_vars(test)} - bound
        rechecks.append(tuple(j for j, names in enumerate(waiting) if names & new))
        bound |= new
        waiting.append({name for test in fields for name in relational_vars(test)})
    if len(_RECHECKS) >= 4096:
        _RECHECKS.clear()
    _RECHECKS[id(ordered)] = (ordered, rechecks)
    return rechecks


_RECHECKS: dict[int, tuple[list, list[tuple[int, ...]]]] = {}


def _positive(cond: Condition) -> Condition:
    return Condition(cond.id_test, cond.attr_test, cond.value_test,
                     acceptable=cond.acceptable, goal=cond.goal)


def _exists(elements: tuple[ConditionElement, ...], bindings: dict[str, Symbol],
            candidates: Candidates) -> bool:
    """Whether ``elements`` (one scope: a conjunctive negation's conditions) have a match
    given ``bindings``: ``brute_force_solutions`` depth first over ``candidates``, the
    positive conditions taken on a bound identifier first where one is."""
    positives = [e for e in elements if isinstance(e, Condition) and not e.negated]
    negations = [e for e in elements if not (isinstance(e, Condition) and not e.negated)]
    return _exists_search(positives, dict(bindings), [], negations, candidates)


def _exists_search(left: list[Condition], current: dict[str, Symbol],
                   pairs: list[tuple[Condition, WME]], negations: list[ConditionElement],
                   candidates: Candidates) -> bool:
    """``_exists`` with the positive conditions ``left`` to match and ``pairs`` matched."""
    if not left:
        return (all(final_tests_hold(cond, wme, current) for cond, wme in pairs)
                and not any(_exists(n.conditions if isinstance(n, ConjunctiveNegation)
                                    else (_positive(n),), current, candidates)  # type: ignore[arg-type]
                            for n in negations))
    pick = next((c for c in left if any(name in current
                                        for name in equality_vars(c.id_test))), left[0])
    rest = [c for c in left if c is not pick]
    for wme in candidates(pick, current):
        extended = wme_fits(pick, wme, current)
        if extended is None:
            continue
        pairs.append((pick, wme))
        if _exists_search(rest, extended, pairs, negations, candidates):
            return True
        pairs.pop()
    return False
