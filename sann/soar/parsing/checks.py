"""Load-time semantic checks of a production: what the kernel refuses or warns about.

``check_production`` refuses what no matcher can run (a relational test on a variable never
bound, a condition whose identifier is a constant, with ``links=True`` a condition not linked
to a state); ``kernel_refusals`` refuses what the Soar 9.6 kernel refuses although we could
run it; ``load_warnings`` lists what the kernel loads with a warning.
"""

from __future__ import annotations

from collections.abc import Iterable

from sann.soar.errors import SoarSemanticError
from sann.soar.matching.symbols import RELATIONS
from sann.soar.matching.variables import (
    atoms,
    bound_by,
    condition_fields,
    equality_vars,
    relational_vars,
)
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


def _validate_test(production: Production, test: Test) -> None:
    if isinstance(test, Conjunction):
        for inner in test.tests:
            _validate_test(production, inner)
    elif isinstance(test, Relational):
        if test.op not in RELATIONS:
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
    bound = outer_bound | bound_by(elements)
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
    for test in condition_fields(cond):
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
    for inner in atoms(test):
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
    bound = outer | bound_by(elements)
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            _check_negated_relations(production, element.conditions, bound)
        elif element.negated:
            _check_relations(production, element, bound)


def _check_relations(production: Production, cond: Condition, bound: set[str]) -> None:
    """Every relational test of ``cond`` compares with a variable in ``bound``."""
    for test in condition_fields(cond):
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
                bound.update(*(equality_vars(test) for test in condition_fields(cond)))
                placed = True
    if waiting:
        found.append("the LHS conditions are not all connected")
    inner_outer = outer | bound_by(elements)
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            _scope_warnings(element.conditions, inner_outer, found, top=False)
