"""The order in which the Rete joins a production's conditions.

Constant tests and checks first, then joins hashed on a bound value, then fan-out over
multi-valued attributes, following the most recently reached object; negations as soon as
their variables are bound; existence tests such as ``(<s> ^step)`` and volatile attributes
(those rules remove) last.
"""

from __future__ import annotations

from collections.abc import Iterator

from sann.soar.matching.variables import condition_fields, equality_vars, mentioned, relational_vars
from sann.soar.production import (
    Condition,
    ConditionElement,
    ConjunctiveNegation,
    Const,
    Production,
    Test,
    Var,
)


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
    own = set().union(*(equality_vars(t) for t in condition_fields(cond)))
    pending = set().union(*(relational_vars(t) for t in condition_fields(cond))) - bound - own
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


def const_attributes(elements: tuple[ConditionElement, ...]) -> set[object]:
    """The constant attributes tested anywhere in ``elements`` (nested negations too)."""
    found: set[object] = set()
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            found |= const_attributes(element.conditions)
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


def singletons(production: Production) -> set[str]:
    """Variables that occur once in the whole production (conditions and actions)."""
    counts: dict[str, int] = {}
    for name in _variables_of((production.conditions, production.actions)):
        counts[name] = counts.get(name, 0) + 1
    return {name for name, count in counts.items() if count == 1}


def join_order(elements: tuple[ConditionElement, ...], bound: dict[str, int], scope: set[str],
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
            for test in condition_fields(element):
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
            if (mentioned(element) & scope) <= age.keys():
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
