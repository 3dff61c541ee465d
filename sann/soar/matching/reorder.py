"""The Soar 9.6 kernel's order of a production's conditions, for the inspection commands.

Our Rete joins conditions in its own order; the kernel reorders them when it adds a rule
(reorder.cpp) and ``matches``, ``preferences --timetags`` and the match-set listings show
them, and their WMEs, in that order. This module reproduces the order as measured against
``soar_sml`` 9.6 — it is never used for matching, so no hot path pays for it:

- cost of a positive condition: unbound identifier -> MAX; value bound or constant -> 1;
  while a root state variable is still unbound -> 8 for anything else; once all roots are
  bound: unbound variable attribute -> 9, an acceptable-preference test -> 2, else one more
  than the attribute's ``multi-attributes`` count (default 1) (relative costs measured).
  Negations and conjunctive negations cost 0 once their outer variables are bound, else
  MAX.
- cheapest first. Ties above 1 look one condition ahead (the cheapest condition that could
  follow); remaining ties go to the condition whose attribute (then value) symbol the
  kernel made last, else to the later-written condition. Ties at 1 or below go to the
  newest symbol, else to the later-written condition.

Symbol age: the kernel numbers symbols as it creates them; the architecture's own symbols
(measured order, ``PREDEFINED``) are older than any rule's, and a rule's constants are as
old as the first loaded rule that wrote them.

The kernel's parser also gives every value test without an equality test a variable (``^a >
3`` becomes ``^a { > 3 <a*1> }``, numbered per first letter in written order, shared with
dot-notation and missing-value variables), and the Rete moves a relational test on a
variable bound only later into the condition that binds it (``<`` becomes ``>``).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field, replace

from sann.soar.printer import format_constant
from sann.soar.production import (
    Action,
    CallAction,
    Condition,
    ConditionElement,
    Conjunction,
    ConjunctiveNegation,
    Const,
    Disjunction,
    FuncCall,
    Production,
    Relational,
    Test,
    Var,
)

MAX_COST = 10_000_005
BRANCHING = 8  # the kernel's branching factor for what it cannot estimate

#: Symbols the 9.6 kernel makes before any rule, oldest first (measured by which of two
#: tied conditions it orders first).
PREDEFINED = (
    "problem-space state operator superstate io object attribute impasse choices none "
    "constraint-failure no-change multiple item-count non-numeric-count conflict tie item "
    "non-numeric quiescence t nil type goal name input-link output-link reward-link reward "
    "value epmem command result retrieved status memory-id present-id graph-match success "
    "failure bad-cmd retrieve query neg-query before after prohibit yes no smem depth store "
    "math-query less-or-equal greater-or-equal max min count dont-learn force-learn halt "
    "link-stm-to-ltm wait write log capitalize-symbol crlf make-constant-symbol strlen "
    "timestamp trim string accept deep-copy ifeq + * - / div size sum product mod set-count "
    "sin cos atan2 sqrt abs int float round-off-heading round-off compute-heading "
    "compute-range rand-int rand-float svs spatial-scene child id interrupt concat exec cmd"
).split()

_INVERSE = {"<": ">", ">": "<", "<=": ">=", ">=": "<=", "<>": "<>", "<=>": "<=>"}
_GENSYM = re.compile(r"^([a-z])\*\d+$")


def symbol_ages(productions: Iterable[Production]) -> dict[tuple[type, object], int]:
    """Creation rank of every constant the rules mention (bigger = made later)."""
    ages: dict[tuple[type, object], int] = {(str, s): i for i, s in enumerate(PREDEFINED)}
    for production in productions:
        for value in constants(production):
            ages.setdefault((type(value), value), len(ages))
    return ages


def constants(production: Production) -> Iterator[object]:
    yield production.name
    yield from _condition_constants(production)
    for action in production.actions:
        yield from _action_constants(action)


def _condition_constants(production: Production) -> Iterator[object]:
    for element in production.conditions:
        yield from _element_constants(element)


def _element_constants(element: ConditionElement) -> Iterator[object]:
    if isinstance(element, ConjunctiveNegation):
        for inner in element.conditions:
            yield from _element_constants(inner)
        return
    for test in (element.id_test, element.attr_test, element.value_test):
        yield from _test_constants(test)


def _test_constants(test: Test) -> Iterator[object]:
    if isinstance(test, Const):
        yield test.value
    elif isinstance(test, Relational):
        yield from _test_constants(test.operand)
    elif isinstance(test, Disjunction):
        yield from (c.value for c in test.values)
    elif isinstance(test, Conjunction):
        for inner in test.tests:
            yield from _test_constants(inner)


def _action_constants(action: Action) -> Iterator[object]:
    values = [action.call] if isinstance(action, CallAction) else [
        action.attr, action.value, action.referent]
    stack = [v for v in values if v is not None]
    while stack:
        value = stack.pop(0)
        if isinstance(value, Const):
            yield value.value
        elif isinstance(value, FuncCall):
            stack[:0] = list(value.args)


@dataclass
class KCond:
    """One condition as the kernel holds it: ``index`` is its top-level element in the
    production (what ``Match.wmes`` is indexed by); ``fields`` the printable id, attribute
    and value tests after the kernel's rewriting; ``inner`` the members of a ``-{...}``."""

    element: ConditionElement
    index: int
    negated: bool = False
    fields: list[list[str]] = field(default_factory=list)
    goal: str | None = None
    inner: list[KCond] = field(default_factory=list)

    @property
    def is_ncc(self) -> bool:
        return isinstance(self.element, ConjunctiveNegation)


class _Namer:
    """The kernel parser's variable numbering: ``<x*N>`` counted per first letter, in
    written order, for dot-notation, missing values and tests without an equality."""

    def __init__(self) -> None:
        self.counts: dict[str, int] = {}
        self.renamed: dict[str, str] = {}

    def new(self, hint: str) -> str:
        letter = hint[:1].lower() if hint[:1].isalpha() else "v"
        self.counts[letter] = self.counts.get(letter, 0) + 1
        return f"{letter}*{self.counts[letter]}"

    def name(self, var: str) -> str:
        """A parser-made variable gets the kernel's number on first sight."""
        if not _GENSYM.match(var):
            return var
        if var not in self.renamed:
            self.renamed[var] = self.new(var)
        return self.renamed[var]


def kernel_conditions(production: Production, ages: dict[tuple[type, object], int],
                      multi: dict[str, int]) -> list[KCond]:
    """The production's conditions in the kernel's order, rewritten as the kernel prints
    them (see the module docstring). The order depends only on the production, the ages
    of the constants its conditions test and the ``multi-attributes`` counts, so it is
    worked out once per distinct triple: loading a rule asks twice (its place in the
    kernel's node tree, the relational tests the kernel moves), and every agent loading
    the same rules asks again. The list is shared: callers only read it."""
    keys = [(type(value), value) for value in _condition_constants(production)]
    missing = len(ages)  # what _age gives a constant not yet aged
    known = tuple(ages.get(key, missing) for key in keys)
    multi_counts = tuple(sorted(multi.items()))
    # By identity: equal productions are not interchangeable (the KConds point at their
    # own condition objects, and 1 == 1.0 for dataclass equality).
    cache_key = (id(production), known, multi_counts)
    hit = _ORDERS.get(cache_key)
    if hit is not None and hit[0] is production:
        return hit[1]
    if len(_ORDERS) >= _ORDERS_SIZE:
        _ORDERS.clear()
    ordered = _ordered_conditions(production, dict(zip(keys, known, strict=True)), multi)
    _ORDERS[cache_key] = (production, ordered)
    return ordered


_ORDERS: dict[tuple[int, tuple[int, ...], tuple[tuple[str, int], ...]],
              tuple[Production, list[KCond]]] = {}
_ORDERS_SIZE = 4096


def _ordered_conditions(production: Production, ages: dict[tuple[type, object], int],
                        multi: dict[str, int]) -> list[KCond]:
    """``kernel_conditions`` with the ages of the conditions' constants: the only ages
    ``_canonical`` reads."""
    namer = _Namer()
    conds = [_kcond(e, i, namer) for i, e in enumerate(production.conditions)]
    roots = _roots(production.conditions)
    ordered = _reorder(conds, set(), roots, ages, multi)
    _move_relations(ordered, set())
    _mark_goals(ordered, roots)
    return ordered


def _kcond(element: ConditionElement, index: int, namer: _Namer) -> KCond:
    if isinstance(element, ConjunctiveNegation):
        inner = [_kcond(e, index, namer) for e in element.conditions]
        if len(inner) == 1 and not inner[0].negated and not inner[0].is_ncc:
            inner[0].negated = True  # -{ (one condition) } is a plain negation
            return inner[0]
        return KCond(element, index, negated=True, inner=inner)
    hint = _hint(element.attr_test)
    fields = [_field(t, namer, None) for t in (element.id_test, element.attr_test)]
    fields.append(_field(element.value_test, namer, hint))
    kcond = KCond(element, index, element.negated, fields, element.goal)
    return kcond


def _hint(test: Test) -> str:
    if isinstance(test, Const):
        return str(test.value)
    if isinstance(test, Var):
        return test.name
    if isinstance(test, Conjunction):
        for inner in test.tests:
            if isinstance(inner, Const | Var):
                return _hint(inner)
    return "v"


def _field(test: Test, namer: _Namer, hint: str | None) -> list[str]:
    """Printable parts of a field: the non-equality tests, then the equality test."""
    parts: list[str] = []
    equality: list[str] = []
    for atom in test.tests if isinstance(test, Conjunction) else (test,):
        if isinstance(atom, Var):
            equality.append(f"<{namer.name(atom.name)}>")
        elif isinstance(atom, Const):
            equality.append(_constant(atom.value))
        elif isinstance(atom, Relational):
            operand = atom.operand
            text = (f"<{namer.name(operand.name)}>" if isinstance(operand, Var)
                    else _constant(operand.value))
            parts.append(f"{atom.op} {text}")
        elif isinstance(atom, Disjunction):
            parts.append(" ".join(["<<", *(_constant(c.value) for c in atom.values), ">>"]))
    if not equality and hint is not None:
        equality.append(f"<{namer.new(hint)}>")
    return parts + equality


def _constant(value: object) -> str:
    if isinstance(value, float):
        return f"{value:f}"
    return format_constant(value)  # type: ignore[arg-type]


def _roots(elements: tuple[ConditionElement, ...]) -> list[str]:
    """Variables written with ``state``/``impasse`` that no positive condition reaches."""
    reached = {name for e in elements if isinstance(e, Condition) and not e.negated
               for name in _equality_names(e.value_test)}
    roots: list[str] = []
    for e in elements:
        if isinstance(e, Condition) and e.goal is not None:
            for name in _equality_names(e.id_test):
                if name not in reached and name not in roots:
                    roots.append(name)
    return roots


def _equality_names(test: Test) -> list[str]:
    if isinstance(test, Var):
        return [test.name]
    if isinstance(test, Conjunction):
        return [t.name for t in test.tests if isinstance(t, Var)]
    return []


def _variables(element: ConditionElement) -> set[str]:
    if isinstance(element, ConjunctiveNegation):
        return set().union(*(_variables(e) for e in element.conditions))
    names: set[str] = set()
    for test in (element.id_test, element.attr_test, element.value_test):
        names.update(_equality_names(test))
    return names


def _mentioned(element: ConditionElement) -> set[str]:
    """Every variable a condition tests, relational operands too."""
    if isinstance(element, ConjunctiveNegation):
        return set().union(*(_mentioned(e) for e in element.conditions))
    names: set[str] = set()
    stack: list[Test] = [element.id_test, element.attr_test, element.value_test]
    while stack:
        test = stack.pop()
        if isinstance(test, Var):
            names.add(test.name)
        elif isinstance(test, Relational):
            stack.append(test.operand)
        elif isinstance(test, Conjunction):
            stack.extend(test.tests)
    return names


def _binds(kcond: KCond) -> set[str]:
    """Variables a positive condition binds (all of its equality variables)."""
    if kcond.negated:
        return set()
    return _variables(kcond.element)


def _covered(test: Test, bound: set[str], extra: list[str]) -> bool:
    atoms = test.tests if isinstance(test, Conjunction) else (test,)
    for atom in atoms:
        if isinstance(atom, Const):
            return True
        if isinstance(atom, Var) and (atom.name in bound or atom.name in extra):
            return True
    return False


def _cost(kcond: KCond, bound: set[str], roots: list[str], needs: dict[int, set[str]],
          multi: dict[str, int]) -> int:
    if kcond.negated:
        return 0 if needs[id(kcond)] <= bound else MAX_COST
    cond = kcond.element
    assert isinstance(cond, Condition)
    if not _covered(cond.id_test, bound, roots):
        return MAX_COST
    if _covered(cond.value_test, bound, roots):
        return 1
    if roots:
        return BRANCHING
    if not _covered(cond.attr_test, bound, roots):
        return BRANCHING + 1
    if cond.acceptable:
        return 2
    attr = cond.attr_test
    if isinstance(attr, Const) and isinstance(attr.value, str):
        return multi.get(attr.value, 1) + 1
    return 2


def _canonical(kcond: KCond, ages: dict[tuple[type, object], int]) -> tuple[int, int]:
    """The kernel's tie-break key: ages of the constant attribute and value tests."""
    if kcond.is_ncc:
        return (-1, -1)
    cond = kcond.element
    assert isinstance(cond, Condition)
    return (_age(cond.attr_test, ages), _age(cond.value_test, ages))


def _age(test: Test, ages: dict[tuple[type, object], int]) -> int:
    if isinstance(test, Const):
        return ages.get((type(test.value), test.value), len(ages))
    return -1


def _reorder(conds: list[KCond], bound: set[str], roots: list[str],
             ages: dict[tuple[type, object], int], multi: dict[str, int]) -> list[KCond]:
    """The kernel's greedy order (reorder_simplified_conditions), NCC members too."""
    scope = set().union(*(_binds(c) for c in conds)) if conds else set()
    needs = {id(c): _mentioned(c.element) & (scope | bound) for c in conds if c.negated}
    remaining, ordered, bound, roots = list(conds), [], set(bound), list(roots)
    while remaining:
        costs = [_cost(c, bound, roots, needs, multi) for c in remaining]
        low = min(costs)
        ties = [c for c, cost in zip(remaining, costs, strict=True) if cost == low]
        if len(ties) > 1 and low > 1:
            chosen = _look_ahead(ties, remaining, bound, roots, needs, ages, multi)
        else:
            chosen = max(reversed(ties), key=lambda c: _canonical(c, ages))
        remaining.remove(chosen)
        if chosen.is_ncc:
            chosen.inner = _reorder(chosen.inner, bound, [], ages, multi)
        ordered.append(chosen)
        bound |= _binds(chosen)
        roots = [r for r in roots if r not in bound]
    return ordered


def _look_ahead(ties: list[KCond], remaining: list[KCond], bound: set[str], roots: list[str],
                needs: dict[int, set[str]], ages: dict[tuple[type, object], int],
                multi: dict[str, int]) -> KCond:
    """Among tied candidates, the one after which the next condition is cheapest; ties go
    to the newest symbols, then to the later-written condition."""
    best: KCond | None = None
    best_key: tuple[int, tuple[int, int]] | None = None
    for candidate in reversed(ties):
        after = bound | _binds(candidate)
        follow = [_cost(c, after, roots, needs, multi) for c in remaining if c is not candidate]
        cost = min(follow, default=MAX_COST + 1)
        key = (cost, _canonical(candidate, ages))
        if best_key is None or cost < best_key[0] or (
                cost == best_key[0] and key[1] > best_key[1]):
            best, best_key = candidate, key
    assert best is not None
    return best


def _move_relations(ordered: list[KCond], bound: set[str]) -> None:
    """Move each relational test on a variable bound only by a later condition into that
    condition, inverted and against this field's equality variable (as the Rete does)."""
    for position, kcond in enumerate(ordered):
        if kcond.is_ncc:
            _move_relations(kcond.inner, set(bound))
            continue
        own = set() if kcond.negated else {p for f in kcond.fields for p in f if _is_var(p)}
        for field_parts in kcond.fields:
            for part in list(field_parts[:-1]):
                op, _, operand = part.partition(" ")
                if not _is_var(operand) or operand in bound or operand in own:
                    continue
                target = _binder(ordered[position + 1:], operand)
                if target is not None:
                    field_parts.remove(part)
                    target.insert(-1, f"{_INVERSE.get(op, op)} {field_parts[-1]}")
        if not kcond.negated:
            bound |= own


def _is_var(text: str) -> bool:
    return text.startswith("<") and text.endswith(">") and len(text) > 2 and " " not in text


def _binder(later: list[KCond], var: str) -> list[str] | None:
    for kcond in later:
        if kcond.negated or kcond.is_ncc:
            continue
        for field_parts in kcond.fields:
            if field_parts and field_parts[-1] == var:
                return field_parts
    return None


def _mark_goals(ordered: list[KCond], roots: list[str]) -> None:
    """``state``/``impasse`` is printed on the first condition of each root variable."""
    seen: set[str] = set()
    for kcond in ordered:
        goal, kcond.goal = kcond.goal, None
        if kcond.is_ncc or kcond.negated:
            continue
        ident = kcond.fields[0][-1][1:-1]
        if ident in roots and ident not in seen:
            seen.add(ident)
            kcond.goal = goal or _goal_of(ordered, ident)


def _goal_of(ordered: list[KCond], ident: str) -> str | None:
    for kcond in ordered:
        element = kcond.element
        if isinstance(element, Condition) and element.goal and ident in _equality_names(
                element.id_test):
            return element.goal
    return None


def format_kcond(kcond: KCond) -> str:
    """``(state <s> ^a { > 3 <a*1> })``, ``(<s> -^b c)``, ``(<s> ^operator <o> +)``, and
    a conjunctive negation (nested in another one: ``-(<x> -^d.e f)``) as ``-{ ... }``."""
    def text(parts: list[str]) -> str:
        return parts[0] if len(parts) == 1 else "{ " + " ".join(parts) + " }"

    if kcond.is_ncc:
        return "-{" + " ".join(format_kcond(inner) for inner in kcond.inner) + "}"
    ident, attr, value = (text(f) for f in kcond.fields)
    head = f"{kcond.goal} " if kcond.goal else ""
    sign = "-" if kcond.negated else ""
    plus = " +" if kcond.element.acceptable else ""  # type: ignore[union-attr]
    return f"({head}{ident} {sign}^{attr} {value}{plus})"


def positive_order(ordered: list[KCond]) -> list[int]:
    """Indexes of the production's top-level positive conditions, in kernel order: the
    order of a token's WMEs."""
    return [k.index for k in ordered if not k.negated]


def with_kernel_relations(production: Production, ages: dict[tuple[type, object], int]
                          ) -> Production:
    """``production`` with each relational test on a variable that the kernel's order
    binds only later moved, inverted, into the condition that binds it, against the
    tested field's equality variable: the kernel's Rete runs it there, on that WME's value
    (``{<w> >= <v>}`` becomes ``{<v> <= <w>}``). It matters when the two values are of
    different kinds, where ``<`` and ``<=`` hold and ``>`` and ``>=`` do not (measured in
    soar_sml). Tests of negated conditions and inside ``-{...}`` stay where they are."""
    ordered = kernel_conditions(production, ages, {})
    positive = [k for k in ordered if not k.negated and not k.is_ncc]
    moves: dict[int, list[tuple[str, object, object]]] = {}  # id(condition) -> changes
    bound: set[str] = set()
    for position, kcond in enumerate(positive):
        cond = kcond.element
        assert isinstance(cond, Condition)
        own = {name for _, test in _fields(cond) for name in _equality_names(test)}
        for field_name, test in _fields(cond):
            equality = next(iter(_equality_names(test)), None)
            for rel in _relationals(test):
                var = rel.operand.name  # type: ignore[union-attr]
                if equality is None or var in bound or var in own:
                    continue
                target = next((k.element for k in positive[position + 1:]
                               if var in {n for _, t in _fields(k.element)  # type: ignore[arg-type]
                                          for n in _equality_names(t)}), None)
                if target is None:
                    continue
                moves.setdefault(id(cond), []).append((field_name, rel, None))
                moves.setdefault(id(target), []).append(
                    (_field_of(target, var), None,  # type: ignore[arg-type]
                     Relational(_INVERSE.get(rel.op, rel.op), Var(equality))))
        bound |= own
    if not moves:
        return production
    conditions = tuple(_moved(c, moves[id(c)]) if id(c) in moves else c
                       for c in production.conditions)
    return replace(production, conditions=conditions)


_FIELDS = ("id_test", "attr_test", "value_test")


def _fields(cond: Condition) -> list[tuple[str, Test]]:
    return [(name, getattr(cond, name)) for name in _FIELDS]


def _relationals(test: Test) -> list[Relational]:
    tests = test.tests if isinstance(test, Conjunction) else (test,)
    return [t for t in tests if isinstance(t, Relational) and isinstance(t.operand, Var)]


def _field_of(cond: Condition, var: str) -> str:
    return next(name for name, test in _fields(cond) if var in _equality_names(test))


def _moved(cond: Condition, changes: list[tuple[str, object, object]]) -> Condition:
    """``cond`` without the moved-away tests and with the moved-in ones."""
    fields = dict(_fields(cond))
    for name, removed, added in changes:
        test = fields[name]
        tests = list(test.tests) if isinstance(test, Conjunction) else [test]
        if removed is not None:
            tests = [t for t in tests if t is not removed]
        if added is not None:
            tests.append(added)
        fields[name] = tests[0] if len(tests) == 1 else Conjunction(tuple(tests))
    return replace(cond, **fields)


__all__ = ["KCond", "format_kcond", "kernel_conditions", "positive_order", "symbol_ages",
           "with_kernel_relations"]
