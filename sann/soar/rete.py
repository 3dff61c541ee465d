"""Matching productions against working memory.

Two matchers with one interface (see notes/RETE-API.md):

- :class:`Rete` — the Doorenbos (1995) Rete: an alpha network hashed on constant attribute
  and value tests, hashed beta joins, negative and conjunctive-negation (NCC) nodes, shared
  prefixes, tree-based removal.  Adding or removing a WME costs in proportion to the alpha
  memories and tokens it touches, not to the size of working memory.
- :class:`BruteForceMatcher` — a naive join over all WMEs, written to be obviously correct.
  It is the oracle of the property tests.

Matching follows the real Soar 9.6 kernel (checked with ``soar_sml``):

- constants and variables compare as Soar symbols: ``1``, ``1.0`` and ``|1|`` are three
  different symbols (equality requires the same Python type);
- ``< > <= >=`` use Soar's total order: identifiers (by letter, then number) before numbers
  (compared numerically, ints with floats) before strings (compared as strings);
- ``<>`` is symbol inequality, ``<=>`` "same type", ``@`` never holds and ``!@`` always holds
  (there are no long-term identifiers here).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator

from sann.soar.errors import SoarSemanticError
from sann.soar.memory import WME, Identifier, Symbol
from sann.soar.production import (
    Condition,
    ConditionElement,
    Conjunction,
    ConjunctiveNegation,
    Const,
    Disjunction,
    Production,
    Relational,
    Test,
    Var,
)

__all__ = ["BruteForceMatcher", "Match", "Rete", "check_production", "symbol_order_less"]


# ---------------------------------------------------------------------------------------------
# Symbols: equality and Soar's order
# ---------------------------------------------------------------------------------------------


def same_symbol(a: object, b: object) -> bool:
    """Soar symbol equality: same type and same value (identifiers by identity)."""
    return a.__class__ is b.__class__ and a == b


def _rank(value: object) -> int:
    cls = value.__class__
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


_RELATIONS: dict[str, Callable[[Symbol, Symbol], bool]] = {
    "<>": lambda a, b: not (a.__class__ is b.__class__ and a == b),
    "<": symbol_order_less,
    ">": lambda a, b: symbol_order_less(b, a),
    "<=": _less_equal,
    ">=": lambda a, b: _less_equal(b, a),
    "<=>": lambda a, b: a.__class__ is b.__class__,
    "@": lambda a, b: False,
    "!@": lambda a, b: True,
}


# ---------------------------------------------------------------------------------------------
# Matches
# ---------------------------------------------------------------------------------------------


class Match:
    """One instantiation of a production.

    Compared and hashed by identity: the object reported as retracted is the same object
    that was reported when the match appeared.  ``wmes`` has one entry per top-level
    condition element in written order (``None`` for negations); ``bindings`` maps every
    variable bound by the positive conditions (name without brackets) to its value.  The
    Rete computes both lazily from its token, since many matches are never looked at.
    """

    __slots__ = ("production", "_wmes", "_bindings", "_token", "_layout")

    def __init__(
        self,
        production: Production,
        wmes: tuple[WME | None, ...] | None = None,
        bindings: dict[str, Symbol] | None = None,
    ) -> None:
        self.production = production
        self._wmes = wmes
        self._bindings = bindings
        self._token: object = None
        self._layout: object = None

    @property
    def wmes(self) -> tuple[WME | None, ...]:
        if self._wmes is None:
            self._wmes = self._layout.wmes_of(self._token)  # type: ignore[union-attr]
        return self._wmes

    @property
    def bindings(self) -> dict[str, Symbol]:
        if self._bindings is None:
            self._bindings = self._layout.bindings_of(self._token)  # type: ignore[union-attr]
        return self._bindings

    def __repr__(self) -> str:
        return f"Match({self.production.name}, {list(self.wmes)})"


class _Changes:
    """New and retracted matches since the last ``take_changes``; an appear/retract pair
    inside one interval cancels out."""

    __slots__ = ("added", "removed")

    def __init__(self) -> None:
        self.added: dict[Match, None] = {}
        self.removed: dict[Match, None] = {}

    def appear(self, match: Match) -> None:
        self.added[match] = None

    def retract(self, match: Match) -> None:
        if match in self.added:
            del self.added[match]
        else:
            self.removed[match] = None

    def take(self) -> tuple[list[Match], list[Match]]:
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
    outer_bound: set[str],
) -> None:
    """Check linkage and bound relational variables of one scope (the production, or the
    inside of a conjunctive negation, whose own positive conditions bind local variables)."""
    bound = outer_bound | _bound_by(elements)
    linked = set(outer_linked)
    positives = [e for e in elements if isinstance(e, Condition) and not e.negated]
    for cond in positives:
        if cond.goal is not None:
            linked.update(equality_vars(cond.id_test))
    grown = True
    while grown:
        grown = False
        for cond in positives:
            if linked.intersection(equality_vars(cond.id_test)):
                new = set(equality_vars(cond.attr_test) + equality_vars(cond.value_test))
                if not new <= linked:
                    linked |= new
                    grown = True
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            if not element.conditions:
                raise SoarSemanticError(production.name, "empty conjunctive negation -{ }",
                                        production.location)
            _check_scope(production, element.conditions, linked, bound)
            continue
        _check_condition(production, element, linked, bound)


def _check_condition(
    production: Production, cond: Condition, linked: set[str], bound: set[str]
) -> None:
    name = production.name
    for test in _fields(cond):
        _validate_test(production, test)
    ids = equality_vars(cond.id_test)
    if not ids:
        raise SoarSemanticError(name, f"the identifier of condition {_show(cond)} must be a "
                                "variable", production.location)
    if not linked.intersection(ids):
        raise SoarSemanticError(name, f"condition {_show(cond)} is not linked to a state: "
                                f"<{ids[0]}> is not reachable from a state or impasse "
                                "condition", production.location)
    scope = bound
    if cond.negated:
        scope = bound.union(*(equality_vars(t) for t in _fields(cond)))
    for test in _fields(cond):
        for var in relational_vars(test):
            if var not in scope:
                raise SoarSemanticError(name, f"variable <{var}> in a relational test of "
                                        f"{_show(cond)} is never bound", production.location)


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


def check_production(production: Production) -> None:
    """Raise :class:`SoarSemanticError` naming the production when it cannot be matched.

    The first condition must be a positive ``state``/``impasse`` condition, every
    condition's identifier must be reachable from a state through positive conditions,
    and every variable used in a relational test must be bound (by a positive condition,
    or — inside a negation — locally by the negation itself).  A variable that appears only
    inside a negation is legal: it is local to the negation.
    """
    conditions = production.conditions
    first = conditions[0] if conditions else None
    if not isinstance(first, Condition) or first.negated or first.goal is None:
        raise SoarSemanticError(production.name, "the first condition must test a state: "
                                "(state <s> ...) or (impasse <s> ...)", production.location)
    _check_scope(production, conditions, set(), set())


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
        if any(_negation_matches(n, wmes, full) for n in negations):
            continue
        yield list(chosen), full


def _negation_matches(element: ConditionElement, wmes: list[WME],
                      bindings: dict[str, Symbol]) -> bool:
    if isinstance(element, ConjunctiveNegation):
        inner = element.conditions
    else:
        inner = (Condition(element.id_test, element.attr_test, element.value_test,
                           acceptable=element.acceptable, goal=element.goal),)
    return next(brute_force_solutions(inner, wmes, bindings), None) is not None


class BruteForceMatcher:
    """Naive matcher: recomputes every production's matches from scratch when asked.

    Quadratic and slow by design: it is obviously correct, which makes it the oracle for
    the Rete's property tests.
    """

    def __init__(self) -> None:
        self._productions: dict[str, Production] = {}
        self._wmes: dict[WME, None] = {}
        self._current: dict[str, dict[tuple[WME | None, ...], Match]] = {}
        self._changes = _Changes()
        self._dirty = False

    def add_production(self, production: Production) -> None:
        if production.name in self._productions:
            raise SoarSemanticError(production.name, "a production with this name exists",
                                    production.location)
        check_production(production)
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

    def take_changes(self) -> tuple[list[Match], list[Match]]:
        self._refresh()
        return self._changes.take()

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


#: Until the Rete lands, the brute-force matcher serves under its name (same interface).
Rete = BruteForceMatcher
