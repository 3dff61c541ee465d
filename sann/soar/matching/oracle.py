"""The brute-force matcher: a naive join over all WMEs, written to be obviously correct.

It is the oracle of the Rete's property tests, and its joins (``join_condition``,
``negation_matches``, ``wme_fits``) serve the views that list partial matches on demand
(``matches``, the kernel-order model), which must not depend on the Rete's own state.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

from sann.soar.errors import SoarSemanticError
from sann.soar.matching.matches import Changes, Match
from sann.soar.matching.symbols import RELATIONS, same_symbol
from sann.soar.matching.variables import condition_fields, equality_vars
from sann.soar.memory import WME, Symbol
from sann.soar.parsing.checks import check_production
from sann.soar.production import (
    Condition,
    ConditionElement,
    ConjunctiveNegation,
    Const,
    Disjunction,
    Production,
    Relational,
    Test,
    Var,
)


def test_holds(test: Test, value: Symbol, bindings: dict[str, Symbol], final: bool) -> bool:
    """Non-binding part of a field test; relational tests on a not-yet-bound variable are
    skipped unless ``final`` (they are then checked once every variable is bound)."""
    if isinstance(test, Const):
        return same_symbol(value, test.value)
    if isinstance(test, Var):
        return True
    if isinstance(test, Disjunction):
        return any(same_symbol(value, c.value) for c in test.values)
    if isinstance(test, Relational):
        operand = test.operand
        if isinstance(operand, Const):
            return RELATIONS[test.op](value, operand.value)
        if operand.name not in bindings:
            return not final
        return RELATIONS[test.op](value, bindings[operand.name])
    return all(test_holds(t, value, bindings, final) for t in test.tests)


def _bind_field(test: Test, value: Symbol, bindings: dict[str, Symbol]) -> bool:
    """Bind or equality-test the variables of a field; False when an equality fails."""
    for name in equality_vars(test):
        if name in bindings:
            if not same_symbol(bindings[name], value):
                return False
        else:
            bindings[name] = value
    return True


def wme_fits(cond: Condition, wme: WME, bindings: dict[str, Symbol]) -> dict[str, Symbol] | None:
    """Bindings extended by matching ``cond`` against ``wme``, or None."""
    if wme.acceptable != cond.acceptable:
        return None
    if cond.goal is not None and wme.id.level is None:
        return None
    extended = dict(bindings)
    for test, value in zip(condition_fields(cond), (wme.id, wme.attr, wme.value), strict=True):
        if not _bind_field(test, value, extended):
            return None
    for test, value in zip(condition_fields(cond), (wme.id, wme.attr, wme.value), strict=True):
        if not test_holds(test, value, extended, final=False):
            return None
    return extended


def final_tests_hold(cond: Condition, wme: WME, bindings: dict[str, Symbol]) -> bool:
    return all(
        test_holds(test, value, bindings, final=True)
        for test, value in zip(condition_fields(cond), (wme.id, wme.attr, wme.value), strict=True)
    )


def brute_force_solutions(
    elements: tuple[ConditionElement, ...], wmes: list[WME], bindings: dict[str, Symbol]
) -> Iterator[tuple[list[WME | None], dict[str, Symbol]]]:
    """Every consistent match of ``elements`` (one scope) given outer ``bindings``.

    Positive conditions are joined by backtracking in written order; relational tests whose
    operand is bound only later are checked at the end; then every negation must find no
    match with the full bindings.
    """
    positives = [(i, e) for i, e in enumerate(elements)
                 if isinstance(e, Condition) and not e.negated]
    negations = [e for e in elements if not (isinstance(e, Condition) and not e.negated)]
    chosen: list[WME | None] = [None] * len(elements)

    def extend(k: int, current: dict[str, Symbol]) -> Iterator[dict[str, Symbol]]:
        if k == len(positives):
            yield current
            return
        index, cond = positives[k]
        for wme in wmes:
            extended = wme_fits(cond, wme, current)
            if extended is not None:
                chosen[index] = wme
                yield from extend(k + 1, extended)
        chosen[index] = None

    for full in extend(0, dict(bindings)):
        if not all(final_tests_hold(cond, chosen[i], full) for i, cond in positives):
            continue
        if any(negation_matches(n, wmes, full) for n in negations):
            continue
        yield list(chosen), full


def negation_matches(element: ConditionElement, wmes: list[WME],
                     bindings: dict[str, Symbol]) -> bool:
    """Whether a negated condition or conjunctive negation finds a match among ``wmes``."""
    if isinstance(element, ConjunctiveNegation):
        inner = element.conditions
    else:
        inner = (Condition(element.id_test, element.attr_test, element.value_test,
                           acceptable=element.acceptable, goal=element.goal),)
    return next(brute_force_solutions(inner, wmes, bindings), None) is not None


#: A partial match as the brute-force views build it: the bindings so far and the
#: (condition, WME) pairs joined.
PartialMatch = tuple[dict[str, Symbol], tuple[tuple[Condition, WME], ...]]


def join_condition(cond: Condition, tokens: list[PartialMatch], wmes: Iterable[WME],
                   first: bool = False) -> list[PartialMatch]:
    """The partial matches ``tokens`` joined with a positive condition over ``wmes`` (in
    that order); relational tests of the earlier pairs on variables bound only now are
    checked now, as the kernel's Rete moves them. ``first``: stop at the first."""
    out: list[PartialMatch] = []
    for bindings, pairs in tokens:
        for wme in wmes:
            extended = wme_fits(cond, wme, bindings)
            if extended is not None and still_hold(pairs, extended):
                out.append((extended, (*pairs, (cond, wme))))
                if first:
                    return out
    return out


def still_hold(pairs: tuple[tuple[Condition, WME], ...], bindings: dict[str, Symbol]) -> bool:
    for cond, wme in pairs:
        values = (wme.id, wme.attr, wme.value)
        if not all(test_holds(t, v, bindings, final=False)
                   for t, v in zip(condition_fields(cond), values, strict=True)):
            return False
    return True


class BruteForceMatcher:
    """Naive matcher: recomputes every production's matches from scratch when asked.

    Quadratic and slow by design: it is obviously correct, which makes it the oracle for
    the Rete's property tests.
    """

    def __init__(self, check_links: bool = False) -> None:
        self.check_links = check_links
        self._productions: dict[str, Production] = {}
        self._wmes: dict[WME, None] = {}
        self._current: dict[str, dict[tuple[WME | None, ...], Match]] = {}
        self._changes = Changes()
        self._dirty = False

    def add_production(self, production: Production) -> None:
        if production.name in self._productions:
            raise SoarSemanticError(production.name, "a production with this name exists",
                                    production.location)
        check_production(production, links=self.check_links)
        self._productions[production.name] = production
        self._current[production.name] = {}
        self._dirty = True

    def excise(self, name: str) -> None:
        self._refresh()
        if name not in self._productions:
            raise KeyError(f"no production named {name!r}")
        del self._productions[name]
        for match in self._current.pop(name).values():
            self._changes.retract(match)

    def add_wme(self, wme: WME) -> None:
        if wme in self._wmes:
            raise ValueError(f"{wme!r} is already in working memory")
        self._wmes[wme] = None
        self._dirty = True

    def remove_wme(self, wme: WME) -> None:
        if wme not in self._wmes:
            raise ValueError(f"{wme!r} is not in working memory")
        del self._wmes[wme]
        self._dirty = True

    def clear_wmes(self) -> None:
        """Remove every WME at once (same changes as ``remove_wme`` on each)."""
        self._wmes.clear()
        self._dirty = True

    def take_changes(self) -> tuple[list[Match], list[Match]]:
        self._refresh()
        return self._changes.take()

    def mark_removals(self) -> None:
        """No order to keep: the matches are found again all at once."""

    blocked_retractions = -1

    def matches(self, name: str) -> list[Match]:
        self._refresh()
        if name not in self._current:
            raise KeyError(f"no production named {name!r}")
        return list(self._current[name].values())

    def productions(self) -> list[Production]:
        return list(self._productions.values())

    def _refresh(self) -> None:
        if not self._dirty:
            return
        self._dirty = False
        wmes = list(self._wmes)
        for name, production in self._productions.items():
            old = self._current[name]
            new: dict[tuple[WME | None, ...], Match] = {}
            for chosen, bindings in brute_force_solutions(production.conditions, wmes, {}):
                key = tuple(chosen)
                match = old.get(key)
                if match is None:
                    match = Match(production, key, bindings)
                    self._changes.appear(match)
                new[key] = match
            for key, match in old.items():
                if key not in new:
                    self._changes.retract(match)
            self._current[name] = new
