"""Which variables a field test, a condition or a condition list binds or mentions.

The load-time checks, the join planner, the brute-force oracle and the kernel-order model all
ask these questions of the parsed conditions.
"""

from __future__ import annotations

from collections.abc import Iterable

from sann.soar.production import (
    Condition,
    ConditionElement,
    Conjunction,
    ConjunctiveNegation,
    Relational,
    Test,
    Var,
)


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


def condition_fields(cond: Condition) -> tuple[Test, Test, Test]:
    return cond.id_test, cond.attr_test, cond.value_test


def bound_by(conditions: Iterable[ConditionElement]) -> set[str]:
    """Variables bound by the positive conditions among ``conditions`` (not nested)."""
    names: set[str] = set()
    for element in conditions:
        if isinstance(element, Condition) and not element.negated:
            for test in condition_fields(element):
                names.update(equality_vars(test))
    return names



def atoms(test: Test) -> list[Test]:
    """A field test as a flat list of Var / Const / Relational / Disjunction."""
    if isinstance(test, Conjunction):
        out: list[Test] = []
        for inner in test.tests:
            out.extend(atoms(inner))
        return out
    return [test]


def mentioned(element: ConditionElement) -> set[str]:
    """Every variable a condition element mentions (equality or relational, nested)."""
    if isinstance(element, ConjunctiveNegation):
        return set().union(*(mentioned(e) for e in element.conditions))
    names: set[str] = set()
    for test in condition_fields(element):
        names.update(equality_vars(test))
        names.update(relational_vars(test))
    return names
