"""Whether two chunks are the same rule up to variable names: conditions, the conditions of
a conjunctive negation, and actions in any order, and a relational test between two
variables on either of them (``{ <j> < <k> }`` on one condition is ``{ <k> > <j> }`` on
the other's). This is how a chunk of this engine is compared with the kernel's, whose
printer groups a chunk's actions by identifier, orders its conditions by its own costs and
moves such tests to the condition its order binds last."""

from __future__ import annotations

from dataclasses import replace

from ..production import (
    Condition,
    Conjunction,
    ConjunctiveNegation,
    Production,
    Relational,
    Test,
    Var,
    _match_elements,
    duplicate_key,
    shape,
)

_INVERSE = {"<": ">", ">": "<", "<=": ">=", ">=": "<=", "<>": "<>", "<=>": "<=>"}
Constraint = tuple[str, str, str]


def same_chunk(a: Production, b: Production) -> bool:
    (a, ca), (b, cb) = _canonical(a), _canonical(b)
    if duplicate_key(a)[0] != duplicate_key(b)[0] or len(ca) != len(cb):
        return False
    mapping: dict[str, str] = {}
    reverse: dict[str, str] = {}
    if not _match_elements(list(a.conditions), list(b.conditions), mapping, reverse):
        return False
    if not _match_elements(list(a.actions), list(b.actions), mapping, reverse):
        return False
    wanted = set(cb)
    for left, op, right in ca:
        x, y = mapping.get(left), mapping.get(right)
        if (x, op, y) not in wanted and (y, _INVERSE[op], x) not in wanted:
            return False
    return True


def _canonical(production: Production) -> tuple[Production, list[Constraint]]:
    """The production with each conjunctive negation's conditions in one order and the
    relational tests between two variables of its positive conditions taken out."""
    constraints: list[Constraint] = []
    conditions = []
    for cond in production.conditions:
        if isinstance(cond, ConjunctiveNegation):
            cond = ConjunctiveNegation(tuple(sorted(cond.conditions, key=lambda x: repr(shape(x)))))
        elif isinstance(cond, Condition) and not cond.negated:
            cond = Condition(_strip(cond.id_test, constraints),
                             _strip(cond.attr_test, constraints),
                             _strip(cond.value_test, constraints),
                             cond.negated, cond.acceptable, cond.goal)
        conditions.append(cond)
    return replace(production, conditions=tuple(conditions)), constraints


def _strip(test: Test, constraints: list[Constraint]) -> Test:
    if not isinstance(test, Conjunction):
        return test
    holder = next((t.name for t in test.tests if isinstance(t, Var)), None)
    if holder is None:
        return test
    kept: list[Test] = []
    for part in test.tests:
        if (isinstance(part, Relational) and isinstance(part.operand, Var)
                and part.op in _INVERSE):
            constraints.append((holder, part.op, part.operand.name))
        else:
            kept.append(part)
    return kept[0] if len(kept) == 1 else Conjunction(tuple(kept))
