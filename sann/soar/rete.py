"""Matching productions against working memory.

Two matchers with one interface:

- :class:`Rete` — the Doorenbos (1995) Rete: an alpha network hashed on constant attribute
  and value tests, hashed beta joins, negative and conjunctive-negation (NCC) nodes, shared
  prefixes, tree-based removal.  Adding or removing a WME costs in proportion to the alpha
  memories and tokens it touches, not to the size of working memory.  A conjunctive negation
  without a nested one is not a subnetwork of tokens but a compiled query that keeps one
  witness per blocked token (:class:`_QueryNCCNode`): Python pays per token, and the
  subnetwork's partial matches were most of the tokens in rules such as "the top disk of a
  peg".
- :class:`BruteForceMatcher` — a naive join over all WMEs, written to be obviously correct.
  It is the oracle of the property tests.

The Rete joins conditions in its own order (``_join_order``): constant tests and checks
first, then joins hashed on a bound value, then fan-out over multi-valued attributes,
following the most recently reached object; negations as soon as their variables are bound;
existence tests such as ``(<s> ^step)`` last.  ``Match.wmes`` stays in written order.

Matching follows the real Soar 9.6 kernel (checked with ``soar_sml``):

- constants and variables compare as Soar symbols: ``1``, ``1.0`` and ``|1|`` are three
  different symbols (equality requires the same Python type);
- ``< > <= >=`` between two variables use Soar's total order: identifiers (by letter, then
  number) before numbers (compared numerically, ints with floats) before strings (compared
  as strings); against a constant, values of another kind pass ``<``/``<=`` and fail
  ``>``/``>=`` (the kernel's constant tests do that: both ``abc < 5`` and ``5 < abc``);
- ``<>`` is symbol inequality, ``<=>`` "same type", ``@`` never holds and ``!@`` always holds
  (there are no long-term identifiers here).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Iterator, Sequence
from operator import attrgetter
from typing import Any

from sann.soar.codegen import define
from sann.soar.errors import SoarSemanticError
from sann.soar.memory import WME, Identifier, Symbol, mypyc_attr
from sann.soar.production import (
    Condition,
    ConditionElement,
    Conjunction,
    ConjunctiveNegation,
    Const,
    Disjunction,
    MakeAction,
    Production,
    Relational,
    Test,
    Var,
)

__all__ = [
    "BruteForceMatcher", "Match", "Rete", "check_production", "symbol_order_less",
    "kernel_refusals", "load_warnings",
]


# ---------------------------------------------------------------------------------------------
# Symbols: equality and Soar's order
# ---------------------------------------------------------------------------------------------


def same_symbol(a: object, b: object) -> bool:
    """Soar symbol equality: same type and same value (identifiers by identity)."""
    return type(a) is type(b) and a == b


def _rank(value: object) -> int:
    cls = type(value)
    if cls is Identifier:
        return 0
    if cls is int or cls is float:
        return 1
    return 2


def symbol_order_less(a: Symbol, b: Symbol) -> bool:
    """``a < b`` in the Soar 9.6 kernel's total order of symbols."""
    ra, rb = _rank(a), _rank(b)
    if ra != rb:
        return ra < rb
    if ra == 0:
        return (a.letter, a.number) < (b.letter, b.number)  # type: ignore[union-attr]
    return a < b  # type: ignore[operator]


def _less_equal(a: Symbol, b: Symbol) -> bool:
    return not symbol_order_less(b, a)


def _relation(op: str) -> Callable[[Symbol, Symbol], bool]:
    """The predicate ``value <op> operand`` as a two-argument function."""
    return _RELATIONS[op]


def _const_order(mixed: bool, holds: Callable[[Symbol, Symbol], bool]
                 ) -> Callable[[Symbol, Symbol], bool]:
    """An ordering test against a constant as the kernel runs it: numbers with numbers,
    strings with strings, and otherwise ``mixed`` whatever the values."""

    def test(value: Symbol, constant: Symbol) -> bool:
        if _rank(value) != _rank(constant):
            return mixed
        return holds(value, constant)

    return test


#: Relational tests as the 9.6 kernel's Rete runs them on the tested WME's value and the
#: other symbol (a constant, or a variable's value): numbers with numbers, strings with
#: strings; when the two are of different kinds (number, string, identifier), ``<`` and
#: ``<=`` hold and ``>`` and ``>=`` do not — so both ``abc < 5`` and ``5 < abc`` hold, as
#: soar_sml shows (for a variable too: ``-{(<y> ^p > <v>)}`` with <v> 1.5 is not blocked
#: by ^p |changed|, ``-{(<y> ^p < <v>)}`` is). The kernel's reorderer may move a test on a
#: variable bound later into that variable's condition, inverted, and run it there on that
#: WME's value: the agent hands the matcher its productions so arranged
#: (``reorder.with_kernel_relations``).
_RELATIONS: dict[str, Callable[[Symbol, Symbol], bool]] = {
    "<>": lambda a, b: not (type(a) is type(b) and a == b),
    "<": _const_order(True, symbol_order_less),
    ">": _const_order(False, lambda a, b: symbol_order_less(b, a)),
    "<=": _const_order(True, _less_equal),
    ">=": _const_order(False, lambda a, b: _less_equal(b, a)),
    "<=>": lambda a, b: type(a) is type(b),
    "@": lambda a, b: False,
    "!@": lambda a, b: True,
}


# ---------------------------------------------------------------------------------------------
# Matches
# ---------------------------------------------------------------------------------------------


@mypyc_attr(native_class=False)  # made and read by generated code
class Match:
    """One instantiation of a production.

    Compared and hashed by identity: the object reported as retracted is the same object
    that was reported when the match appeared.  ``wmes`` has one entry per top-level
    condition element in written order (``None`` for negations); ``bindings`` maps every
    variable bound by the positive conditions (name without brackets) to its value;
    ``newest`` is the timetag of the newest matched WME and the first written index it is
    at (``(0, -1)`` without any): the order of match creation in the kernel's Rete.

    Plain slots, filled when the match is made (the Rete's generated ``_Layout.match_lines``):
    most matches are fired, and CPython 3.11 reads a property through a C call into a new
    interpreter frame, several times the cost of the slot read."""

    __slots__ = ("production", "wmes", "newest", "bindings")

    def __init__(self, production: Production, wmes: tuple[WME | None, ...],
                 bindings: dict[str, Symbol]) -> None:
        self.production = production
        self.wmes = wmes
        self.bindings = bindings
        self.newest = _newest_of(wmes)

    def __repr__(self) -> str:
        return f"Match({self.production.name}, {list(self.wmes)})"


def _newest_of(wmes: tuple[WME | None, ...]) -> tuple[int, int]:
    """``Match.newest`` from the WMEs in written order."""
    newest, index = 0, -1
    for i, wme in enumerate(wmes):
        if wme is not None and wme.timetag > newest:
            newest, index = wme.timetag, i
    return newest, index


class _Changes:
    """New and retracted matches since the last ``take_changes``; an appear/retract pair
    inside one interval cancels out."""

    __slots__ = ("added", "removed", "mark", "blocked")

    def __init__(self) -> None:
        self.added: dict[Match, None] = {}
        self.removed: dict[Match, None] = {}
        # how many retractions came before the first WME removal (``mark_removals``): the
        # ones new WMEs made, by blocking a negation; ``blocked`` is it for the last take
        # (-1: no removal was marked)
        self.mark = -1
        self.blocked = -1

    def mark_removals(self) -> None:
        if self.mark < 0:
            self.mark = len(self.removed)

    def appear(self, match: Match) -> None:
        self.added[match] = None

    def retract(self, match: Match) -> None:
        if match in self.added:
            del self.added[match]
        else:
            self.removed[match] = None

    def take(self) -> tuple[list[Match], list[Match]]:
        mark, self.mark = self.mark, -1
        if not self.added and not self.removed:
            return [], []
        self.blocked = mark
        added, removed = list(self.added), list(self.removed)
        self.added.clear()
        self.removed.clear()
        return added, removed


# ---------------------------------------------------------------------------------------------
# Semantic checks (shared by both matchers)
# ---------------------------------------------------------------------------------------------


def equality_vars(test: Test) -> list[str]:
    """Variables a field test binds or equality-tests: ``<x>`` or ``{<x> ...}``."""
    if isinstance(test, Var):
        return [test.name]
    if isinstance(test, Conjunction):
        names: list[str] = []
        for inner in test.tests:
            names.extend(equality_vars(inner))
        return names
    return []


def relational_vars(test: Test) -> list[str]:
    """Variables used as operands of relational tests inside a field test."""
    if isinstance(test, Relational):
        return [test.operand.name] if isinstance(test.operand, Var) else []
    if isinstance(test, Conjunction):
        names: list[str] = []
        for inner in test.tests:
            names.extend(relational_vars(inner))
        return names
    return []


def _fields(cond: Condition) -> tuple[Test, Test, Test]:
    return cond.id_test, cond.attr_test, cond.value_test


def _bound_by(conditions: Iterable[ConditionElement]) -> set[str]:
    """Variables bound by the positive conditions among ``conditions`` (not nested)."""
    names: set[str] = set()
    for element in conditions:
        if isinstance(element, Condition) and not element.negated:
            for test in _fields(element):
                names.update(equality_vars(test))
    return names


def _validate_test(production: Production, test: Test) -> None:
    if isinstance(test, Conjunction):
        for inner in test.tests:
            _validate_test(production, inner)
    elif isinstance(test, Relational):
        if test.op not in _RELATIONS:
            raise SoarSemanticError(production.name, f"unknown relation {test.op!r}",
                                    production.location)
        if not isinstance(test.operand, (Var, Const)):
            raise SoarSemanticError(production.name, f"bad operand in test {test!r}",
                                    production.location)
    elif isinstance(test, Disjunction):
        if not all(isinstance(value, Const) for value in test.values):
            raise SoarSemanticError(production.name, "a disjunction << >> holds only constants",
                                    production.location)
    elif not isinstance(test, (Var, Const)):
        raise SoarSemanticError(production.name, f"not a test: {test!r}", production.location)


def _check_scope(
    production: Production, elements: tuple[ConditionElement, ...], outer_linked: set[str],
    outer_bound: set[str], links: bool,
) -> None:
    """Check one scope (the production, or the inside of a conjunctive negation, whose own
    positive conditions bind local variables): its conjunctive negations are not empty, its
    negated conditions' relational tests compare with bound variables, and (``links``
    only) every condition is linked to a state."""
    bound = outer_bound | _bound_by(elements)
    linked = _linked(elements, outer_linked)
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            if not element.conditions:
                raise SoarSemanticError(production.name, "empty conjunctive negation -{ }",
                                        production.location)
            _check_scope(production, element.conditions, linked, bound, links)
            continue
        _check_condition(production, element, linked, bound, links)


def _linked(elements: Iterable[ConditionElement], outer: set[str]) -> set[str]:
    """``outer`` and the identifiers the positive conditions of one scope reach from the
    states: a state or impasse condition's identifier, then the values of conditions on
    reached identifiers (the kernel's "connected to a goal": never through attributes)."""
    linked = set(outer)
    positives = [e for e in elements if isinstance(e, Condition) and not e.negated]
    for cond in positives:
        if cond.goal is not None:
            linked.update(equality_vars(cond.id_test))
    grown = True
    while grown:
        grown = False
        for cond in positives:
            if linked.intersection(equality_vars(cond.id_test)):
                new = set(equality_vars(cond.value_test))
                if not new <= linked:
                    linked |= new
                    grown = True
    return linked


def _check_condition(
    production: Production, cond: Condition, linked: set[str], bound: set[str], links: bool
) -> None:
    name = production.name
    for test in _fields(cond):
        _validate_test(production, test)
    ids = equality_vars(cond.id_test)
    if not ids:
        raise SoarSemanticError(name, f"the identifier of condition {_show(cond)} must be a "
                                "variable", production.location)
    if links and not linked.intersection(ids):
        raise SoarSemanticError(name, f"condition {_show(cond)} is not linked to a state: "
                                f"<{ids[0]}> is not reachable from a state or impasse "
                                "condition", production.location)
    _check_relations(production, cond, bound)


def _relation_text(test: Test, var: str) -> str:
    """The relational test of ``test`` that compares with ``<var>``, as written."""
    for inner in _atoms(test):
        if isinstance(inner, Relational) and inner.operand == Var(var):
            return f"{inner.op} <{var}>"
    return f"<{var}>"


def _show(cond: Condition) -> str:
    def text(test: Test) -> str:
        if isinstance(test, Var):
            return f"<{test.name}>"
        if isinstance(test, Const):
            return str(test.value)
        if isinstance(test, Relational):
            return f"{test.op} {text(test.operand)}"
        if isinstance(test, Disjunction):
            return "<< " + " ".join(text(v) for v in test.values) + " >>"
        return "{ " + " ".join(text(t) for t in test.tests) + " }"

    prefix = "-" if cond.negated else ""
    goal = f"{cond.goal} " if cond.goal else ""
    plus = " +" if cond.acceptable else ""
    return (f"{prefix}({goal}{text(cond.id_test)} ^{text(cond.attr_test)} "
            f"{text(cond.value_test)}{plus})")


def check_production(production: Production, links: bool = False) -> None:
    """Raise :class:`SoarSemanticError` naming the production when the kernel refuses it.

    Measured in soar_sml 9.6, the kernel refuses a production whose match has no root
    (see `_roots`: no ``state`` condition, and every positive condition's identifier is
    the value of another, as in ``(<s> ^a <s>)`` or only negations), and a negated condition
    with a relational test on a variable no positive condition binds (its own equality
    tests do not count: ``-(<s> ^b {<z> > <z>})`` is refused).  Everything else loads, in
    any order: a negation first, conditions no state reaches (it warns, see
    :func:`load_warnings`), identifiers reached only through an attribute variable.  It
    silently drops a relational test of a positive condition on a variable that nothing
    binds (the parser does that too, see ``syntax._drop_unbound_relations``); here such a
    test is refused, as a production built by hand that holds one does not say what it
    means.  A variable that appears only inside a negation is local to it.

    ``links=True`` adds a rule stricter than the kernel's: every condition must be linked
    to a state through positive conditions.
    """
    kernel_refusals(production)
    _check_scope(production, production.conditions, set(), set(), links)


def kernel_refusals(production: Production) -> None:
    """The refusals of :func:`check_production` that the kernel makes when it loads a
    production (the parser makes them too): no root, and a negated condition's relational
    test on a variable no positive condition binds."""
    if not _roots(production.conditions, set(), top=True)[0]:
        raise SoarSemanticError(production.name, "no positive condition tests a state and "
                                "each identifier is the value of another condition, so the "
                                "match has nowhere to start: add a condition such as (state "
                                "<s> ^superstate nil)", production.location)
    _check_negated_relations(production, production.conditions, set())


def _check_negated_relations(production: Production, elements: tuple[ConditionElement, ...],
                             outer: set[str]) -> None:
    bound = outer | _bound_by(elements)
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            _check_negated_relations(production, element.conditions, bound)
        elif element.negated:
            _check_relations(production, element, bound)


def _check_relations(production: Production, cond: Condition, bound: set[str]) -> None:
    """Every relational test of ``cond`` compares with a variable in ``bound``."""
    for test in _fields(cond):
        for var in relational_vars(test):
            if var in bound:
                continue
            if cond.negated:
                raise SoarSemanticError(production.name, "unbound referent in negated "
                                        f"relational test {_relation_text(test, var)} of "
                                        f"{_show(cond)}: a negated condition can only compare "
                                        "with a variable bound by a positive condition",
                                        production.location)
            raise SoarSemanticError(production.name, f"variable <{var}> in a relational test "
                                    f"of {_show(cond)} is never bound", production.location)


def _roots(elements: Iterable[ConditionElement], outer: set[str], top: bool
           ) -> tuple[list[str], set[str]]:
    """The kernel's root variables of one scope (reorder.cpp's ``collect_root_variables``,
    as measured in soar_sml 9.6), in written order: the identifiers of its positive
    conditions that are neither bound outside it (``outer``) nor the value of one of its
    positive conditions; at the top, when there are none, the identifier of the first
    ``state`` condition (``(state <s> ^a <s>)`` loads, ``(impasse <s> ^a <s>)`` does not).
    Also returned: the identifiers of state and impasse conditions (never warned about)."""
    positives = [e for e in elements if isinstance(e, Condition) and not e.negated]
    values = set(outer)
    for cond in positives:
        values.update(equality_vars(cond.value_test))
    roots: dict[str, None] = {}
    goals: set[str] = set()
    for cond in positives:
        for name in equality_vars(cond.id_test):
            if cond.goal is not None:
                goals.add(name)
            if name not in values:
                roots.setdefault(name, None)
    if not roots and top:
        first = next((c for c in positives if c.goal == "state"), None)
        if first is not None:
            roots = dict.fromkeys(equality_vars(first.id_test))
    return list(roots), goals


def load_warnings(production: Production) -> list[str]:
    """What the kernel warns about when it loads the production (it loads it anyway): each
    root identifier of a scope that is not a state or impasse ("identifier <x> is not
    connected to any goal or impasse"), and positive conditions that no root reaches by
    binding identifiers in any field ("the LHS conditions are not all connected")."""
    found: list[str] = []
    _scope_warnings(production.conditions, set(), found, top=True)
    return list(dict.fromkeys(found))


def _scope_warnings(elements: tuple[ConditionElement, ...], outer: set[str],
                    found: list[str], top: bool) -> None:
    roots, goals = _roots(elements, outer, top)
    found.extend(f"identifier <{name}> is not connected to any goal or impasse"
                 for name in roots if name not in goals)
    bound = outer | set(roots)
    waiting = [e for e in elements if isinstance(e, Condition) and not e.negated]
    placed = True
    while waiting and placed:
        placed = False
        for cond in list(waiting):
            if bound.intersection(equality_vars(cond.id_test)):
                waiting.remove(cond)
                bound.update(*(equality_vars(test) for test in _fields(cond)))
                placed = True
    if waiting:
        found.append("the LHS conditions are not all connected")
    inner_outer = outer | _bound_by(elements)
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            _scope_warnings(element.conditions, inner_outer, found, top=False)


# ---------------------------------------------------------------------------------------------
# The brute-force matcher (test oracle)
# ---------------------------------------------------------------------------------------------


def _test_holds(test: Test, value: Symbol, bindings: dict[str, Symbol], final: bool) -> bool:
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
            return _RELATIONS[test.op](value, operand.value)
        if operand.name not in bindings:
            return not final
        return _RELATIONS[test.op](value, bindings[operand.name])
    return all(_test_holds(t, value, bindings, final) for t in test.tests)


def _bind_field(test: Test, value: Symbol, bindings: dict[str, Symbol]) -> bool:
    """Bind or equality-test the variables of a field; False when an equality fails."""
    for name in equality_vars(test):
        if name in bindings:
            if not same_symbol(bindings[name], value):
                return False
        else:
            bindings[name] = value
    return True


def _wme_fits(cond: Condition, wme: WME, bindings: dict[str, Symbol]) -> dict[str, Symbol] | None:
    """Bindings extended by matching ``cond`` against ``wme``, or None."""
    if wme.acceptable != cond.acceptable:
        return None
    if cond.goal is not None and wme.id.level is None:
        return None
    extended = dict(bindings)
    for test, value in zip(_fields(cond), (wme.id, wme.attr, wme.value), strict=True):
        if not _bind_field(test, value, extended):
            return None
    for test, value in zip(_fields(cond), (wme.id, wme.attr, wme.value), strict=True):
        if not _test_holds(test, value, extended, final=False):
            return None
    return extended


def _final_tests_hold(cond: Condition, wme: WME, bindings: dict[str, Symbol]) -> bool:
    return all(
        _test_holds(test, value, bindings, final=True)
        for test, value in zip(_fields(cond), (wme.id, wme.attr, wme.value), strict=True)
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
            extended = _wme_fits(cond, wme, current)
            if extended is not None:
                chosen[index] = wme
                yield from extend(k + 1, extended)
        chosen[index] = None

    for full in extend(0, dict(bindings)):
        if not all(_final_tests_hold(cond, chosen[i], full) for i, cond in positives):
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
            extended = _wme_fits(cond, wme, bindings)
            if extended is not None and _still_hold(pairs, extended):
                out.append((extended, (*pairs, (cond, wme))))
                if first:
                    return out
    return out


def _still_hold(pairs: tuple[tuple[Condition, WME], ...], bindings: dict[str, Symbol]) -> bool:
    for cond, wme in pairs:
        values = (wme.id, wme.attr, wme.value)
        if not all(_test_holds(t, v, bindings, final=False)
                   for t, v in zip(_fields(cond), values, strict=True)):
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
        self._changes = _Changes()
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


# ---------------------------------------------------------------------------------------------
# The Rete (Doorenbos 1995)
# ---------------------------------------------------------------------------------------------
#
# Tokens carry a flat tuple ``vals`` of the variable values bound so far (one slot per binding
# join), so that a join test or a hash key is one tuple index.  Every beta node keeps its own
# output memory (``tokens``) and, on demand, hash indices of it on the value positions its
# children join on; alpha memories keep hash indices on the WME fields their join nodes test.
# Removal is tree-based: each WME knows its alpha memories, the tokens built on it and the
# negative-node tokens it blocks; each token knows its children.

_FLOAT = object()  # hash keys of floats are (_FLOAT, x): 1.0 must never meet 1 in a join
_ANY = object()  # alpha index: no constant test on this field
_IDENT = object()  # alpha cache: any identifier
_UNTESTED = object()  # alpha cache: any value no alpha memory tests for
_FIELDS = ("id", "attr", "value")
_GET = {name: attrgetter(name) for name in _FIELDS}
_INDEX_PREFERENCE = {"id": 0, "value": 1, "attr": 2}
_ALPHA_CACHE_LIMIT = 100_000

Ref = tuple[str, object]  # ("v", position in vals) or ("w", field of the current WME)
BetaSpec = tuple[Ref, str, Ref]


def _hkey(value: object) -> object:
    return (_FLOAT, value) if type(value) is float else value


def _typed(value: object) -> tuple[str, object]:
    """A constant inside a sharing key: 1, 1.0 and "1" must give different keys."""
    return (value.__class__.__name__, value)


def _index_add(index: dict, value: object, item: object) -> None:
    """File ``item`` under ``value`` (hashed as ``_hkey`` does, inline: this is hot)."""
    key = (_FLOAT, value) if type(value) is float else value
    bucket = index.get(key)
    if bucket is None:
        index[key] = {item: None}
    else:
        bucket[item] = None


def _index_remove(index: dict, value: object, item: object) -> None:
    key = (_FLOAT, value) if type(value) is float else value
    bucket = index[key]
    del bucket[item]
    if not bucket:
        del index[key]


@mypyc_attr(native_class=False)  # made and read by generated code
class _Token:
    """A partial match: ``parent`` token, ``wme`` (or the tuple of a run node's WMEs),
    ``vals`` the tuple of variable values bound so far, ``node`` the beta node that owns it
    (``None`` once deleted), ``children`` a dict of child tokens or None, and ``extra``
    depends on the node: the blocking WMEs of a negative-node token, the results of an NCC
    owner, the owner of an NCC partner result, the witness of a query-NCC token, the Match
    of a production-node token.  Hashed by identity.

    Slots, not a list: CPython 3.11 specializes slot reads and writes, not the subscripts of
    a list subclass (three times slower), and the hot paths read tokens all the time.  No
    ``__init__``: tokens are made by calling the bare class and storing the six slots
    (inline in generated code, ``_token_lines``), cheaper than passing them to ``__init__``
    and than ``object.__new__(_Token)``."""

    __slots__ = ("parent", "wme", "vals", "node", "children", "extra")
    parent: Any
    wme: Any
    vals: Any
    node: Any
    children: Any
    extra: Any


_new = object.__new__


def _new_token(parent: _Token | None, wme: object, vals: tuple, node: _Node,
               extra: object = None) -> _Token:
    tok = _Token()
    tok.parent, tok.wme, tok.vals, tok.node = parent, wme, vals, node
    tok.children = None
    tok.extra = extra
    return tok


def _token_lines(pad: str, parent: str, wme: str, vals: str) -> list[str]:
    """Generated code: ``tok`` = a new token of node ``N`` (``Tok`` in the namespace), what
    ``_new_token`` does, inline."""
    return [f"{pad}tok = Tok(); tok.parent = {parent}; tok.wme = {wme}; tok.vals = {vals}",
            f"{pad}tok.node = N; tok.children = tok.extra = None"]


def _adopt(parent: _Token, tok: _Token) -> None:
    children = parent.children
    if children is None:
        parent.children = {tok: None}
    else:
        children[tok] = None


class _CompileFirst:
    """Stands in for a node's generated function until the node generates its code: the
    first call runs the node's ``_compile`` (which replaces every stand-in) and then the
    function it made. Nodes reset their functions to stand-ins when what the code was
    generated from changes."""

    __slots__ = ("node", "name")

    def __init__(self, node: object, name: str) -> None:
        self.node = node
        self.name = name

    def __call__(self, *args: object) -> None:
        self.node._compile()  # type: ignore[attr-defined]
        getattr(self.node, self.name)(*args)


def _compile_first(node: object, *names: str) -> None:
    """Set the node's generated functions ``names`` to stand-ins (``_CompileFirst``)."""
    for name in names:
        setattr(node, name, _CompileFirst(node, name))


class _AlphaMemory:
    """The WMEs that pass one condition's constant tests, with hash indices on the fields
    the join nodes below test."""

    __slots__ = ("key", "lookup", "accept", "wmes", "indexes", "successors", "activations",
                 "listeners", "on_add", "on_remove")

    def __init__(self, key: tuple, lookup: tuple, accept: Callable[[WME], bool] | None) -> None:
        self.key = key
        self.lookup = lookup
        self.accept = accept
        self.wmes: dict[WME, None] = {}
        self.indexes: dict[str, dict] = {}  # field -> hash index on it
        self.successors: list[_Node] = []
        # (right_activate, parent memory) per successor: a node whose parent memory is empty
        # has nothing to join with, so add_wme skips the call (Doorenbos's right unlinking,
        # as a test instead of a relink).
        self.activations: list[tuple[Callable[[WME], None], dict]] = []
        # (query NCC node, inner condition number): told of every WME added and, for an
        # inner negated condition, removed
        self.listeners: list[tuple[_QueryNCCNode, int]] = []
        # What a WME entering (leaving) the memory does, generated from the above; compiled
        # on first use after any of them changes.
        self.on_add: Callable[[WME], None]
        self.on_remove: Callable[[WME], None]
        _compile_first(self, "on_add", "on_remove")

    def link(self, node: _Node) -> None:
        """Add a successor in front: nodes are built top-down, and a descendant must be
        right-activated before its ancestor or a WME joining both makes a token twice."""
        self.successors.insert(0, node)
        self._relink()

    def unlink(self, node: _Node) -> None:
        self.successors.remove(node)
        self._relink()

    def listen(self, node: _QueryNCCNode, k: int) -> None:
        self.listeners.append((node, k))
        self._stale()

    def unlisten(self, node: _QueryNCCNode, k: int) -> None:
        self.listeners.remove((node, k))
        self._stale()

    def _relink(self) -> None:
        self.activations = [(node.activation(self), node.parent.tokens)  # type: ignore[union-attr]
                            for node in self.successors]
        self._stale()

    def _stale(self) -> None:
        _compile_first(self, "on_add", "on_remove")

    def _compile(self) -> None:
        """Generate ``on_add`` and ``on_remove`` as straight-line code: store the WME in the
        memory and its indices, then right-activate each successor whose parent memory is
        not empty and tell the listening query nodes that have owners.  Every WME added to
        working memory passes here once per alpha memory it enters, and the generated code
        costs half the interpreted loops over indices, successors and listeners."""
        namespace: dict[str, object] = {"FLOAT": _FLOAT, "W": self.wmes}
        add = ["def on_add(wme):", "    W[wme] = None"]
        remove = ["def on_remove(wme):", "    del W[wme]"]
        for k, (field, index) in enumerate(self.indexes.items()):
            namespace[f"I{k}"] = index
            add += _filing_lines(f"I{k}", f"wme.{field}", "wme", "    ", field != "id")
            remove += _key_lines(f"wme.{field}", "    ", field != "id") + [
                f"    b = I{k}[key]", "    del b[wme]", f"    if not b: del I{k}[key]"]
        for k, (activate, parent_tokens) in enumerate(self.activations):
            namespace[f"P{k}"], namespace[f"R{k}"] = parent_tokens, activate
            add.append(f"    if P{k}: R{k}(wme)")
        for k, (node, level) in enumerate(self.listeners):
            # the node's inner_added, read at each call: it is regenerated with the node
            namespace[f"O{k}"], namespace[f"L{k}"] = node.owners, node
            add.append(f"    if O{k}: L{k}.inner_added({level}, wme)")
        self.on_add = define(add, namespace, "on_add")  # type: ignore[method-assign]
        self.on_remove = define(remove, dict(namespace), "on_remove")  # type: ignore[method-assign]

    def index(self, field: str) -> dict:
        index = self.indexes.get(field)
        if index is None:
            index = {}
            getter = _GET[field]
            for wme in self.wmes:
                _index_add(index, getter(wme), wme)
            self.indexes[field] = index
            self._stale()
        return index

    def add(self, wme: WME) -> None:
        """Store a WME without activating anything (a new memory taking in working memory)."""
        self.wmes[wme] = None
        for field, index in self.indexes.items():
            _index_add(index, _GET[field](wme), wme)


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class _Node:
    """A beta node with its memory of (active) output tokens and hash indices on it."""

    __slots__ = ("rete", "parent", "key", "children", "child_map", "tokens", "indexes",
                 "index_list")

    def __init__(self, rete: Rete, parent: _Node | None, key: object = None) -> None:
        self.rete = rete
        self.parent = parent
        self.key = key
        self.children: list[_Node] = []
        self.child_map: dict[object, _Node] = {}
        self.tokens: dict[_Token, None] = {}
        self.indexes: dict[int, dict] = {}
        self.index_list: list[tuple[int, dict]] = []

    def index(self, pos: int) -> dict:
        index = self.indexes.get(pos)
        if index is None:
            index = {}
            for tok in self.tokens:
                _index_add(index, tok.vals[pos], tok)
            self.indexes[pos] = index
            self.index_list.append((pos, index))
        return index

    def store(self, tok: _Token) -> None:
        """Add an active output token and pass it to the children."""
        self.tokens[tok] = None
        if self.index_list:
            vals = tok.vals
            for pos, index in self.index_list:
                key = vals[pos]
                if type(key) is float:
                    key = (_FLOAT, key)
                bucket = index.get(key)
                if bucket is None:
                    index[key] = {tok: None}
                else:
                    bucket[tok] = None
        for child in self.children:
            child.left_activate(tok)

    def forget(self, tok: _Token) -> None:
        """Drop an active output token from the memory and its indices."""
        del self.tokens[tok]
        if self.index_list:
            vals = tok.vals
            for pos, index in self.index_list:
                key = vals[pos]
                if type(key) is float:
                    key = (_FLOAT, key)
                bucket = index[key]
                del bucket[tok]
                if not bucket:
                    del index[key]

    def unstore(self, tok: _Token) -> None:
        """`_Node.forget` whatever the subclass's ``forget`` (not ``unstore = forget``: mypyc
        fails on that in a non-native class)."""
        _Node.forget(self, tok)

    def all_tokens(self) -> list[_Token]:
        return list(self.tokens)

    def activation(self, amem: _AlphaMemory) -> Callable[[WME], None]:
        """What a WME entering ``amem`` calls (a join or negative node: right_activate)."""
        return self.right_activate  # type: ignore[attr-defined]

    def left_activate(self, tok: _Token) -> None:  # the root has no parent
        raise AssertionError("the root node is never activated")


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class _JoinNode(_Node):
    """Joins parent tokens with the WMEs of an alpha memory, hashed on one equality test.

    This is the innermost loop of the matcher, so both activations are generated for the
    node as straight-line code (its test, what a new token binds and the indices on its
    tokens are fixed when it is compiled).  They are compiled on first use, and again after
    an index is added to the node's memory; the alpha memory then picks up the new
    ``right_activate``."""

    __slots__ = ("amem", "pos", "field", "check", "extend", "registry", "left_activate",
                 "right_activate")

    def __init__(self, rete: Rete, parent: _Node, key: object, amem: _AlphaMemory,
                 index: tuple[int, str] | None, check: Callable | None,
                 extend: Callable | None) -> None:
        super().__init__(rete, parent, key)
        self.amem = amem
        self.check = check
        self.extend = extend
        self.registry = rete._wme_info
        self.pos, self.field = (-1, "") if index is None else index
        if index is not None:  # the hashes both activations look up
            amem.index(self.field)
            parent.index(self.pos)
        self.left_activate: Callable[[_Token], None]
        self.right_activate: Callable[[WME], None]
        _compile_first(self, "left_activate", "right_activate")

    def index(self, pos: int) -> dict:
        known = pos in self.indexes
        index = super().index(pos)
        if not known:  # the generated code updates the indices it knew of
            _compile_first(self, "left_activate", "right_activate")
            self.amem._relink()  # it holds the right activation
        return index

    def _compile(self) -> None:
        hashed = self.pos >= 0
        namespace: dict[str, object] = {
            **_CHECK_NAMES, "FLOAT": _FLOAT, "Tok": _Token, "N": self,
            "E": self.extend, "R": self.registry, "T": self.tokens, "CH": self.children,
            "AB": self.amem.indexes[self.field] if hashed else self.amem.wmes,
            "PB": self.parent.indexes[self.pos] if hashed else self.parent.tokens,  # type: ignore[union-attr]
        }
        grow = ("vals" if self.extend is None else "vals + (wme.value,)"
                if self.extend is _EXTEND_VALUE else "E(vals, wme)")

        left = ["def left_activate(t):", "    vals = t.vals"]
        if hashed:
            left += [f"    key = vals[{self.pos}]",
                     "    if key.__class__ is float: key = (FLOAT, key)",
                     "    bucket = AB.get(key)", "    if bucket is None: return"]
        left += [f"    for wme in {'bucket' if hashed else 'AB'}:"] + _join_body(
            self, namespace, grow, "R[wme][1][tok] = None")
        right = ["def right_activate(wme):"]
        if hashed:
            right.append(f"    key = wme.{self.field}")
            if self.field != "id":  # identifiers are never floats
                right.append("    if key.__class__ is float: key = (FLOAT, key)")
            right += ["    bucket = PB.get(key)", "    if bucket is None: return"]
        right += ["    built = R[wme][1]", f"    for t in {'bucket' if hashed else 'PB'}:",
                  "        vals = t.vals"] + _join_body(self, namespace, grow, "built[tok] = None")
        self.left_activate = define(left, namespace, "left_activate")
        self.right_activate = define(right, namespace, "right_activate")
        self.amem._relink()  # the alpha memory calls the compiled right_activate from now on


def _join_body(node: _JoinNode, namespace: dict[str, object], grow: str,
               register: str) -> list[str]:
    """Test the pair, make the token, register, index and pass it on (a function of its
    own, not nested in ``_JoinNode._compile``: mypyc fails on a closure there)."""
    lines = [] if node.check is None else _check_lines(
        node.check.specs, "vals", "wme", "continue", "")  # type: ignore[attr-defined]
    lines += [f"new = {grow}", *_token_lines("", "t", "wme", "new"), "s = t.children",
              "if s is None: t.children = {tok: None}", "else: s[tok] = None", register,
              "T[tok] = None"]
    for k, (pos, index) in enumerate(node.index_list):
        namespace[f"I{k}"] = index
        lines += _filing_lines(f"I{k}", f"new[{pos}]", "tok", "", True)
    lines += ["for child in CH:", "    child.left_activate(tok)"]
    return ["        " + line for line in lines]


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class _NegativeNode(_Node):
    """Passes a parent token on while no WME of its alpha memory joins with it."""

    __slots__ = ("amem", "pos", "getter", "amem_index", "check", "every", "every_index")

    def __init__(self, rete: Rete, parent: _Node, key: object, amem: _AlphaMemory,
                 index: tuple[int, str] | None, check: Callable | None) -> None:
        super().__init__(rete, parent, key)
        self.amem = amem
        self.check = check
        self.every: dict[_Token, None] = {}  # blocked and active tokens
        self.every_index: dict = {}
        if index is None:
            self.pos = -1
            self.getter = None
            self.amem_index = None
        else:
            self.pos, field = index
            self.getter = _GET[field]
            self.amem_index = amem.index(field)

    def all_tokens(self) -> list[_Token]:
        return list(self.every)

    def left_activate(self, t: _Token) -> None:
        vals = t.vals
        tok = _new_token(t, None, vals, self)
        _adopt(t, tok)
        self.every[tok] = None
        if self.pos >= 0:
            value = vals[self.pos]
            _index_add(self.every_index, value, tok)
            bucket = self.amem_index.get((_FLOAT, value) if type(value) is float else value)
        else:
            bucket = self.amem.wmes
        blockers: dict[WME, None] | None = None
        if bucket:
            check = self.check
            for wme in bucket:
                if check is None or check(vals, wme):
                    if blockers is None:
                        blockers = {}
                    blockers[wme] = None
        if blockers is None:
            self.store(tok)
            return
        tok.extra = blockers
        info = self.rete._wme_info
        for wme in blockers:
            _block(info[wme], tok)

    def right_activate(self, wme: WME) -> None:
        if self.pos >= 0:
            bucket = self.every_index.get(_hkey(self.getter(wme)))
            if bucket is None:
                return
        else:
            bucket = self.every
        check = self.check
        info = self.rete._wme_info[wme]
        for tok in bucket:
            if check is None or check(tok.vals, wme):
                blockers = tok.extra
                if blockers is None:
                    tok.extra = {wme: None}
                    self.unstore(tok)
                    self.rete._delete_children(tok)
                else:
                    blockers[wme] = None
                _block(info, tok)

    def unblock(self, tok: _Token) -> None:
        tok.extra = None
        self.store(tok)

    def forget(self, tok: _Token) -> None:
        del self.every[tok]
        if self.pos >= 0:
            _index_remove(self.every_index, tok.vals[self.pos], tok)
        if tok.extra is None:
            self.unstore(tok)
            return
        info = self.rete._wme_info
        for wme in tok.extra:
            record = info.get(wme)
            if record is not None and record[2]:
                record[2].pop(tok, None)


def _key_lines(value: str, pad: str, floats: bool) -> list[str]:
    """Generated code: ``key`` = the hash key of ``value`` (see ``_hkey``); an identifier
    field (``floats`` false) is never a float."""
    lines = [f"{pad}key = {value}"]
    if floats:
        lines.append(f"{pad}if key.__class__ is float: key = (FLOAT, key)")
    return lines


def _filing_lines(index: str, value: str, item: str, pad: str, floats: bool) -> list[str]:
    """Generated code: file ``item`` under ``value`` in the hash index ``index`` (what
    ``_index_add`` does, inline)."""
    return _key_lines(value, pad, floats) + [
        f"{pad}b = {index}.get(key)", f"{pad}if b is None: {index}[key] = {{{item}: None}}",
        f"{pad}else: b[{item}] = None"]


def _unlink_tokens(root: _Token) -> None:
    """Cut the links from every token below ``root`` to its children and to what its node
    keeps in ``extra`` (results, owners, matches), leaving only child-to-parent links: the
    dropped tokens then hold no cycle, and reference counting frees them at once instead of
    the cyclic garbage collector later."""
    stack = [root]
    while stack:
        tok = stack.pop()
        children = tok.children
        if children:
            stack.extend(children)
        tok.children = tok.extra = None


def _block(record: list, tok: _Token) -> None:
    blocked = record[2]
    if blocked is None:
        record[2] = {tok: None}
    else:
        blocked[tok] = None


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class _NCCNode(_Node):
    """Conjunctive negation: passes a parent token on while its subnetwork has no result
    for it.  Results arrive through the partner node at the bottom of the subnetwork."""

    __slots__ = ("partner", "owners")

    def __init__(self, rete: Rete, parent: _Node, key: object) -> None:
        super().__init__(rete, parent, key)
        self.partner: _PartnerNode | None = None
        self.owners: dict[_Token, _Token] = {}  # parent token -> this node's token

    def all_tokens(self) -> list[_Token]:
        return list(self.owners.values())

    def left_activate(self, t: _Token) -> None:
        tok = _new_token(t, None, t.vals, self)
        _adopt(t, tok)
        self.owners[t] = tok
        results = self.partner.buffer.pop(t, None)  # type: ignore[union-attr]
        if results:
            tok.extra = results
            for result in results:
                result.extra = tok
        else:
            self.store(tok)

    def block(self, owner: _Token, result: _Token) -> None:
        results = owner.extra
        if results is None:
            owner.extra = {result: None}
            self.unstore(owner)
            self.rete._delete_children(owner)
        else:
            results[result] = None

    def release(self, owner: _Token, result: _Token) -> None:
        results = owner.extra
        del results[result]
        # An owner whose parent is being deleted stays blocked (and unstored) until its turn.
        if not results and owner.parent.node is not None:
            owner.extra = None
            self.store(owner)

    def forget(self, tok: _Token) -> None:
        del self.owners[tok.parent]
        if tok.extra is None:
            self.unstore(tok)
            return
        for result in tok.extra:
            result.extra = None


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class _PartnerNode(_Node):
    """Bottom of an NCC subnetwork: each token reaching it is a result for the NCC token
    ``levels`` levels up."""

    __slots__ = ("ncc", "levels", "buffer")

    def __init__(self, rete: Rete, parent: _Node, ncc: _NCCNode, levels: int) -> None:
        super().__init__(rete, parent, ("partner", id(ncc)))
        self.ncc = ncc
        self.levels = levels
        self.buffer: dict[_Token, dict[_Token, None]] = {}

    def _owner_key(self, bottom: _Token) -> _Token:
        t = bottom
        for _ in range(self.levels):
            t = t.parent
        return t

    def left_activate(self, bottom: _Token) -> None:
        result = _new_token(bottom, None, (), self)
        _adopt(bottom, result)
        self.tokens[result] = None
        t = self._owner_key(bottom)
        owner = self.ncc.owners.get(t)
        if owner is None:  # the NCC node sees this parent token right after us
            waiting = self.buffer.get(t)
            if waiting is None:
                self.buffer[t] = {result: None}
            else:
                waiting[result] = None
            return
        result.extra = owner
        self.ncc.block(owner, result)

    def forget(self, result: _Token) -> None:
        del self.tokens[result]
        owner = result.extra
        if owner is None:
            waiting = self.buffer.get(self._owner_key(result.parent))
            if waiting is not None:
                waiting.pop(result, None)
        elif owner.node is not None:
            self.ncc.release(owner, result)


def _bucket_lines(k: int, pad: str, key: str | None, seeded: bool) -> list[str]:
    """Generated code: ``b<k>`` = the WMEs of condition ``k`` hashed on the value ``key``
    (an expression; its alpha memory ``W<k>`` when None), or just the seed WME when it
    fits."""
    if seeded:  # same_symbol(key, the seed's field), inline
        test = (f"(x := {key}).__class__ is (y := G{k}(seed)).__class__ and x == y"
                if key is not None else "True")
        return [f"{pad}b{k} = (seed,) if {test} else ()"]
    if key is None:
        return [f"{pad}b{k} = W{k}"]
    return [f"{pad}key = {key}", f"{pad}if key.__class__ is float: key = (FLOAT, key)",
            f"{pad}b{k} = I{k}.get(key, ())"]


def _compile_query(levels: list[tuple], seed: int,
                   width: int) -> Callable[[tuple, WME | None], tuple | None]:
    """A search for one match of a query NCC's inner conditions as nested loops, one per
    condition (a negated one as ``for ... break / else``), with condition ``seed`` (if
    any) matching only the WME passed in: the search runs for every parent token that
    could change, and generated loops cost a third of an interpreted walk over the levels.
    The owner's ``width`` values are read from ``v0``; what the inner conditions bind is
    kept in locals, and the values tuple is built only for the match returned."""
    namespace: dict[str, object] = {**_CHECK_NAMES, "FLOAT": _FLOAT}
    lines = ["def solve(v0, seed):"]
    depth = 1
    matched: list[str] = []
    names: dict[int, str] = {}  # value position bound inside -> local name

    def value(pos: int) -> str:
        return names.get(pos, f"v0[{pos}]")

    for k, (wmes, index, pos, getter, check, fields, negated, _) in enumerate(levels):
        pad = "    " * depth
        namespace.update({f"W{k}": wmes, f"I{k}": index, f"G{k}": getter})
        lines += _bucket_lines(k, pad, value(pos) if pos >= 0 else None, k == seed)
        lines.append(f"{pad}for w{k} in b{k}:")
        inner = pad + "    "
        if check is not None:
            lines += _check_lines(check.specs, "v0", f"w{k}", "continue", inner, value)
        if negated:  # the levels below are the body of the else: no WME matched
            lines += [f"{inner}break", f"{pad}else:"]
        else:
            for field in fields:
                name = names[width + len(names)] = f"x{width + len(names)}"
                lines.append(f"{inner}{name} = w{k}.{field}")
            matched.append(f"w{k}")
        depth += 1
    pad = "    " * depth
    bound = "".join(f"{names[p]}, " for p in sorted(names))
    lines.append(f"{pad}return {f'v0 + ({bound})' if bound else 'v0'},"
                 f" ({''.join(w + ', ' for w in matched)})")
    lines.append("    return None")
    return define(lines, namespace, "solve")


#: The query NCC node's generated functions (see _QueryNCCNode._compile).
_QUERY_GENERATED = ("left_activate", "forget", "recheck", "inner_added")


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class _QueryNCCNode(_Node):
    """Conjunctive negation answered by a query over the alpha memories instead of a
    subnetwork of tokens.

    A subnetwork keeps, under every parent token, a token for every partial match of the
    negated conditions; when a WME those partial matches join on changes (a disk moving in
    the Towers of Hanoi) they are all deleted and rebuilt, and in Python a token costs a few
    microseconds.  This node keeps, per blocked parent token, one *witness*: the WMEs and
    bindings of one match of the inner conditions (``tok.extra = (vals, wmes)``).  The query
    runs again for a token only when a WME of its witness goes, or a WME arrives that an
    inner negated condition rejects the witness with.  A WME entering the memory of an
    inner positive condition is tried as a seed against the unblocked tokens it could join
    (hashed on the parent variable the condition is joined on, when there is one); a WME
    leaving an inner negated condition's memory sends the unblocked tokens that could join
    it back to the query.  Conjunctive negations with a nested one keep the subnetwork."""

    __slots__ = ("levels", "width", "owners", "owner_index", "amems", "owner_tests",
                 "seed_filters", "solvers", "left_activate", "forget", "recheck",
                 "inner_added")

    def __init__(self, rete: Rete, parent: _Node, key: object, levels: list[tuple],
                 width: int, amems: list[_AlphaMemory],
                 owner_tests: list[list[tuple[Callable, int]]]) -> None:
        super().__init__(rete, parent, key)
        self.amems = amems
        # per inner condition, in join order:
        # (amem.wmes, hash index or None, vals position or -1, getter, check, fields bound,
        #  negated, equality tests as (field, vals position))
        self.levels = levels
        self.width = width  # the parent tokens' number of values
        # per inner condition: its equality tests against parent values, (getter, position)
        self.owner_tests = owner_tests
        # per inner condition: (getter, hashed alpha memory) pairs that a WME entering it
        # must find itself in to be part of any inner match (see _seed_filters)
        self.seed_filters = _seed_filters(levels, width, amems, owner_tests)
        # solvers[0](vals, None): one match of the inner conditions as (vals, wmes), or
        # None; solvers[k + 1](vals, wme): one in which inner condition k matches wme
        self.solvers = [_compile_query(levels, seed, width)  # negated levels are never seeds
                        if seed < 0 or not levels[seed][6] else None
                        for seed in range(-1, len(levels))]
        self.owners: dict[_Token, _Token] = {}  # parent token -> this node's token
        self.owner_index: dict[int, dict] = {}  # parent value position -> hashed owners
        for tests in owner_tests:
            if tests:
                self.owner_index.setdefault(tests[0][1], {})
        # generated on first use, and again after an index is added to the node's tokens
        self.left_activate: Callable[[_Token], None]
        self.forget: Callable[[_Token], None]
        # recheck(tok): the witness of a blocked token is gone: find another, or pass the
        # token on
        self.recheck: Callable[[_Token], None]
        # inner_added(k, wme): wme entered the memory of inner condition k (see _compile)
        self.inner_added: Callable[[int, WME], None]
        _compile_first(self, *_QUERY_GENERATED)

    def all_tokens(self) -> list[_Token]:
        return list(self.owners.values())

    def index(self, pos: int) -> dict:
        if pos not in self.indexes:
            _compile_first(self, *_QUERY_GENERATED)
        return super().index(pos)

    # ----- parent tokens -----

    def _compile(self) -> None:
        """Generate ``left_activate`` (a parent token arrives: make its token, file it
        among the owners, search once, then pass it on or keep the witness), ``forget``
        (its undoing), ``recheck`` (the witness of a blocked token is gone: drop it,
        search again, then pass the token on or keep the new witness) and ``inner_added``
        (see ``_inner_added_lines``) as straight-line code, with the node's indices fixed
        in it.  Generated, not compiled: they read and write token slots, which compiled
        code reaches through the generic attribute lookup."""
        namespace: dict[str, object] = {
            "FLOAT": _FLOAT, "Tok": _Token, "N": self, "OWN": self.owners,
            "T": self.tokens, "CH": self.children, "R": self.rete._wme_info,
            "SOLVE": self.solvers[0]}
        left = ["def left_activate(t):", "    vals = t.vals",
                *_token_lines("    ", "t", "None", "vals"), "    s = t.children",
                "    if s is None: t.children = {tok: None}", "    else: s[tok] = None",
                "    OWN[t] = tok"]
        forget = ["def forget(tok):", "    del OWN[tok.parent]", "    vals = tok.vals"]
        for k, (pos, index) in enumerate(self.owner_index.items()):
            namespace[f"O{k}"] = index
            left += _filing_lines(f"O{k}", f"vals[{pos}]", "tok", "    ", True)
            forget += _key_lines(f"vals[{pos}]", "    ", True) + [
                f"    b = O{k}[key]", "    del b[tok]", f"    if not b: del O{k}[key]"]
        left += ["    found = SOLVE(vals, None)", "    if found is None:", "        T[tok] = None"]
        recheck = ["def recheck(tok):", "    for w in tok.extra[1]:", "        record = R.get(w)",
                   "        if record is not None and record[3]: record[3].pop(tok, None)",
                   "    tok.extra = None", "    vals = tok.vals", "    found = SOLVE(vals, None)",
                   "    if found is None:", "        T[tok] = None"]
        forget += ["    found = tok.extra", "    if found is None:", "        del T[tok]"]
        for k, (pos, index) in enumerate(self.index_list):
            namespace[f"I{k}"] = index
            left += _filing_lines(f"I{k}", f"vals[{pos}]", "tok", "        ", True)
            recheck += _filing_lines(f"I{k}", f"vals[{pos}]", "tok", "        ", True)
            forget += _key_lines(f"vals[{pos}]", "        ", True) + [
                f"        b = I{k}[key]", "        del b[tok]", f"        if not b: del I{k}[key]"]
        witness = _witness_lines("    ")
        left += ["        for child in CH:", "            child.left_activate(tok)",
                 "        return", *witness]
        recheck += ["        for child in CH:", "            child.left_activate(tok)",
                    "        return", *witness]
        forget += ["        return", "    for w in found[1]:", "        record = R.get(w)",
                   "        if record is not None and record[3]: record[3].pop(tok, None)",
                   "    tok.extra = None"]
        self.left_activate = define(left, namespace, "left_activate")  # type: ignore[method-assign]
        self.forget = define(forget, dict(namespace), "forget")  # type: ignore[method-assign]
        self.recheck = define(recheck, dict(namespace), "recheck")  # type: ignore[method-assign]
        namespace = {**_CHECK_NAMES, "FLOAT": _FLOAT, "N": self, "OWN": self.owners,
                     "T": self.tokens, "R": self.rete._wme_info, "SAME": same_symbol,
                     "DT": self.rete._delete_tokens}
        self.inner_added = define(  # type: ignore[method-assign]
            self._inner_added_lines(namespace), namespace, "inner_added")

    def _inner_added_lines(self, namespace: dict[str, object]) -> list[str]:
        """Generated ``inner_added(k, wme)``: ``wme`` entered the memory of inner condition
        k.  Negated: the witnesses it rejects (of the tokens whose values it could join)
        are no longer results, and their tokens are searched again.  Positive: unless a
        seed filter rules it out, each unblocked token it could join is searched with it
        as inner condition k; a match blocks the token (dropped from the memory, its
        descendants deleted, the match kept as its witness)."""
        lines = ["def inner_added(k, wme):"]
        fields = {getter: field for field, getter in _GET.items()}
        for k, level in enumerate(self.levels):
            lines.append(f"    if k == {k}:")
            pad = "        "
            if not level[6]:
                for n, (getter, index) in enumerate(self.seed_filters[k]):
                    field = fields[getter]
                    namespace[f"F{k}_{n}"] = index
                    lines += _key_lines(f"wme.{field}", pad, field != "id")
                    lines.append(f"{pad}if key not in F{k}_{n}: return")
            tests = [(field, p) for field, p in level[7] if p < self.width]
            if not tests:
                lines.append(f"{pad}candidates = list(OWN.values())")
            else:
                field, p = tests[0]
                namespace[f"Q{p}"] = self.owner_index[p]
                lines += _key_lines(f"wme.{field}", pad, field != "id")
                lines += [f"{pad}found = Q{p}.get(key)", f"{pad}if not found: return"]
                if len(tests) == 1:
                    lines.append(f"{pad}candidates = list(found)")
                else:
                    rest = tests[1:]
                    lines += [f"{pad}v{n} = wme.{field}" for n, (field, _) in enumerate(rest)]
                    same = " and ".join(f"SAME(tok.vals[{p}], v{n})"
                                        for n, (_, p) in enumerate(rest))
                    lines.append(f"{pad}candidates = [tok for tok in found if {same}]")
            lines.append(f"{pad}for tok in candidates:")
            if level[6]:
                pos, check = level[2], level[4]
                lines += [f"{pad}    found = tok.extra",
                          f"{pad}    if found is None or tok.node is None: continue",
                          f"{pad}    vals = found[0]"]
                if pos >= 0:
                    lines += [f"{pad}    x = vals[{pos}]; y = wme.{level[7][0][0]}",
                              f"{pad}    if not (x.__class__ is y.__class__ and x == y): "
                              "continue"]
                if check is not None:
                    lines += _check_lines(check.specs, "vals", "wme", "continue", pad + "    ")
                lines += [f"{pad}    N.recheck(tok)", f"{pad}return"]
                continue
            namespace[f"S{k}"] = self.solvers[k + 1]
            inner = pad + "        "
            lines += [f"{pad}    if tok.extra is None and tok.node is not None:",
                      f"{pad}        found = S{k}(tok.vals, wme)",
                      f"{pad}        if found is not None:",  # block it (see _block)
                      f"{inner}    del T[tok]"]
            for n, (pos, index) in enumerate(self.index_list):
                namespace[f"I{n}"] = index
                lines += _key_lines(f"tok.vals[{pos}]", inner + "    ", True) + [
                    f"{inner}    b = I{n}[key]", f"{inner}    del b[tok]",
                    f"{inner}    if not b: del I{n}[key]"]
            lines += [f"{inner}    s = tok.children", f"{inner}    if s:",
                      f"{inner}        tok.children = None", f"{inner}        DT(list(s))",
                      *_witness_lines(inner + "    ")]
            lines.append(f"{pad}return")
        return lines

    def _witness(self, tok: _Token, found: tuple[tuple, tuple]) -> None:
        tok.extra = found
        info = self.rete._wme_info
        for w in found[1]:
            record = info[w]
            if record[3] is None:
                record[3] = {tok: None}
            else:
                record[3][tok] = None

    def _block(self, tok: _Token, found: tuple[tuple, tuple]) -> None:
        self.unstore(tok)
        self.rete._delete_children(tok)
        self._witness(tok, found)

    # ----- inner WME changes -----

    def _candidates(self, k: int, wme: WME) -> list[_Token]:
        """The tokens whose values could let ``wme`` match inner condition ``k``: those
        passing its equality tests against parent values (the first one hashed)."""
        tests = self.owner_tests[k]
        if not tests:
            return list(self.owners.values())
        getter, pos = tests[0]
        found = self.owner_index[pos].get(_hkey(getter(wme)))
        if not found:
            return []
        if len(tests) == 1:
            return list(found)
        rest = [(getter(wme), pos) for getter, pos in tests[1:]]
        return [tok for tok in found
                if all(same_symbol(tok.vals[pos], value) for value, pos in rest)]

    def inner_removed(self, k: int, wme: WME) -> None:
        """A WME left a negated inner condition's memory: results may appear."""
        for tok in self._candidates(k, wme):
            if tok.extra is None and tok.node is not None:
                found = self.solvers[0](tok.vals, None)
                if found is not None:
                    self._block(tok, found)


def _witness_lines(pad: str) -> list[str]:
    """Generated code: keep ``found`` as the witness of the blocked ``tok`` (what
    ``_QueryNCCNode._witness`` does, inline; ``R`` is the Rete's WME records)."""
    return [f"{pad}tok.extra = found", f"{pad}for w in found[1]:", f"{pad}    record = R[w]",
            f"{pad}    s = record[3]", f"{pad}    if s is None: record[3] = {{tok: None}}",
            f"{pad}    else: s[tok] = None"]


def _seed_filters(levels: list[tuple], width: int, amems: list[_AlphaMemory],
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
    filter.  ``levels`` are as in :class:`_QueryNCCNode`; ``levels[k][7]`` are their
    equality tests ``(field, vals position)``."""
    bound_at: dict[int, tuple[int, str]] = {}
    position = width
    for j, level in enumerate(levels):
        for field in level[5]:
            bound_at[position] = (j, field)
            position += 1
    filters: list[list[tuple[Callable, dict]]] = [[] for _ in levels]
    for k, level in enumerate(levels):
        if level[6]:  # a negated condition needs no match
            continue
        for field, p in level[7]:
            if p in bound_at and bound_at[p][0] != k:
                j, bound_field = bound_at[p]
                if not owner_tests[k]:
                    filters[k].append((_GET[field], amems[j].index(bound_field)))
                if not owner_tests[j]:
                    filters[j].append((_GET[bound_field], amems[k].index(field)))
    return filters


def _joins_within(plan: _Plan, base: int, amem: _AlphaMemory, run: list[tuple]) -> bool:
    """Whether a condition can join a run that started with ``base`` values: it is hashed
    on one of them and tests no other value bound after them (so it is independent of the
    run's other conditions), and its alpha memory is not one of theirs."""
    if plan.index is None or plan.index[0] >= base:
        return False
    if any(ref[0] == "v" and ref[1] >= base for spec in plan.beta for ref in (spec[0], spec[2])):
        return False
    return all(other is not amem for _, _, other in run)


def _compile_run(node: _RunNode, seed: int) -> Callable:
    """Generate what makes a run node's tokens: one per combination of WMEs matching its run
    of independent conditions, found in nested loops, each token adopted, registered with
    its WMEs and stored as it is found.  ``seed`` < 0: ``make(t)``, every combination
    below a new parent token ``t``; otherwise ``right_activate(seed)``, the combinations in
    which member ``seed`` matches the WME just added, below every parent token it joins."""
    members = node.members
    namespace: dict[str, object] = {**_CHECK_NAMES, "FLOAT": _FLOAT, "Tok": _Token,
                                    "N": node, "R": node.registry, "T": node.tokens,
                                    "CH": node.children}
    if seed < 0:
        lines, depth = ["def make(t):", "    vals = t.vals"], 1
    else:
        namespace["PI"] = node.parent.index(members[seed][2])  # type: ignore[union-attr]
        lines = ["def right_activate(seed):", f"    key = G{seed}(seed)",
                 "    if key.__class__ is float: key = (FLOAT, key)",
                 "    bucket = PI.get(key)", "    if not bucket: return",
                 "    for t in list(bucket):", "        vals = t.vals"]
        depth = 2
    for k, (_, index, pos, getter, check, _) in enumerate(members):
        pad = "    " * depth
        namespace.update({f"I{k}": index, f"G{k}": getter})
        lines += _bucket_lines(k, pad, f"vals[{pos}]" if pos >= 0 else None, k == seed)
        lines.append(f"{pad}for w{k} in b{k}:")
        if check is not None:
            lines += _check_lines(check.specs, "vals", f"w{k}", "continue", pad + "    ")
        depth += 1
    pad = "    " * depth
    bound = "".join(f"w{k}.{field}, " for k, member in enumerate(members) for field in member[5])
    wmes = "".join(f"w{k}, " for k in range(len(members)))
    lines += [*_token_lines(pad, "t", f"({wmes})", f"vals + ({bound})" if bound else "vals"),
              f"{pad}s = t.children",
              f"{pad}if s is None: t.children = {{tok: None}}",
              f"{pad}else: s[tok] = None"]
    lines += [f"{pad}R[w{k}][1][tok] = None" for k in range(len(members))]
    lines.append(f"{pad}T[tok] = None")
    for k, (pos, index) in enumerate(node.index_list):
        namespace[f"X{k}"] = index
        lines += _filing_lines(f"X{k}", f"tok.vals[{pos}]", "tok", pad, True)
    lines += [f"{pad}for child in CH:", f"{pad}    child.left_activate(tok)"]
    return define(lines, namespace, "make" if seed < 0 else "right_activate")


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class _RunNode(_Node):
    """Consecutive positive conditions that test only values the parent token already has,
    joined as one node: ``(<c> ^zmax > <zl>)`` filters after ``<c>`` and ``<zl>`` are bound,
    or ``(<o> ^disk <d>) (<o> ^from <f>)`` once ``<o>`` is.

    Such conditions are independent of one another, so their join is the product of their
    matches: one token per combination (``tok.wme`` is the tuple of its WMEs, ``tok.vals`` the
    values extended by what they bind), instead of a chain of nodes with a token per
    condition, most of which die a level or two further down.  In the block planner's
    geometry rules every pair of blocks goes through six filters; as a chain they made three
    tokens per pair."""

    __slots__ = ("members", "amems", "makers", "registry", "left_activate", "forget")

    def __init__(self, rete: Rete, parent: _Node, key: object, members: list[tuple]) -> None:
        super().__init__(rete, parent, key)
        # per condition: (alpha memory, its hash index, parent value position, getter,
        # check, fields it binds)
        self.members = members
        self.amems = [member[0] for member in members]
        self.registry = rete._wme_info
        for member in members:
            parent.index(member[2])
        self.makers: list[Callable] = []
        self.left_activate: Callable[[_Token], None]
        self.forget: Callable[[_Token], None]
        self._compile()

    def _compile(self) -> None:
        """Generate the makers: ``makers[0](t)`` makes every combination below a parent
        token (the left activation), ``makers[k + 1](wme)`` those with condition k matching
        a new WME (the right activation for its alpha memory); and ``forget``, which drops a
        token from the memory, its indices and its WMEs' records."""
        self.makers = [_compile_run(self, seed) for seed in range(-1, len(self.members))]
        self.left_activate = self.makers[0]
        namespace: dict[str, object] = {"FLOAT": _FLOAT, "T": self.tokens, "R": self.registry}
        lines = ["def forget(tok):", "    del T[tok]"]
        for k, (pos, index) in enumerate(self.index_list):
            namespace[f"I{k}"] = index
            lines += _key_lines(f"tok.vals[{pos}]", "    ", True) + [
                f"    b = I{k}[key]", "    del b[tok]", f"    if not b: del I{k}[key]"]
        wmes = [f"w{k}" for k in range(len(self.members))]
        lines.append(f"    {', '.join(wmes)}, = tok.wme")
        for w in wmes:
            lines += [f"    r = R.get({w})", "    if r is not None: r[1].pop(tok, None)"]
        self.forget = define(lines, namespace, "forget")

    def index(self, pos: int) -> dict:
        """The makers file new tokens in the node's indices: a new one means new makers,
        and the alpha memories relink to their new right activations."""
        known = pos in self.indexes
        index = super().index(pos)
        if not known:
            self._compile()
            for amem in set(self.amems):
                amem._relink()
        return index

    def activation(self, amem: _AlphaMemory) -> Callable[[WME], None]:
        return self.makers[self.amems.index(amem) + 1]


@mypyc_attr(native_class=False)  # methods and generated functions in the same places
class _ProductionNode(_Node):
    """Bottom of a production: each token is a Match.

    Both activations are generated for the production (on first use) as straight-line
    code, the Match made inline (``_Layout.match_lines``): most matches are fired, which
    needs all their fields, and compiled methods of this class would reach the tokens'
    and matches' slots through the generic attribute lookup, several times slower than
    the interpreter's specialized slot access."""

    __slots__ = ("production", "layout", "added", "removed", "left_activate", "forget")

    def __init__(self, rete: Rete, parent: _Node, production: Production,
                 layout: _Layout) -> None:
        super().__init__(rete, parent, ("production", production.name))
        self.production = production
        self.layout = layout
        # the Rete's _Changes, whose dicts are emptied in place (never replaced)
        self.added = rete._changes.added
        self.removed = rete._changes.removed
        self.left_activate: Callable[[_Token], None]
        self.forget: Callable[[_Token], None]
        _compile_first(self, "left_activate", "forget")

    def _compile(self) -> None:
        """Generate ``left_activate`` (make the Match and its token, report it) and
        ``forget`` (drop the token; retract its Match, or cancel its appearance in this
        interval, as ``_Changes.retract`` does; a token without a Match is one whose Match
        moved to a rebuilt network, see Rete._rebuild)."""
        namespace: dict[str, object] = {
            "NEW": _new, "Match": Match, "P": self.production, "Tok": _Token, "N": self,
            "T": self.tokens, "A": self.added, "D": self.removed}
        left = ["def left_activate(t):", *self.layout.match_lines("t", "    "),
                *_token_lines("    ", "t", "None", "None"), "    tok.extra = m",
                "    s = t.children", "    if s is None: t.children = {tok: None}",
                "    else: s[tok] = None", "    T[tok] = None", "    A[m] = None"]
        forget = ["def forget(tok):", "    del T[tok]", "    m = tok.extra",
                  "    if m is not None:", "        if m in A: del A[m]",
                  "        else: D[m] = None"]
        self.left_activate = define(left, namespace, "left_activate")
        self.forget = define(forget, dict(namespace), "forget")


class _Layout:
    """Where a production's WMEs and variables sit in its tokens, and the generated lines
    that make the Match of a token (``match_lines``): a loop over the levels that tests
    each one's kind costs twice as much as straight-line code."""

    __slots__ = ("production", "levels", "size", "bindings", "positive")

    def __init__(self, production: Production, levels: list[tuple[int, ...]],
                 bindings: list[tuple[str, int]], positive: set[int]) -> None:
        self.production = production
        # levels[k] = written indices of the elements matched at token level k: one, or
        # several for a run of independent conditions (whose token holds a tuple of WMEs)
        self.levels = levels[::-1]
        self.size = sum(len(level) for level in levels)
        self.bindings = bindings
        self.positive = positive  # written indices of the positive conditions

    def match_lines(self, tok: str, pad: str) -> list[str]:
        """Generated code: ``m`` = the Match of the token ``tok`` (``NEW``, ``Match`` and the
        production ``P`` in the namespace): the WMEs in written order (``None`` for
        negations), ``newest`` (the first index of the newest WME, found in written
        order), and the variables' values as a dict literal."""
        items = "".join(f"{name!r}: v[{pos}], " for name, pos in self.bindings)
        lines = ["m = NEW(Match)", "m.production = P", f"v = {tok}.vals",
                 f"m.bindings = {{{items}}}", f"k = {tok}"]
        last = len(self.levels) - 1
        for k, level in enumerate(self.levels):
            if len(level) > 1:
                lines.append(f"{', '.join(f'w{i}' for i in level)}, = k.wme")
            elif level[0] in self.positive:
                lines.append(f"w{level[0]} = k.wme")
            if k < last:
                lines.append("k = k.parent")
        lines.append("newest, at = 0, -1")
        for i in sorted(self.positive):
            lines.append(f"if w{i}.timetag > newest: newest, at = w{i}.timetag, {i}")
        written = "".join(f"w{i}, " if i in self.positive else "None, " for i in range(self.size))
        lines += [f"m.wmes = ({written})", "m.newest = (newest, at)"]
        return [pad + line for line in lines]


# ----- compiling conditions -------------------------------------------------------------------


def _atoms(test: Test) -> list[Test]:
    """A field test as a flat list of Var / Const / Relational / Disjunction."""
    if isinstance(test, Conjunction):
        out: list[Test] = []
        for inner in test.tests:
            out.extend(_atoms(inner))
        return out
    return [test]


def _mentioned(element: ConditionElement) -> set[str]:
    """Every variable a condition element mentions (equality or relational, nested)."""
    if isinstance(element, ConjunctiveNegation):
        return set().union(*(_mentioned(e) for e in element.conditions))
    names: set[str] = set()
    for test in _fields(element):
        names.update(equality_vars(test))
        names.update(relational_vars(test))
    return names


def _compile_alpha(specs: list[tuple]) -> Callable[[WME], bool] | None:
    """One generated function for a condition's constant tests (as for the join tests)."""
    if not specs:
        return None
    lines = ["def accept(w):"]
    namespace: dict[str, object] = {"NUMBERS": _NUMBERS}
    for n, spec in enumerate(specs):
        kind = spec[0]
        if kind == "state":
            lines.append("    if w.id.level is None: return False")
            continue
        if kind == "never":
            lines.append("    return False")
            continue
        lines.append(f"    x = w.{spec[1]}")
        if kind == "type":
            lines.append(f"    if x.__class__ is not {spec[2]}: return False")
        elif kind == "eq":
            namespace[f"c{n}"] = spec[2][1]
            lines.append(f"    if not (x.__class__ is c{n}.__class__ and x == c{n}): return False")
        elif kind == "rel":
            namespace[f"c{n}"] = spec[3][1]
            namespace[f"r{n}"] = _RELATIONS[spec[2]]
            lines.append(f"    if not r{n}(x, c{n}): return False")
        else:  # disjunction of typed constants
            namespace[f"d{n}"] = frozenset(spec[2])
            lines.append(f"    if (x.__class__.__name__, x) not in d{n}: return False")
    lines.append("    return True")
    return define(lines, namespace, "accept")


_NUMBERS = frozenset((int, float))
_ORDER_OPS = {"<": "<", ">": ">", "<=": "<=", ">=": ">="}
_CHECK_NAMES: dict[str, object] = {"NUMBERS": _NUMBERS, "RELATIONS": _RELATIONS}


def _check_lines(specs: Sequence[BetaSpec], vals: str, w: str, fail: str, pad: str,
                 value: Callable[[int], str] | None = None) -> list[str]:
    """Generated code testing every beta test of a join on the values ``vals`` and the WME
    ``w``, running ``fail`` (``return False``, ``continue``) at the first that does not
    hold.  The join and query loops inline these lines: in the innermost loop a call per
    pair costs more than the tests themselves.  ``value(pos)`` may name a value position
    otherwise than ``vals[pos]``."""
    if value is None:
        value = f"{vals}[{{}}]".format  # not a nested def: mypyc fails on one rebinding a parameter
    lines = []
    for n, ((lk, la), op, (rk, ra)) in enumerate(specs):
        left = f"{w}.{la}" if lk == "w" else value(la)  # type: ignore[arg-type]
        right = f"{w}.{ra}" if rk == "w" else value(ra)  # type: ignore[arg-type]
        x, y = f"cx{n}", f"cy{n}"
        lines.append(f"{x} = {left}; {y} = {right}")
        if op == "=":
            lines.append(f"if {x} is not {y} and not ({x}.__class__ is {y}.__class__ "
                         f"and {x} == {y}): {fail}")
        elif op == "<>":
            lines.append(f"if {x} is {y} or ({x}.__class__ is {y}.__class__ "
                         f"and {x} == {y}): {fail}")
        elif op == "<=>":
            lines.append(f"if {x}.__class__ is not {y}.__class__: {fail}")
        elif op == "@":
            lines.append(fail)
        elif op in _ORDER_OPS:
            lines.append(f"if {x}.__class__ in NUMBERS and {y}.__class__ in NUMBERS:")
            lines.append(f"    if not ({x} {op} {y}): {fail}")
            lines.append(f"elif not RELATIONS[{op!r}]({x}, {y}): {fail}")
        elif op != "!@":
            raise AssertionError(f"unknown relation {op!r}")
    return [pad + line for line in lines]


def _compile_check(specs: list[BetaSpec]) -> Callable[[tuple, WME], bool] | None:
    """One Python function testing every beta test of a join, for the nodes that call it
    per WME; its ``specs`` attribute lets generated loops inline the same tests."""
    if not specs:
        return None
    lines = ["def check(vals, w):", *_check_lines(specs, "vals", "w", "return False", "    "),
             "    return True"]
    check = define(lines, dict(_CHECK_NAMES), "check")
    check.specs = tuple(specs)  # type: ignore[attr-defined]
    return check


def _EXTEND_VALUE(vals: tuple, w: WME) -> tuple:  # noqa: N802 -- a marker as much as a function
    return vals + (w.value,)


def _extender(fields: tuple[str, ...]) -> Callable | None:
    """How a join extends a token's values with what the WME binds."""
    if not fields:
        return None
    if fields == ("value",):
        return _EXTEND_VALUE
    code = "lambda vals, w: vals + (" + "".join(f"w.{f}, " for f in fields) + ")"
    return eval(code)  # noqa: S307 -- field names from _FIELDS only


class _Plan:
    """What one condition compiles to at its place in the join order."""

    __slots__ = ("alpha_key", "lookup", "alpha_tests", "index", "beta", "new_fields")

    def __init__(self) -> None:
        self.alpha_key: tuple = ()
        self.lookup: tuple = ()
        self.alpha_tests: list[tuple] = []
        self.index: tuple[int, str] | None = None
        self.beta: list[BetaSpec] = []
        self.new_fields: list[str] = []


def _plan_condition(cond: Condition, var_pos: dict[str, int], nvals: int,
                    deferred: list[tuple[int, str, str]], states: set[str]) -> _Plan:
    """Compile ``cond`` given the variables bound so far (``var_pos``, updated in place for a
    positive condition).  Relational tests on variables bound only later are appended to
    ``deferred`` and placed at the join that binds them."""
    plan = _Plan()
    attr_key: object = _ANY
    value_key: object = _ANY
    alpha: list[tuple] = []
    local: dict[str, Ref] = {}  # variables first bound by this condition -> their field
    field_ref: dict[str, Ref] = {}
    relational: list[tuple[str, str, str]] = []
    if cond.goal is not None and not any(
            name in var_pos and name in states for name in equality_vars(cond.id_test)):
        alpha.append(("state",))  # (a variable already tested as a state needs no retest)
    for field, test in zip(_FIELDS, _fields(cond), strict=True):
        ref: Ref | None = None
        new_names: list[str] = []
        for atom in _atoms(test):
            if isinstance(atom, Var):
                known = ("v", var_pos[atom.name]) if atom.name in var_pos else local.get(atom.name)
                if known is None:
                    new_names.append(atom.name)
                elif ref is None:
                    ref = known
                    if known != ("w", field):
                        plan.beta.append((("w", field), "=", known))
                elif known != ref:
                    plan.beta.append((("w", field), "=", known))
            elif isinstance(atom, Const):
                value = atom.value
                if field == "attr" and attr_key is _ANY:
                    attr_key = value
                elif field == "value" and value_key is _ANY:
                    value_key = value
                else:
                    alpha.append(("eq", field, _typed(value)))
                    continue
                if value.__class__ in (int, float):
                    alpha.append(("type", field, value.__class__.__name__))
            elif isinstance(atom, Disjunction):
                alpha.append(("disj", field, tuple(sorted({_typed(c.value) for c in atom.values},
                                                         key=repr))))
            elif isinstance(atom.operand, Const):
                if atom.op == "@":
                    alpha.append(("never",))
                elif atom.op != "!@":
                    alpha.append(("rel", field, atom.op, _typed(atom.operand.value)))
            elif atom.op == "@":
                alpha.append(("never",))
            elif atom.op != "!@":
                relational.append((field, atom.op, atom.operand.name))
        if new_names:
            if ref is None:
                ref = ("w", field)
                if not cond.negated:
                    plan.new_fields.append(field)
            for name in new_names:
                local[name] = ref
        if ref is not None:
            field_ref[field] = ref
    for field, op, name in relational:
        if name in var_pos:
            plan.beta.append((("w", field), op, ("v", var_pos[name])))
        elif name in local:
            plan.beta.append((("w", field), op, local[name]))
        else:  # bound by a later condition: keep this field's value in the token
            ref = field_ref.get(field)
            if ref is None:
                plan.new_fields.append(field)
                ref = field_ref[field] = ("w", field)
            lhs = nvals + plan.new_fields.index(ref[1]) if ref[0] == "w" else ref[1]
            deferred.append((lhs, op, name))  # type: ignore[arg-type]
    if not cond.negated:
        for name, ref in local.items():
            var_pos[name] = ref[1] if ref[0] == "v" else nvals + plan.new_fields.index(ref[1])
        for item in list(deferred):
            lhs, op, name = item
            if name in local and lhs < nvals:
                plan.beta.append((("v", lhs), op, local[name]))
                deferred.remove(item)
    _choose_index(plan)
    tests = tuple(sorted(set(alpha), key=repr))
    acc = bool(cond.acceptable)
    plan.alpha_tests = list(tests)
    plan.lookup = (attr_key, value_key, acc)
    plan.alpha_key = (_typed(attr_key) if attr_key is not _ANY else None,
                      _typed(value_key) if value_key is not _ANY else None, acc, tests)
    return plan


def _choose_index(plan: _Plan) -> None:
    """Hash the join on one equality test between the WME and an earlier binding."""
    candidates = [spec for spec in plan.beta
                  if spec[1] == "=" and spec[0][0] == "w" and spec[2][0] == "v"]
    if not candidates:
        return
    # The most recently bound variable is usually the most selective key: joining
    # (<il> ^block <o>) with both bound should look up <o>, not every block of <il>.
    best = max(candidates, key=lambda spec: (spec[2][1], -_INDEX_PREFERENCE[spec[0][1]]))
    plan.beta.remove(best)
    plan.index = (best[2][1], best[0][1])  # type: ignore[assignment]


def _join_cost(cond: Condition, bound: set[str], singletons: set[str],
               volatile: set[object]) -> int:
    """Estimated fan-out class, cheapest first:

    0. a check or a constant test (attribute and value fixed), or a step of a path (see
       ``_path_hop``);
    1. a join on the value, bound elsewhere (``(<b> ^name <n>)``: the WMEs with that value
       are usually few);
    2. a constant attribute with a new value (all the values of a multi-valued attribute);
    3. the same, with a relational test waiting for a variable bound later (cannot prune);
    4. a variable attribute;
    5. an existence test (``(<s> ^step)``: its value is used nowhere else), or a check of a
       volatile attribute (one that rules remove, like ``^last-moved``, and ``^operator``).
       They go last, the classic advice for Rete rules: every change of a WME a condition
       matches rebuilds all the tokens below that condition.
    """
    late = isinstance(cond.attr_test, Const) and cond.attr_test.value in volatile
    if _path_hop(cond, bound, late):
        return 0

    def fixed(test: Test) -> bool:  # binds nothing new: a constant, a check or a filter
        return set(equality_vars(test)) <= bound

    if not fixed(cond.attr_test):
        return 4
    values = set(equality_vars(cond.value_test))
    if not bound.intersection(equality_vars(cond.id_test)):
        if values and values <= bound:
            return 1
        if not values:
            return 5 if late else 0
    elif fixed(cond.value_test):
        return 5 if late else 0
    if values - bound and values - bound <= singletons:
        return 5
    own = set().union(*(equality_vars(t) for t in _fields(cond)))
    pending = set().union(*(relational_vars(t) for t in _fields(cond))) - bound - own
    return 3 if pending else 2


def _path_hop(cond: Condition, bound: set[str], late: bool) -> bool:
    """A step of a path such as ``^io.input-link``: a stable constant attribute leading from a
    bound identifier to a variable the parser generated for the path.  Such steps are
    structure (usually one value each), so they join first: their tokens then form a prefix
    that stays put while the volatile conditions below it change."""
    value = cond.value_test
    return (not late and isinstance(cond.attr_test, Const) and isinstance(value, Var)
            and "*" in value.name and value.name not in bound
            and bool(bound.intersection(equality_vars(cond.id_test))))


def _const_attributes(elements: tuple[ConditionElement, ...]) -> set[object]:
    """The constant attributes tested anywhere in ``elements`` (nested negations too)."""
    found: set[object] = set()
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            found |= _const_attributes(element.conditions)
        elif isinstance(element.attr_test, Const):
            found.add(element.attr_test.value)
    return found


def _variables_of(item: object) -> Iterator[str]:
    """Every variable occurrence in a condition element, action or value (recursively)."""
    if isinstance(item, Var):
        yield item.name
    elif isinstance(item, (tuple, list)):
        for part in item:
            yield from _variables_of(part)
    elif hasattr(item, "__dataclass_fields__"):
        for name in item.__dataclass_fields__:  # type: ignore[attr-defined]
            yield from _variables_of(getattr(item, name))


def _singletons(production: Production) -> set[str]:
    """Variables that occur once in the whole production (conditions and actions)."""
    counts: dict[str, int] = {}
    for name in _variables_of((production.conditions, production.actions)):
        counts[name] = counts.get(name, 0) + 1
    return {name for name, count in counts.items() if count == 1}


def _join_order(elements: tuple[ConditionElement, ...], bound: dict[str, int], scope: set[str],
                singletons: set[str], volatile: set[object]) -> list[int]:
    """Most constrained first, keeping linkage: a positive condition joins on an identifier
    already bound, or on its value when that is a bound variable and the attribute a constant
    (a hashed "reverse" join: ``(<b> ^name <n>)`` with ``<n>`` bound finds the one block
    instead of walking all of them; the identifier test becomes a check later on).
    Negations go in as soon as the variables they share are bound.  Among
    equally constrained conditions the one on the most recently bound identifier wins: it
    follows the object just reached (whose attributes are usually single-valued) and binds
    what pending negations wait for before fanning out elsewhere."""
    age = {name: pos + 1 for name, pos in bound.items()}  # binding order, outer ones first
    clock = len(bound) + 1
    remaining = list(range(len(elements)))
    order: list[int] = []

    def place(index: int) -> None:
        remaining.remove(index)
        order.append(index)
        element = elements[index]
        if isinstance(element, Condition) and not element.negated:
            late = isinstance(element.attr_test, Const) and element.attr_test.value in volatile
            if _path_hop(element, set(age), late):
                # A path step does not move the focus: the next join follows the object the
                # path started from, not the path's own (single-valued) variable.
                start = max(age[name] for name in equality_vars(element.id_test) if name in age)
                age.setdefault(element.value_test.name, start)  # type: ignore[union-attr]
                return
            for test in _fields(element):
                for name in equality_vars(test):
                    age.setdefault(name, clock + len(order))

    def recency(cond: Condition) -> int:
        names = equality_vars(cond.id_test)
        if not age.keys() & set(names):  # joined on its value
            names = equality_vars(cond.value_test)
        return max((age.get(name, -1) for name in names), default=-1)

    def value_linked(cond: Condition) -> bool:
        return (isinstance(cond.attr_test, Const)
                and bool(age.keys() & set(equality_vars(cond.value_test))))

    while remaining:
        for index in list(remaining):
            element = elements[index]
            if isinstance(element, Condition) and not element.negated:
                continue
            if (_mentioned(element) & scope) <= age.keys():
                place(index)
        positives = [i for i in remaining
                     if isinstance(elements[i], Condition) and not elements[i].negated]
        if not positives:
            if remaining:
                place(remaining[0])
            continue
        linked = [i for i in positives if age.keys() & set(equality_vars(elements[i].id_test))
                  or value_linked(elements[i])]
        pool = linked or [i for i in positives if elements[i].goal is not None] or positives
        place(min(pool, key=lambda i: (_join_cost(elements[i], set(age), singletons, volatile),
                                       -recency(elements[i]), i)))
    return order


# ----- the network ----------------------------------------------------------------------------


class Rete:
    """Doorenbos's Rete with hashed alpha and beta memories, negative and NCC nodes and
    shared prefixes.  Same interface as :class:`BruteForceMatcher`.

    Conditions not linked to a state load, as in the kernel (which warns about them); they
    are joined on any bound variable, or as a cross product.  ``check_links=True`` refuses
    them instead (see :func:`check_production`).
    """

    def __init__(self, check_links: bool = False) -> None:
        self.check_links = check_links
        self._root = _Node(self, None)
        self._root_token = _new_token(None, None, (), self._root)
        self._root.tokens[self._root_token] = None
        self._pnodes: dict[str, _ProductionNode] = {}
        self._productions: dict[str, Production] = {}  # in the order added
        self._pending: list[Production] = []  # added, network not built yet (see _flush)
        self._removed_attrs: set[object] = {"operator"}  # attributes rules remove
        self._stale: set[str] = set()  # built before an attribute they check became volatile
        self._amems: dict[tuple, _AlphaMemory] = {}
        self._alpha_index: dict[tuple, list[_AlphaMemory]] = {}
        # constant values that alpha memories test for -> how many do: a WME whose value
        # is none of them is cached under _UNTESTED, so a fresh number (a counter's next
        # value) does not miss the cache
        self._tested_values: dict[object, int] = {}
        self._alpha_cache: dict[tuple, tuple[list[_AlphaMemory], bool]] = {}
        # per WME: [alpha memories, tokens built on it, negative tokens it blocks]
        self._wme_info: dict[WME, list] = {}
        self._changes = _Changes()

    # ----- public interface -----

    def add_production(self, production: Production) -> None:
        if production.name in self._productions:
            raise SoarSemanticError(production.name, "a production with this name exists",
                                    production.location)
        check_production(production, links=self.check_links)
        self._productions[production.name] = production
        self._pending.append(production)
        for action in production.actions:
            if (isinstance(action, MakeAction) and action.preference == "-"
                    and isinstance(action.attr, Const)
                    and action.attr.value not in self._removed_attrs):
                attr = action.attr.value
                self._removed_attrs.add(attr)
                self._stale.update(name for name, pnode in self._pnodes.items()
                                   if attr in _const_attributes(pnode.production.conditions))

    def _flush(self) -> None:
        """Build the productions added since the last change of working memory or query.

        Deferring the build lets the join order see the rules added together: which
        attributes the rules remove (volatile) is known only then.  A production built
        before one of its checked attributes turned out volatile is rebuilt, keeping its
        Match objects.  Matches still appear in the next take_changes(), as promised."""
        stale, self._stale = self._stale, set()
        for name in stale:
            if name in self._pnodes:
                self._rebuild(self._pnodes[name])
        pending, self._pending = self._pending, []
        for production in pending:
            self._build(production)

    def _rebuild(self, old: _ProductionNode) -> None:
        """Rebuild a production with the current join order; its live matches keep their
        identity (same WMEs, same Match object), so no change is reported for them."""
        live = {tuple(map(id, tok.extra.wmes)): tok for tok in old.tokens}
        added = self._changes.added
        new = self._build(old.production)
        for tok in new.tokens:
            match = tok.extra
            previous = live.pop(tuple(map(id, match.wmes)), None)
            if previous is None:
                continue
            kept = previous.extra
            previous.extra = None  # its old token leaves without retracting it
            added.pop(match, None)
            tok.extra = kept
        self._remove_node(old)

    def _build(self, production: Production) -> _ProductionNode:
        conditions = production.conditions
        scope = _bound_by(conditions)
        var_pos: dict[str, int] = {}
        bottom, levels = self._build_scope(conditions, self._root, var_pos, 0, scope,
                                           _singletons(production), set(), runs=True)
        positive = {i for i, element in enumerate(conditions)
                    if isinstance(element, Condition) and not element.negated}
        bindings = sorted((n, p) for n, p in var_pos.items() if n in scope)
        layout = _Layout(production, levels, bindings, positive)
        pnode = _ProductionNode(self, bottom, production, layout)
        bottom.children.append(pnode)
        self._pnodes[production.name] = pnode
        for tok in list(bottom.tokens):
            pnode.left_activate(tok)
        return pnode

    def excise(self, name: str) -> None:
        if self._pending:
            self._flush()
        pnode = self._pnodes.pop(name, None)
        if pnode is None:
            raise KeyError(f"no production named {name!r}")
        del self._productions[name]
        self._remove_node(pnode)

    def add_wme(self, wme: WME) -> None:
        if self._pending:
            self._flush()
        attr, value = wme.attr, wme.value
        key = (_IDENT if type(attr) is Identifier else attr,
               value if value in self._tested_values else _UNTESTED,  # an identifier never is
               wme.acceptable)
        entry = self._alpha_cache.get(key)
        found, plain = entry if entry is not None else self._alpha_entry(key)
        if plain:
            # No memory here filters further: the WME enters them all, and the cache's list
            # (never mutated, see _alpha_memory) is its record of them.
            record = [found, {}, None, None]
            if self._wme_info.setdefault(wme, record) is not record:
                raise ValueError(f"{wme!r} is already in working memory")
            for amem in found:
                amem.on_add(wme)
            return
        amems: list[_AlphaMemory] = []
        record = [amems, {}, None, None]
        if self._wme_info.setdefault(wme, record) is not record:
            raise ValueError(f"{wme!r} is already in working memory")
        for amem in found:
            accept = amem.accept
            if accept is None or accept(wme):
                amems.append(amem)
                amem.on_add(wme)

    def remove_wme(self, wme: WME) -> None:
        if self._pending:
            self._flush()
        info = self._wme_info.pop(wme, None)
        if info is None:
            raise ValueError(f"{wme!r} is not in working memory")
        for amem in info[0]:
            amem.on_remove(wme)
        built = info[1]
        if built:
            # Detached from their parents first, then deleted in one walk (a token built on
            # this WME below another one is detached from its still-live parent: each is
            # deleted once).
            doomed = []
            for tok in built:
                if tok.node is not None:
                    del tok.parent.children[tok]
                    doomed.append(tok)
            doomed.reverse()  # the walk pops from the end: the first built goes first
            self._delete_tokens(doomed)
        blocked = info[2]
        if blocked:
            for tok in blocked:
                node = tok.node
                if node is not None:
                    blockers = tok.extra
                    del blockers[wme]
                    if not blockers:
                        node.unblock(tok)
        witnessed = info[3]
        if witnessed:
            for tok in list(witnessed):
                node = tok.node
                if node is not None and tok.extra is not None:
                    node.recheck(tok)
        for amem in info[0]:
            if amem.listeners:
                for node, k in amem.listeners:
                    if node.owners and node.levels[k][6]:
                        node.inner_removed(k, wme)

    def clear_wmes(self) -> None:
        """Remove every WME at once: the same changes as ``remove_wme`` on each (every live
        match is retracted), but the memories are emptied in place instead of deleting the
        tokens one by one, so ``init-soar`` costs the size of the network, not the joins."""
        if self._pending:
            self._flush()
        for pnode in self._pnodes.values():
            for tok in pnode.tokens:
                if tok.extra is not None:
                    self._changes.retract(tok.extra)
        self._wme_info.clear()
        for amem in self._amems.values():
            amem.wmes.clear()
            for index in amem.indexes.values():
                index.clear()  # cleared in place: the join nodes hold these very dicts
        self._clear_memories(self._root)
        _unlink_tokens(self._root_token)
        for child in self._root.children:  # a node needing no WME gets its token back
            child.left_activate(self._root_token)

    def _clear_memories(self, top: _Node) -> None:
        """Empty the token memories of every node below ``top`` (in place).  A node passes
        on only its active tokens, so the children of a node without any hold none either:
        the walk costs the live part of the network."""
        stack = list(top.children)
        while stack:
            node = stack.pop()
            if node.tokens:
                stack.extend(node.children)
                node.tokens.clear()
            for index in node.indexes.values():
                index.clear()
            if isinstance(node, _NegativeNode):
                node.every.clear()
                node.every_index.clear()
            elif isinstance(node, _NCCNode):
                node.owners.clear()
            elif isinstance(node, _PartnerNode):
                node.buffer.clear()
            elif isinstance(node, _QueryNCCNode):
                node.owners.clear()
                for index in node.owner_index.values():
                    index.clear()

    def take_changes(self) -> tuple[list[Match], list[Match]]:
        if self._pending:
            self._flush()
        return self._changes.take()

    def mark_removals(self) -> None:
        """The WMEs removed from here on: the retractions reported before were made by
        added WMEs (``blocked_retractions`` counts them at the next take_changes)."""
        self._changes.mark_removals()

    @property
    def blocked_retractions(self) -> int:
        return self._changes.blocked

    def matches(self, name: str) -> list[Match]:
        if self._pending:
            self._flush()
        pnode = self._pnodes.get(name)
        if pnode is None:
            raise KeyError(f"no production named {name!r}")
        return [tok.extra for tok in pnode.tokens]

    def productions(self) -> list[Production]:
        return list(self._productions.values())

    # ----- alpha network -----

    def _alpha_entry(self, key: tuple) -> tuple[list[_AlphaMemory], bool]:
        """For an alpha cache key (see add_wme): the alpha memories whose lookup key fits,
        and whether none of them has a further test (then a WME enters them all); cached."""
        akey, vkey, acc = key
        found: list[_AlphaMemory] = []
        for probe in (key, (akey, _ANY, acc), (_ANY, vkey, acc), (_ANY, _ANY, acc)):
            amems = self._alpha_index.get(probe)
            if amems:
                found.extend(amems)
        if len(self._alpha_cache) >= _ALPHA_CACHE_LIMIT:
            self._alpha_cache.clear()
        entry = self._alpha_cache[key] = (found, all(a.accept is None for a in found))
        return entry

    def _alpha_memory(self, plan: _Plan) -> _AlphaMemory:
        amem = self._amems.get(plan.alpha_key)
        if amem is not None:
            return amem
        amem = _AlphaMemory(plan.alpha_key, plan.lookup,
                            _compile_alpha(plan.alpha_tests))
        self._amems[plan.alpha_key] = amem
        self._alpha_index.setdefault(plan.lookup, []).append(amem)
        value_key = plan.lookup[1]
        if value_key is not _ANY:
            self._tested_values[value_key] = self._tested_values.get(value_key, 0) + 1
        self._alpha_cache.clear()
        for wme, info in self._wme_info.items():
            if self._alpha_accepts(amem, wme):
                amem.add(wme)
                info[0] = [*info[0], amem]  # a new list: it may be shared (see add_wme)
        return amem

    @staticmethod
    def _alpha_accepts(amem: _AlphaMemory, wme: WME) -> bool:
        attr_key, value_key, acc = amem.lookup
        if wme.acceptable != acc:
            return False
        if attr_key is not _ANY and not (wme.attr.__class__ is not Identifier
                                         and wme.attr == attr_key):
            return False
        if value_key is not _ANY and not (wme.value.__class__ is not Identifier
                                          and wme.value == value_key):
            return False
        return amem.accept is None or amem.accept(wme)

    def _drop_alpha_memory(self, amem: _AlphaMemory) -> None:
        del self._amems[amem.key]
        value_key = amem.lookup[1]
        if value_key is not _ANY:
            count = self._tested_values[value_key] - 1
            if count:
                self._tested_values[value_key] = count
            else:
                del self._tested_values[value_key]
        siblings = self._alpha_index[amem.lookup]
        siblings.remove(amem)
        if not siblings:
            del self._alpha_index[amem.lookup]
        self._alpha_cache.clear()
        for wme in amem.wmes:
            info = self._wme_info[wme]
            info[0] = [other for other in info[0] if other is not amem]  # may be shared

    # ----- building -----

    def _build_scope(self, elements: tuple[ConditionElement, ...], parent: _Node,
                     var_pos: dict[str, int], nvals: int, scope: set[str],
                     singletons: set[str], states: set[str], runs: bool = False
                     ) -> tuple[_Node, list[tuple[int, ...]]]:
        """Build the nodes of ``elements`` below ``parent``; return the bottom node and the
        written indices matched at each token level.  ``runs``: join consecutive independent
        conditions as one node (not inside an NCC subnetwork, whose partner counts levels)."""
        order = _join_order(elements, var_pos, scope, singletons, self._removed_attrs)
        deferred: list[tuple[int, str, str]] = []
        node = parent
        levels: list[tuple[int, ...]] = []
        run: list[tuple[int, _Plan, _AlphaMemory]] = []  # independent conditions to join
        base = nvals  # the parent's number of values when the run started

        def close_run() -> None:
            nonlocal node, base
            if run:
                node = self._run_node(node, run)
                levels.append(tuple(index for index, _, _ in run))
                run.clear()
            base = nvals

        for index in order:
            element = elements[index]
            if isinstance(element, ConjunctiveNegation):
                close_run()
                node = self._build_ncc(element, node, dict(var_pos), nvals, scope, singletons,
                                       set(states))
                levels.append((index,))
                continue
            plan = _plan_condition(element, var_pos, nvals, deferred, states)
            if element.goal is not None and not element.negated:
                states.update(equality_vars(element.id_test))
            amem = self._alpha_memory(plan)
            if runs and not element.negated:
                if run and not _joins_within(plan, base, amem, run):
                    close_run()
                if _joins_within(plan, nvals if not run else base, amem, run):
                    run.append((index, plan, amem))
                    nvals += len(plan.new_fields)
                    continue
            close_run()
            levels.append((index,))
            check = _compile_check(plan.beta)
            if element.negated:
                key: tuple = ("neg", id(amem), plan.index, tuple(plan.beta))
                node = self._child(node, key, lambda p, k, a=amem, pl=plan, c=check:
                                   _NegativeNode(self, p, k, a, pl.index, c), amem)
            else:
                fields = tuple(plan.new_fields)
                key = ("join", id(amem), plan.index, tuple(plan.beta), fields)
                node = self._child(node, key, lambda p, k, a=amem, pl=plan, c=check, f=fields:
                                   _JoinNode(self, p, k, a, pl.index, c, _extender(f)), amem)
                nvals += len(fields)
        close_run()
        if deferred:  # unreachable after check_production; kept as a loud guard
            raise AssertionError(f"relational tests never placed: {deferred}")
        return node, levels

    def _run_node(self, parent: _Node, run: list[tuple[int, _Plan, _AlphaMemory]]) -> _Node:
        """A lone condition is an ordinary join node; two or more make a _RunNode."""
        if len(run) == 1:
            _, plan, amem = run[0]
            fields = tuple(plan.new_fields)
            key: tuple = ("join", id(amem), plan.index, tuple(plan.beta), fields)
            return self._child(parent, key, lambda p, k: _JoinNode(
                self, p, k, amem, plan.index, _compile_check(plan.beta), _extender(fields)),
                amem)
        key = ("run", tuple((id(amem), plan.index, tuple(plan.beta), tuple(plan.new_fields))
                            for _, plan, amem in run))
        node = parent.child_map.get(key)
        if node is not None:
            return node
        members = [(amem, amem.index(plan.index[1]), plan.index[0], _GET[plan.index[1]],
                    _compile_check(plan.beta), tuple(plan.new_fields))
                   for _, plan, amem in run]  # type: ignore[index]
        node = _RunNode(self, parent, key, members)
        parent.children.append(node)
        parent.child_map[key] = node
        for _, _, amem in run:
            amem.link(node)
        for tok in list(parent.tokens):
            node.left_activate(tok)
        return node

    def _child(self, parent: _Node, key: tuple, make: Callable, amem: _AlphaMemory) -> _Node:
        node = parent.child_map.get(key)
        if node is not None:
            return node
        node = make(parent, key)
        parent.children.append(node)
        parent.child_map[key] = node
        amem.link(node)
        for tok in list(parent.tokens):
            node.left_activate(tok)
        return node

    def _build_ncc(self, ncc: ConjunctiveNegation, parent: _Node, var_pos: dict[str, int],
                   nvals: int, scope: set[str], singletons: set[str], states: set[str]
                   ) -> _Node:
        inner_scope = scope | _bound_by(ncc.conditions)
        if not any(isinstance(e, ConjunctiveNegation) for e in ncc.conditions):
            return self._build_query_ncc(ncc, parent, var_pos, nvals, inner_scope, singletons,
                                         states)
        bottom, _ = self._build_scope(ncc.conditions, parent, var_pos, nvals, inner_scope,
                                      singletons, states)
        key = ("ncc", id(bottom))
        node = parent.child_map.get(key)
        if node is not None:
            return node
        node = _NCCNode(self, parent, key)
        partner = _PartnerNode(self, bottom, node, len(ncc.conditions))
        node.partner = partner
        bottom.children.append(partner)
        for tok in list(bottom.tokens):
            partner.left_activate(tok)
        parent.children.append(node)  # after the subnetwork: it must see a token first
        parent.child_map[key] = node
        for tok in list(parent.tokens):
            node.left_activate(tok)
        return node

    def _build_query_ncc(self, ncc: ConjunctiveNegation, parent: _Node,
                         var_pos: dict[str, int], nvals: int, scope: set[str],
                         singletons: set[str], states: set[str]) -> _Node:
        """Plan the inner conditions as for a subnetwork, but keep them as the levels of a
        query (see :class:`_QueryNCCNode`)."""
        order = _join_order(ncc.conditions, var_pos, scope, singletons, self._removed_attrs)
        deferred: list[tuple[int, str, str]] = []
        levels: list[tuple] = []
        shape: list[tuple] = []
        amems: list[_AlphaMemory] = []
        owner_tests: list[list[tuple[Callable, int]]] = []
        width = nvals
        for index in order:
            element = ncc.conditions[index]
            plan = _plan_condition(element, var_pos, nvals, deferred, states)  # type: ignore[arg-type]
            if element.goal is not None and not element.negated:  # type: ignore[union-attr]
                states.update(equality_vars(element.id_test))  # type: ignore[union-attr]
            amem = self._alpha_memory(plan)
            negated = bool(element.negated)  # type: ignore[union-attr]
            fields = () if negated else tuple(plan.new_fields)
            if plan.index is None:
                pos, getter, hashed = -1, None, None
            else:
                pos, field = plan.index
                getter, hashed = _GET[field], amem.index(field)
            equalities: list[tuple[Any, Any]] = (
                [] if plan.index is None else [(plan.index[1], plan.index[0])])
            equalities += [(left[1], right[1]) for left, op, right in plan.beta
                           if op == "=" and left[0] == "w" and right[0] == "v"]
            levels.append((amem.wmes, hashed, pos, getter, _compile_check(plan.beta),
                           fields, negated, tuple(equalities)))
            owner_tests.append([(_GET[field], p) for field, p in equalities if p < width])
            shape.append((id(amem), plan.index, tuple(plan.beta), fields, negated))
            amems.append(amem)
            nvals += len(fields)
        if deferred:  # unreachable after check_production; kept as a loud guard
            raise AssertionError(f"relational tests never placed: {deferred}")
        key = ("query-ncc", tuple(shape))
        node = parent.child_map.get(key)
        if node is not None:
            return node
        node = _QueryNCCNode(self, parent, key, levels, width, amems, owner_tests)
        for k, amem in enumerate(amems):
            amem.listen(node, k)
        parent.children.append(node)
        parent.child_map[key] = node
        for tok in list(parent.tokens):
            node.left_activate(tok)
        return node

    # ----- removing -----

    def _remove_node(self, node: _Node) -> None:
        """Remove a childless node, then its ancestors that are left without children."""
        if node is self._root or node.parent is None or node.children:
            return
        parent = node.parent
        for tok in node.all_tokens():
            if tok.node is not None:
                tok.parent.children.pop(tok, None)
                self._delete_tokens([tok])
        parent.children.remove(node)
        if parent.child_map.get(node.key) is node:
            del parent.child_map[node.key]
        node.parent = None  # marks it removed
        amem = getattr(node, "amem", None)
        if amem is not None:
            amem.unlink(node)
            if not amem.successors and not amem.listeners:
                self._drop_alpha_memory(amem)
        if isinstance(node, _RunNode):
            for amem in node.amems:
                amem.unlink(node)
                if not amem.successors and not amem.listeners and amem.key in self._amems:
                    self._drop_alpha_memory(amem)
        if isinstance(node, _QueryNCCNode):
            for k, amem in enumerate(node.amems):
                amem.unlisten(node, k)
            for amem in dict.fromkeys(node.amems):
                if not amem.successors and not amem.listeners and amem.key in self._amems:
                    self._drop_alpha_memory(amem)
        if isinstance(node, _NCCNode):
            self._remove_node(node.partner)  # type: ignore[arg-type]
        self._remove_node(parent)

    def _delete_children(self, tok: _Token) -> None:
        children = tok.children
        if children:
            tok.children = None
            self._delete_tokens(list(children))

    def _delete_tokens(self, stack: list[_Token]) -> None:
        """Delete tokens (already detached from their parents) and all their descendants.
        A token is marked dead (node None) before its descendants are visited, which an NCC
        owner relies on (see _NCCNode.release).  Join-node tokens, the bulk, are dropped
        inline."""
        info = self._wme_info
        join = _JoinNode
        while stack:
            tok = stack.pop()
            node = tok.node
            if node is None:
                continue
            if type(node) is join:
                del node.tokens[tok]
                if node.index_list:
                    vals = tok.vals
                    for pos, index in node.index_list:
                        key = vals[pos]
                        if type(key) is float:
                            key = (_FLOAT, key)
                        bucket = index[key]
                        del bucket[tok]
                        if not bucket:
                            del index[key]
                record = info.get(tok.wme)
                if record is not None:
                    del record[1][tok]
            else:
                node.forget(tok)
            tok.node = None
            children = tok.children
            if children:
                tok.children = None
                for child in children:  # not stack.extend: compiled, it copies the dict first
                    stack.append(child)


# ---------------------------------------------------------------------------------------------
# The kernel Rete's order of making matches
# ---------------------------------------------------------------------------------------------
#
# Which of several matches made by one WME the kernel fires first is its Rete's order of
# making them (its match-set lists take the newest first).  Measured against soar_sml 9.6:
# a WME enters its alpha memories (* ^attr *) before (* ^attr value); an alpha memory
# right-activates its join nodes oldest first (a new join goes to the tail of the list);
# a join passes a token to its children newest first (a new child goes to the head), and
# all its positive continuations hang below one beta memory, made with the first of them.
# The kernel's join nodes are its own: the conditions in the kernel's order (reorder.py),
# shared by equal prefixes.  This model builds that tree of nodes (no memories, no tokens):
# a production's nodes are numbered when made, and a match's place is the path from the
# join that the WME activated down to the production.


class _KernelNode:
    __slots__ = ("serial", "born", "children", "users")

    def __init__(self, serial: int, born: int) -> None:
        self.serial = serial
        self.born = born  # the timetag counter when it was made
        self.children: dict[object, _KernelNode] = {}
        self.users = 0


_KERNEL_VAR = re.compile(r"<[^<>\s]+>")


def _same_alpha(one: Condition, other: Condition) -> bool:
    """Whether one WME may match both conditions (in one alpha memory or two)."""
    if one.acceptable != other.acceptable:
        return False
    a, b = one.attr_test, other.attr_test
    return not (type(a) is Const and type(b) is Const and not same_symbol(a.value, b.value))


def _node_keys(reorder: Any, ordered: list) -> list[object]:
    """The keys of the kernel's nodes for conditions in the kernel's order: their text with
    the variables numbered in order of appearance, so that equal prefixes share nodes.
    Worked out once per order (``reorder.kernel_conditions`` shares its lists)."""
    hit = _NODE_KEYS.get(id(ordered))
    if hit is not None and hit[0] is ordered:
        return hit[1]
    names: dict[str, str] = {}

    def canonical(text: str) -> str:
        return _KERNEL_VAR.sub(
            lambda m: names.setdefault(m.group(0), f"<{len(names)}>"), text)

    def key(kcond: Any) -> object:
        # A -{...} may hold another -{...}: its key is made of its own conditions' keys.
        if kcond.is_ncc:
            return ("ncc", tuple(key(c) for c in kcond.inner))
        return canonical(reorder.format_kcond(kcond))

    keys: list[object] = [key(kcond) for kcond in ordered]
    if len(_NODE_KEYS) >= 4096:
        _NODE_KEYS.clear()
    _NODE_KEYS[id(ordered)] = (ordered, keys)
    return keys


_NODE_KEYS: dict[int, tuple[list, list[object]]] = {}


def prefix_tokens(ordered: list, count: int, pool: Callable[[Condition], list[WME]],
                  order: tuple[int, ...], one: bool = False) -> list[tuple]:
    """The tokens of the kernel's beta memory above its ``count``-th condition (in
    ``ordered``, the kernel's order: ``reorder.KCond``s), as ``introspect`` counts partial
    matches: each token as the WMEs of the positive conditions whose written indexes are
    ``order``. ``pool``: the WMEs a condition may match (a superset: those with its
    attribute); ``one``: at most one token. The negations and conjunctive negations right
    above the join are not tested: the kernel's negative and NCC nodes, which are then the
    join's parent, keep the tokens they block in their memory too."""
    while count and (ordered[count - 1].negated or ordered[count - 1].is_ncc):
        count -= 1  # a negative or NCC node holds its blocked tokens too (no beta memory)
    tokens: list[PartialMatch] = [({}, ())]
    indexes: list[int] = []  # the written index of each positive condition joined
    for k, kcond in enumerate(ordered[:count]):
        element = kcond.element
        if kcond.negated or kcond.is_ncc:
            inner: list[WME] = []
            for cond in (element.conditions if kcond.is_ncc else (element,)):
                inner += pool(cond)
            tokens = [t for t in tokens if not negation_matches(element, inner, t[0])]
        else:
            tokens = join_condition(element, tokens, pool(element), one and k == count - 1)
            indexes.append(kcond.index)
        if not tokens:
            return []
    found: list[tuple] = []
    for _, pairs in tokens:
        by_index: dict[int, WME] = {}
        for index, (_, wme) in zip(indexes, pairs, strict=True):
            by_index.setdefault(index, wme)
        found.append(tuple([by_index.get(j) for j in order]))
    return found


class KernelOrder:
    """The kernel's node tree for the loaded productions (see above).  ``add`` gives, per
    written condition index of a positive condition, ``(kernel position, written indexes
    of the positive conditions before it, when its join was made, path key)``: the match
    a WME makes through that condition is made in the order of the path keys, except that
    a join whose parent memory was empty is unlinked from its alpha memory and relinked
    at the tail when the memory gets a token: its place is then the newest WME of the
    conditions before it, when that is newer than the join (``Agent._kernel_key``).  The
    tuple also holds the twin conditions, the condition's kernel position, when the
    production was loaded (its matches of older WMEs were made then, in loading order),
    and the path below the join cut at each positive join after it, with that join's
    written index in between: the kernel passes each token down to every child before it
    makes the next, so the matches one activation makes are ordered depth first
    (``Agent._token_order``)."""

    def __init__(self) -> None:
        from sann.soar import reorder

        self._reorder: Any = reorder  # a module (mypyc: an attribute of module type fails)
        self._ages: dict[tuple[type, object], int] = {
            (str, s): i for i, s in enumerate(reorder._PREDEFINED)}
        self._serial = 0
        self._top = _KernelNode(0, 0)
        self._paths: dict[str, list[tuple[_KernelNode, object, _KernelNode]]] = {}
        self._places: dict[str, dict[int, tuple]] = {}
        self._ordered: dict[str, list] = {}

    def ordered(self, name: str) -> list | None:
        """The production's conditions in the kernel's order (``reorder.KCond``)."""
        return self._ordered.get(name)

    def _node(self, parent: _KernelNode, key: object,
              path: list[tuple[_KernelNode, object, _KernelNode]], now: int) -> _KernelNode:
        node = parent.children.get(key)
        if node is None:
            self._serial += 1
            node = parent.children[key] = _KernelNode(self._serial, now)
        node.users += 1
        path.append((parent, key, node))
        return node

    def add(self, production: Production, now: int
            ) -> dict[int, tuple[int, tuple[int, ...], int, tuple[int, ...]]]:
        reorder = self._reorder
        for value in reorder._constants(production):
            self._ages.setdefault((type(value), value), len(self._ages))
        ordered = reorder.kernel_conditions(production, self._ages, {})
        self._ordered[production.name] = ordered
        path: list[tuple[_KernelNode, object, _KernelNode]] = []
        node, is_join = self._top, False
        joins: list[tuple[int, int, int]] = []  # (written index, kernel position, path length)
        for position, (kcond, key) in enumerate(zip(ordered, _node_keys(reorder, ordered),
                                                    strict=True)):
            parent = node
            positive = not kcond.negated and not kcond.is_ncc
            if positive and is_join:
                parent = self._node(node, "memory", path, now)
            node = self._node(parent, key, path, now)
            if positive:
                joins.append((kcond.index, position, len(path)))
            is_join = positive
        self._serial += 1
        pnode = _KernelNode(self._serial, now)
        node.children[("p", production.name)] = pnode
        pnode.users = 1
        path.append((node, ("p", production.name), pnode))
        self._paths[production.name] = path
        below = [-step[2].serial for step in path]
        conditions = production.conditions
        places: dict[int, tuple] = {}
        for k, (index, position, length) in enumerate(joins):
            if index not in places:
                join = path[length - 1][2]
                before = tuple(dict.fromkeys(j[0] for j in joins[:k]))
                cond = conditions[index]
                mask = ((2 if type(cond.attr_test) is Const else 0)  # type: ignore[union-attr]
                        | (4 if type(cond.value_test) is Const else 0))  # type: ignore[union-attr]
                twins = tuple(j for j, _, _ in joins if j != index
                              and _same_alpha(cond, conditions[j]))  # type: ignore[arg-type]
                # the path below the join cut at each positive join after it, with the
                # written index of that join's condition (for the depth-first order)
                steps: list[object] = []
                start = length
                for later, _, later_length in joins[k + 1:]:
                    steps.append(tuple(below[start:later_length]))
                    steps.append(later)
                    start = later_length
                steps.append(tuple(below[start:]))
                places[index] = (mask, before, join.born, (join.serial, *below[length:]),
                                 twins, position, pnode.born, tuple(steps))
        self._places[production.name] = places  # shared with the caller: see restart
        return places

    def with_kernel_relations(self, production: Production) -> Production:
        """``production`` with its relational tests where the kernel's Rete runs them
        (``reorder.with_kernel_relations``; call after ``add``, which ages its constants)."""
        return self._reorder.with_kernel_relations(production, self._ages)

    def restart(self) -> None:
        """Working memory was emptied (init-soar): every join counts as made before it."""
        stack = [self._top]
        while stack:
            node = stack.pop()
            node.born = 0
            stack.extend(node.children.values())
        for places in self._places.values():
            for index, place in list(places.items()):
                places[index] = (*place[:2], 0, *place[3:6], 0, *place[7:])

    def remove(self, name: str) -> None:
        self._places.pop(name, None)
        self._ordered.pop(name, None)
        for parent, key, node in reversed(self._paths.pop(name, [])):
            node.users -= 1
            if node.users <= 0:
                del parent.children[key]
