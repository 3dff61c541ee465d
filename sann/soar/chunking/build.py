"""A chunk from an explanation: grounds variablized by identity, results as actions.

The conditions are the grounds (one per superstate WME: conditions of several firings that
tested the same WME are merged, their identities unified), their tests as the rules wrote
them with each variable replaced by its identity's variable, or by the symbol when the
identity was literalized; the kept negations; the constraints of local conditions on the
identities they constrain. The actions are the results' actions, variablized the same way;
a local identifier a result links to becomes a new identifier of the chunk. The chunk is
then checked as a parsed rule is (`parsing.actions.check_production`,
`parsing.checks.load_warnings`): an unconnected condition or action refuses it, and a
justification stands in.
"""

from __future__ import annotations

import re
from collections.abc import Hashable

from ..errors import SoarSemanticError
from ..memory import Identifier
from ..parsing.actions import check_production
from ..parsing.checks import load_warnings
from ..printer import format_condition
from ..production import (
    Condition,
    ConditionElement,
    Conjunction,
    ConjunctiveNegation,
    Const,
    FuncCall,
    MakeAction,
    Production,
    Relational,
    RhsValue,
    Test,
    Var,
)
from ..rhs import FUNCTIONS
from .backtrace import FIELDS, Explanation, Ground, Step, equality_var


class Variablizer:
    """Names the chunk's variables, one per identity root (``<x1>``, ``<x2>``, ...)."""

    def __init__(self, ex: Explanation) -> None:
        self.ex = ex
        self.names: dict[Hashable, str] = {}
        self.counts: dict[str, int] = {}
        self.bound: set[Hashable] = set()
        self.goal: Identifier | None = None
        self.goal_ids: set[object] = set()
        #: the names of variables local to a negation
        self.locals: set[str] = set()
        #: the negation being variablized: its local variables are its own
        self.scope = 0

    def name(self, root: Hashable, hint: str) -> str:
        found = self.names.get(root)
        if found is None:
            letter = hint[0].lower() if hint and hint[0].isalpha() else "v"
            count = self.counts.get(letter, 0) + 1
            self.counts[letter] = count
            found = self.names[root] = f"{letter}{count}"
        return found

    def find_goal_ids(self, grounds: list[Ground]) -> None:
        """The chunk's ``state`` variables: its match goal as a rule tested it with
        ``state`` or as the substate's ``^superstate`` gave it (measured in soar_sml:
        ``(state <s1> ^top-state <t1>) (<t1> ^block <b1>)`` for one state reached both
        ways); any variable of the match goal when neither."""
        root = self.ex.ids.find(("state", self.goal))
        for ground in grounds:
            if ground.wme.id is not self.goal:
                continue
            for cond, step in ground.tests:
                var = equality_var(cond.id_test)
                if var is not None and (cond.goal == "state" or self.ex.ids.find(
                        self.ex.key(step, var)) == root):
                    self.goal_ids.add(self.test(cond.id_test, step))

    def is_goal(self, ident: object, test: Test) -> bool:
        if ident is not self.goal or self.goal is None:
            return False
        return not self.goal_ids or _equality(test) in self.goal_ids

    def var(self, step: Step, name: str, lhs: bool = True) -> Test:
        """The variable (or literal) of a rule variable of a step in the chunk."""
        key = self.ex.key(step, name)
        root = self.ex.ids.find(key)
        value = step.bindings.get(name)
        if self.ex.ids.is_literal(key) and value is not None and not isinstance(
                value, Identifier):
            return Const(value)  # type: ignore[arg-type]
        if not lhs and root not in self.bound:
            if isinstance(value, Identifier):  # a new identifier of the chunk
                return Var(self.name(("new", value), name))
            if value is None:  # local to a negation (each its own)
                local = self.name(("unbound", root, self.scope), name)
                self.locals.add(local)
                return Var(local)
            return Const(value)  # type: ignore[arg-type]
        return Var(self.name(root, "s" if isinstance(root[0], str) else name))  # type: ignore[index]

    def test(self, test: Test, step: Step, lhs: bool = True) -> Test:
        if isinstance(test, Var):
            return self.var(step, test.name, lhs)
        if isinstance(test, Relational):
            operand = test.operand
            if isinstance(operand, Var):
                mapped = self.var(step, operand.name, lhs=False)
                return Relational(test.op, mapped)  # type: ignore[arg-type]
            return test
        if isinstance(test, Conjunction):
            return _conjoin([self.test(part, step, lhs) for part in test.tests])
        return test


def build_chunk(ex: Explanation, name: str) -> Production:
    """The chunk of an explanation, parsed and checked (raises the parser's error)."""
    grounds = list(ex.grounds.values())
    for ground in grounds:
        _join(ex, ground)
    vz = Variablizer(ex)
    vz.goal = _match_goal(grounds)
    for ground in grounds:
        for cond, step in ground.tests:
            for field in FIELDS:
                var = equality_var(getattr(cond, field))
                if var is not None:
                    vz.bound.add(ex.ids.find(ex.key(step, var)))
    vz.find_goal_ids(grounds)
    conditions: list[ConditionElement] = []
    where: dict[Hashable, tuple[int, str]] = {}
    for ground in grounds:
        _ground_conditions(vz, ground, conditions, where)
    _add_constraints(vz, ex, conditions, where)
    seen: set[str] = set()
    for scope, (element, step) in enumerate(ex.negations, 1):
        vz.scope = scope
        negation = _negation(vz, element, step)
        # the same negation from several firings is tested once
        key = re.sub(r"<([^>]+)>", lambda m: "<_>" if m.group(1) in vz.locals else m.group(0),
                     format_condition(negation))
        if key not in seen:
            seen.add(key)
            conditions.append(negation)
    conditions = _join_order(list(dict.fromkeys(conditions)))  # equal ones once
    actions = [_action(vz, action, step) for _, action, step in ex.results]
    production = Production(name, tuple(conditions), tuple(actions), flags=("chunk",))
    production = check_production(production, FUNCTIONS.keys())
    problems = load_warnings(production)
    if problems:  # a warning for a rule: a chunk is refused (a justification stands in)
        raise SoarSemanticError(name, problems[0])
    return production


def _join_order(conditions: list[ConditionElement]) -> list[ConditionElement]:
    """The conditions in an order our matcher joins well (it joins them as written): the
    state first, then always a condition on a bound identifier, those whose value is bound
    or constant first; negations last. (The kernel reorders a chunk's conditions too, by
    its own cost; the order means nothing else.)"""
    positive = [c for c in conditions if isinstance(c, Condition) and not c.negated]
    rest = [c for c in conditions if not (isinstance(c, Condition) and not c.negated)]
    ordered: list[ConditionElement] = []
    bound: set[str] = set()
    while positive:
        def cost(cond: Condition) -> tuple[int, int, int]:
            ident = equality_var(cond.id_test)
            reached = ident in bound or (not bound and cond.goal == "state")
            value = _equality(cond.value_test)
            known = isinstance(value, Const) or (isinstance(value, Var) and value.name in bound)
            return (0 if reached else 1, 0 if known else 1,
                    0 if isinstance(cond.attr_test, Const) else 1)
        best = min(positive, key=cost)
        positive.remove(best)
        ordered.append(best)
        for field in FIELDS:
            var = _equality(getattr(best, field))
            if isinstance(var, Var):
                bound.add(var.name)
    return ordered + rest


def _match_goal(grounds: list[Ground]) -> Identifier | None:
    """The deepest state the grounds test: the only one the chunk tests as a ``state``
    (measured in soar_sml: a chunk for the selection state is ``(state <s1> ^name selection
    ^superstate <s2>) (<s2> ^name water-jug ...)``)."""
    best: Identifier | None = None
    for ground in grounds:
        ident = ground.wme.id
        if isinstance(ident, Identifier) and ident.is_state and (
                best is None or (ident.level or 0) > (best.level or 0)):
            best = ident
    return best


def _join(ex: Explanation, ground: Ground) -> None:
    """Conditions of several firings on one WME: their identifier and value identities
    become one (a literal one makes the other literal: measured in soar_sml, ``^cook-time
    { <c> > 1 }`` and a literalized ``^cook-time 2`` of one WME give ``^cook-time 2``);
    attribute identities stay apart (measured: the selection space's ``(<ts> ^<state-att>
    <id>)`` on ``(S1 ^jug J1)``, once per copied augmentation of J1, stays ``^<a1> <j1>
    ^<a3> <j1>`` beside ``^jug { <j1> <=> <s1> }``, whose attribute was literalized)."""
    first, step0 = ground.tests[0]
    for cond, step in ground.tests[1:]:
        for field in ("id_test", "value_test"):
            a, b = equality_var(getattr(first, field)), equality_var(getattr(cond, field))
            if a is None or b is None:
                continue
            ex.ids.union(ex.key(step0, a), ex.key(step, b))


def _ground_conditions(vz: Variablizer, ground: Ground, conditions: list[ConditionElement],
                       where: dict[Hashable, tuple[int, str]]) -> None:
    """The conditions of one ground: those whose equality tests came out the same are
    merged (their other tests together), the others stay apart."""
    merged: dict[tuple, int] = {}
    for cond, step in ground.tests:
        fields = [vz.test(getattr(cond, field), step) for field in FIELDS]
        is_state = vz.is_goal(ground.wme.id, fields[0])
        if _equality(fields[2]) is None:
            # the kernel gives a value test without an equality test a variable (measured:
            # ``^max-look-ahead-depth { <m1> < 5 }``)
            attr = fields[1]
            hint = str(attr.value) if isinstance(attr, Const) else "v"
            fresh = Var(vz.name(("fresh", len(conditions), id(cond)), hint))
            fields[2] = _conjoin([fresh, fields[2]])
        signature = tuple(_equality(test) for test in fields)
        index = merged.get(signature)
        if index is None:
            index = merged[signature] = len(conditions)
            conditions.append(Condition(fields[0], fields[1], fields[2],
                                        acceptable=ground.wme.acceptable,
                                        goal="state" if is_state else None))
        else:
            old = conditions[index]
            assert isinstance(old, Condition)
            conditions[index] = Condition(
                *(_conjoin([getattr(old, f), t]) for f, t in zip(FIELDS, fields, strict=True)),
                acceptable=old.acceptable, goal=old.goal)
        for field in FIELDS:
            var = equality_var(getattr(cond, field))
            if var is not None:
                where.setdefault(vz.ex.ids.find(vz.ex.key(step, var)), (index, field))


def _equality(test: Test) -> object:
    if isinstance(test, Var | Const):
        return test
    if isinstance(test, Conjunction):
        for part in test.tests:
            if isinstance(part, Var | Const):
                return part
    return None


def _add_constraints(vz: Variablizer, ex: Explanation, conditions: list[ConditionElement],
                     where: dict[Hashable, tuple[int, str]]) -> None:
    """Relational tests of local conditions, on the ground field that binds their identity
    (dropped when the identity was literalized or no ground tests it)."""
    for key, rel, step, value in ex.constraints:
        target = _placed(vz, ex, key, rel, step, value, where)
        if target is None:
            continue
        (index, field), test = target
        cond = conditions[index]
        assert isinstance(cond, Condition)
        conditions[index] = _replace(cond, field, _conjoin([getattr(cond, field), test]))


#: ``a op b`` is ``b (inverse op) a``
_INVERSE = {"<": ">", ">": "<", "<=": ">=", ">=": "<=", "<>": "<>", "<=>": "<=>"}


def _placed(vz: Variablizer, ex: Explanation, key: Hashable, rel: Relational, step: Step,
            value: object, where: dict[Hashable, tuple[int, str]]
            ) -> tuple[tuple[int, str], Test] | None:
    """Where a constraint goes and as what test: on its own identity's ground field, or,
    when that identity is a literal, inverted onto its operand's (measured in soar_sml:
    ``^top { <t> < <b> }`` with the top literalized to 5 gives the chunk ``^digit2 { <d1>
    > 5 }``). None when no ground tests either identity (the constraint is dropped)."""
    root = ex.ids.find(key)
    if not ex.ids.is_literal(key) and root in where:
        return where[root], vz.test(rel, step)
    operand = rel.operand
    if not isinstance(operand, Var) or rel.op not in _INVERSE:
        return None
    other = ex.key(step, operand.name)
    other_root = ex.ids.find(other)
    if ex.ids.is_literal(other) or other_root not in where:
        return None
    if not ex.ids.is_literal(key) or isinstance(value, Identifier):
        return None
    return where[other_root], Relational(_INVERSE[rel.op], Const(value))  # type: ignore[arg-type]


def _replace(cond: Condition, field: str, test: Test) -> Condition:
    tests = {name: getattr(cond, name) for name in FIELDS}
    tests[field] = test
    return Condition(tests["id_test"], tests["attr_test"], tests["value_test"],
                     cond.negated, cond.acceptable, cond.goal)


def _conjoin(parts: list[Test]) -> Test:
    """One test from several on one field, equal ones once, the equality test first."""
    flat: list[Test] = []
    for part in parts:
        for test in part.tests if isinstance(part, Conjunction) else (part,):
            if test not in flat:
                flat.append(test)
    if any(isinstance(test, Const) for test in flat):
        # a literalized identity: its relational tests go with it (measured: ``{ <y> > 2 }``
        # behind a function's value becomes ``4``)
        flat = [test for test in flat if not isinstance(test, Relational)]
    if len(flat) == 1:
        return flat[0]
    flat.sort(key=lambda t: 0 if isinstance(t, Var | Const) else 1)
    return Conjunction(tuple(flat))


def _negation(vz: Variablizer, element: Condition | ConjunctiveNegation,
              step: Step) -> ConditionElement:
    if isinstance(element, ConjunctiveNegation):
        return ConjunctiveNegation(tuple(_negation(vz, inner, step)  # type: ignore[misc]
                                         for inner in element.conditions))
    tests = [vz.test(getattr(element, field), step, lhs=False) for field in FIELDS]
    for k, test in enumerate(tests):
        if _equality(test) is None:  # a variable, as the kernel's parser gives it
            hint = str(tests[1].value) if isinstance(tests[1], Const) else "v"
            local = vz.name(("fresh", vz.scope, id(element), k), hint)
            vz.locals.add(local)
            tests[k] = _conjoin([Var(local), test])
    is_state = vz.is_goal(step.bindings.get(equality_var(element.id_test) or ""), tests[0])
    return Condition(tests[0], tests[1], tests[2], element.negated, element.acceptable,
                     "state" if is_state else None)


def _action(vz: Variablizer, action: MakeAction, step: Step) -> MakeAction:
    def value(node: RhsValue) -> RhsValue:
        if isinstance(node, Var):
            return vz.var(step, node.name, lhs=False)  # type: ignore[return-value]
        if isinstance(node, FuncCall):
            return FuncCall(node.name, tuple(value(arg) for arg in node.args))
        return node

    ident = value(action.id)
    assert isinstance(ident, Var), ident
    referent = value(action.referent) if action.referent is not None else None
    return MakeAction(ident, value(action.attr), value(action.value), action.preference,
                      referent)
