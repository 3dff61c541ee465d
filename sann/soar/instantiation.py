"""Instantiations (fired rules) and what the engine precomputes about each production.

An instantiation is one match of a production that fired; it owns the preferences its
actions made. Its *match goal* is the deepest state among the identifiers of the WMEs it
matched (the kernel's ``find_goal_for_match_set_change_assertion``); support is Soar 9's:
o-support when the match tests the selected operator of the match goal (a positive,
non-acceptable ``^operator`` condition on that state) and the action is not on that
operator; ``:o-support``/``:i-support`` override it. A *justification* stands in for a
substate rule that returned results: it holds copies of the result preferences and, when
i-supported, is retracted as soon as one of the superstate WMEs they depended on leaves
working memory.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from .memory import WME, Identifier
from .production import CallAction, Const, FuncCall, MakeAction, Production, RhsValue, Var

if TYPE_CHECKING:
    from .goals import Goal
    from .preferences import Preference


@dataclass
class ProductionInfo:
    """Facts about a production that the per-match path needs, computed once at load."""

    production: Production
    #: Indexes of positive, non-acceptable conditions whose attribute is the constant
    #: ``operator``: the conditions that can make the rule o-supported.
    operator_conditions: tuple[int, ...]
    declared: str | None
    #: Variables naming the tested operators (``<o>`` in ``^operator <o>``), if simple.
    actions: tuple[MakeAction | CallAction, ...]
    #: Variable names on which the make-actions create preferences.
    make_ids: tuple[str, ...] = ()
    firings: int = 0
    #: Order in which the production was loaded (a replaced production is loaded anew).
    load_index: int = 0
    #: Per top-level condition: 2 if its attribute test is a constant, +4 if its value test
    #: is; the kernel's alpha-memory order when one WME makes several matches.
    cond_masks: tuple[int, ...] = ()
    #: Variables used on the right-hand side; ``rhs_binds`` says, once the first match has
    #: shown which variables the left-hand side binds, whether firing creates identifiers
    #: (and so needs its own copy of the match's bindings).
    rhs_vars: tuple[str, ...] = ()
    rhs_binds: bool | None = None
    #: Per action, the common make-action shape ``(<id> ^const value)`` without referent as
    #: ``(id name, attr, value is a constant, constant or variable name, preference)`` so
    #: firing can skip the general evaluator; ``None`` for any other action.
    plans: tuple[tuple[str, object, bool, object, str] | None, ...] = ()
    #: Per action, what firing walks: ``(action, id name, attr, value is a constant,
    #: constant or variable name, preference)`` from its plan, or ``(action, None, ...)``.
    steps: tuple[tuple[MakeAction | CallAction, str | None, object, bool, object, str], ...] = ()

    @classmethod
    def of(cls, production: Production) -> ProductionInfo:
        indexes = []
        for index, cond in enumerate(production.conditions):
            attr = getattr(cond, "attr_test", None)
            if (
                isinstance(attr, Const)
                and attr.value == "operator"
                and not cond.negated  # type: ignore[union-attr]
                and not cond.acceptable  # type: ignore[union-attr]
            ):
                indexes.append(index)
        make_ids = tuple(
            dict.fromkeys(
                a.id.name
                for a in production.actions
                if isinstance(a, MakeAction) and isinstance(a.id, Var)
            )
        )
        masks = tuple(
            (2 if type(getattr(cond, "attr_test", None)) is Const else 0)
            | (4 if type(getattr(cond, "value_test", None)) is Const else 0)
            for cond in production.conditions
        )
        rhs_vars: dict[str, None] = {}
        for action in production.actions:
            values = (
                (action.id, action.attr, action.value, action.referent)
                if isinstance(action, MakeAction)
                else (action.call,)
            )
            for value in values:
                if value is not None:
                    rhs_vars.update(dict.fromkeys(variables_in(value)))
        plans = tuple(_action_plan(action) for action in production.actions)
        return cls(
            production,
            tuple(indexes),
            production.support,
            production.actions,
            make_ids,
            cond_masks=masks,
            rhs_vars=tuple(rhs_vars),
            plans=plans,
            steps=tuple(
                (action, *(plan or (None, None, False, None, "")))
                for action, plan in zip(production.actions, plans, strict=True)
            ),
        )


def _action_plan(action: MakeAction | CallAction) -> tuple[str, object, bool, object, str] | None:
    """The fast firing form of a make-action with a constant attribute (see ``plans``)."""
    if type(action) is not MakeAction or action.referent is not None:
        return None
    if type(action.id) is not Var or type(action.attr) is not Const:
        return None
    value = action.value
    if type(value) is Const:
        return (action.id.name, action.attr.value, True, value.value, action.preference)
    if type(value) is Var:
        return (action.id.name, action.attr.value, False, value.name, action.preference)
    return None


class Instantiation:
    """A fired match (or a justification) and the preferences it asserted."""

    __slots__ = (
        "name",
        "match",
        "goal",
        "wmes",
        "prefs",
        "o_support",
        "is_justification",
        "grounds",
        "retracted",
    )

    def __init__(
        self,
        name: str,
        match: object | None,
        goal: Goal,
        wmes: tuple[WME | None, ...],
        o_support: bool,
        is_justification: bool = False,
    ) -> None:
        self.name = name
        self.match = match
        self.goal = goal
        self.wmes = wmes
        self.prefs: list[Preference] = []
        self.o_support = o_support
        self.is_justification = is_justification
        self.grounds: tuple[WME, ...] = ()
        self.retracted = False

    def __repr__(self) -> str:
        return f"<Instantiation {self.name} at {self.goal.id}>"


def match_goal(wmes: tuple[WME | None, ...]) -> Identifier | None:
    """The deepest state among the identifiers of the matched WMEs."""
    best: Identifier | None = None
    for wme in wmes:
        if wme is not None:
            ident = wme.id
            level = ident.level
            if level is not None and (best is None or level > best.level):  # type: ignore[operator]
                best = ident
    return best


def is_o_supported(
    info: ProductionInfo, wmes: tuple[WME | None, ...], goal: Identifier, match: object = None
) -> bool:
    """Whether this match fires as an o-assertion (PE) rather than an i-assertion (IE).

    It does when the match tests the selected operator of its goal and some action is not an
    elaboration of that operator."""
    if info.declared is not None:
        return info.declared == "o-support"
    operators = None
    for i in info.operator_conditions:
        wme = wmes[i]
        if wme is not None and wme.id is goal:
            if operators is None:
                operators = [wme.value]
            else:
                operators.append(wme.value)
    if operators is None:
        return False
    make_ids = info.make_ids
    if not make_ids:
        return False  # the kernel fires write/halt-only rules as i-assertions
    bindings = match.bindings if match is not None else {}  # type: ignore[attr-defined]
    for name in make_ids:
        value = bindings.get(name)
        if value is None:
            return True
        if type(value) is Identifier:
            if value not in operators:  # identifiers are equal only to themselves
                return True
        elif not any(value is op for op in operators):
            return True
    return False


def tested_operators(
    info: ProductionInfo, wmes: tuple[WME | None, ...], goal: Identifier
) -> list[object]:
    """Values of the selected-operator WMEs of the match goal that the match tested."""
    return [
        wmes[i].value  # type: ignore[union-attr]
        for i in info.operator_conditions
        if wmes[i] is not None and wmes[i].id is goal  # type: ignore[union-attr]
    ]


def variables_in(value: RhsValue) -> list[str]:
    """Variable names used in an RHS value (for error messages and checks)."""
    if isinstance(value, Var):
        return [value.name]
    if isinstance(value, FuncCall):
        out: list[str] = []
        for arg in value.args:
            out.extend(variables_in(arg))
        return out
    return []
