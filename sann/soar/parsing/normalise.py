"""The kernel's rewriting of conditions as it loads a production, and its names for the
variables it makes up.

- Fresh variables: a ``^a.b.c`` path becomes a chain through fresh variables, a missing value
  or identifier test a fresh variable. They are named like the kernel's (``<a*1>``, ``<b*1>``:
  the first letter of the attribute and a counter per letter that skips names the production
  already uses, `fresh_names`), once the whole production is known.
- A relational test of a positive condition on a variable nothing binds is dropped
  (`drop_unbound_relations`), and the negation of one conjunctive negation is its conditions
  (`negate`).

Known difference from the kernel's naming: the kernel also adds a fresh equality variable to
an attribute or value test that has none (``^b << x y >>`` prints as ``^b { << x y >> <b*1> }``)
which shifts its counters; we keep such tests as written.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from sann.soar.matching.variables import equality_vars
from sann.soar.production import (
    Action,
    CallAction,
    Condition,
    ConditionElement,
    Conjunction,
    ConjunctiveNegation,
    Const,
    FuncCall,
    MakeAction,
    Relational,
    RhsValue,
    Test,
    Var,
)

__all__ = [
    "TEMPORARY",
    "drop_unbound_relations",
    "first_letter",
    "fresh_names",
    "lhs_bound",
    "negate",
    "rename_action",
    "rename_element",
]

# Fresh variables get a temporary name no user variable can have (NUL is not a constituent
# character) and are renamed to the kernel's `<a*1>` names once the whole production is known,
# so that the final names skip every name the production already uses.
TEMPORARY = "\0"


def first_letter(value: object) -> str:
    """The letter Soar names a fresh variable after (``^block.top`` gives ``<b*1>``)."""
    if isinstance(value, Var):
        letter = value.name[:1]
        return letter if letter.isalnum() else "v"
    if isinstance(value, Const):
        if isinstance(value.value, bool) or not isinstance(value.value, str):
            return "i" if isinstance(value.value, int) else "f"
        letter = value.value[:1].lower()
        return letter if letter.isalpha() else "v"
    if isinstance(value, Conjunction):
        for test in value.tests:
            if isinstance(test, Var | Const):
                return first_letter(test)
    return "v"


def negate(elements: list[ConditionElement]) -> list[ConditionElement]:
    """``-`` before a condition or group, as the kernel does it: one condition flips its
    sign (``-(<s> -^a b)`` is positive), one conjunctive negation gives back its conditions
    (``-(<s> -^a.b c)`` is ``(<s> ^a <a*1>) (<a*1> ^b c)``, measured in soar_sml 9.6);
    several become a conjunctive negation."""
    if len(elements) == 1 and isinstance(elements[0], Condition):
        only = elements[0]
        return [dataclasses.replace(only, negated=not only.negated)]
    if len(elements) == 1 and isinstance(elements[0], ConjunctiveNegation):
        return list(elements[0].conditions)
    return [ConjunctiveNegation(tuple(elements))] if elements else []


def drop_unbound_relations(
    elements: tuple[ConditionElement, ...], outer: set[str], fresh: Callable[[str], Var]
) -> tuple[ConditionElement, ...]:
    """The conditions without the relational tests of positive conditions on variables that
    no positive condition of their scope binds: the kernel drops them silently (measured in
    soar_sml 9.6: ``(state <s> ^c < <y>)`` with ``<y>`` bound nowhere, or only inside a
    negation, loads and prints as ``(state <s> ^c <c*1>)``, and matches any ``^c``). A field
    left with no test gets a fresh variable, as the kernel's does. Negated conditions keep
    theirs: the kernel refuses those (`rete.check_production`)."""
    bound = outer | lhs_bound(elements)
    kept: list[ConditionElement] = []
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            inner = drop_unbound_relations(element.conditions, bound, fresh)
            kept.append(ConjunctiveNegation(inner))
        elif element.negated:
            kept.append(element)
        else:
            letter = first_letter(element.attr_test)
            kept.append(dataclasses.replace(
                element,
                id_test=_without_unbound(element.id_test, bound, "s", fresh),
                attr_test=_without_unbound(element.attr_test, bound, "a", fresh),
                value_test=_without_unbound(element.value_test, bound, letter, fresh),
            ))
    return tuple(kept)


def _without_unbound(test: Test, bound: set[str], letter: str, fresh: Callable[[str], Var]) -> Test:
    """``test`` without its relational tests on variables outside ``bound``."""
    if _compares_unbound(test, bound):
        return fresh(letter)
    if not isinstance(test, Conjunction):
        return test
    kept = tuple(t for t in test.tests if not _compares_unbound(t, bound))
    if len(kept) == len(test.tests):
        return Conjunction(tuple(_without_unbound(t, bound, letter, fresh) for t in kept))
    if not kept:
        return fresh(letter)
    return kept[0] if len(kept) == 1 else Conjunction(kept)


def _compares_unbound(test: Test, bound: set[str]) -> bool:
    return (
        isinstance(test, Relational)
        and isinstance(test.operand, Var)
        and test.operand.name not in bound
    )


def lhs_bound(elements: tuple[ConditionElement, ...]) -> set[str]:
    """Variables bound by equality tests of the positive conditions of one scope."""
    bound: set[str] = set()
    for element in elements:
        if isinstance(element, Condition) and not element.negated:
            for test in (element.id_test, element.attr_test, element.value_test):
                bound.update(equality_vars(test))
    return bound


def fresh_names(temporary: list[str], used: set[str]) -> dict[str, str]:
    """The kernel's names for fresh variables: ``<letter*n>``, n counting per letter from 1
    in creation order and skipping names the production already uses."""
    counters: dict[str, int] = {}
    names: dict[str, str] = {}
    for name in temporary:
        letter = name.rsplit(TEMPORARY, 1)[1]
        while True:
            counters[letter] = counters.get(letter, 0) + 1
            candidate = f"{letter}*{counters[letter]}"
            if candidate not in used:
                break
        names[name] = candidate
    return names


# Renaming is written out per type: it runs on most productions (every path and missing value
# makes a fresh variable), and a generic walk over dataclass fields costs several times more.


def _rename_var(var: Var, names: dict[str, str]) -> Var:
    return Var(names[var.name]) if var.name in names else var


def _rename_test(test: Test, names: dict[str, str]) -> Test:
    if isinstance(test, Var):
        return _rename_var(test, names)
    if isinstance(test, Conjunction):
        return Conjunction(tuple(_rename_test(t, names) for t in test.tests))
    if isinstance(test, Relational) and isinstance(test.operand, Var):
        return Relational(test.op, _rename_var(test.operand, names))
    return test


def rename_element(element: ConditionElement, names: dict[str, str]) -> ConditionElement:
    if isinstance(element, ConjunctiveNegation):
        return ConjunctiveNegation(tuple(rename_element(c, names) for c in element.conditions))
    return Condition(
        _rename_test(element.id_test, names),
        _rename_test(element.attr_test, names),
        _rename_test(element.value_test, names),
        element.negated,
        element.acceptable,
        element.goal,
    )


def _rename_call(call: FuncCall, names: dict[str, str]) -> FuncCall:
    return FuncCall(call.name, tuple(_rename_value(a, names) for a in call.args))


def _rename_value(value: RhsValue, names: dict[str, str]) -> RhsValue:
    if isinstance(value, Var):
        return _rename_var(value, names)
    if isinstance(value, FuncCall):
        return _rename_call(value, names)
    return value


def rename_action(action: Action, names: dict[str, str]) -> Action:
    if isinstance(action, CallAction):
        return CallAction(_rename_call(action.call, names))
    referent = action.referent
    return MakeAction(
        _rename_var(action.id, names),
        _rename_value(action.attr, names),
        _rename_value(action.value, names),
        action.preference,
        None if referent is None else _rename_value(referent, names),
    )
