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

from collections.abc import Callable, Container, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .codegen import define
from .errors import SoarError, SoarRuntimeError
from .memory import WME, Identifier, Symbol, rhs_id_hint
from .preferences import NATIVE, Preference, preference_type
from .production import CallAction, Const, FuncCall, MakeAction, Production, RhsValue, Var
from .rhs import FUNCTIONS
from .text import format_symbol as kernel_shown

if TYPE_CHECKING:
    from .goals import Goal

#: A production's compiled right-hand side: ``program(agent, bindings, inst, o_support,
#: operators)`` appends the instantiation's preferences (see `compile_actions`).
RhsProgram = Callable[[object, dict, "Instantiation", bool, Sequence[object]], None]


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
    #: The compiled right-hand side (`compile_actions`), made once the production has
    #: fired `COMPILE_AFTER` times; until then its actions are interpreted.
    program: RhsProgram | None = None
    #: Firings since load (``firings`` restarts at init-soar).
    runs: int = 0
    #: Variables on which the actions propose an operator (an acceptable preference for
    #: ``^operator``): on a state, that makes the rule i-supported (see is_o_supported).
    proposal_ids: tuple[str, ...] = ()

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
        proposals = tuple(
            dict.fromkeys(
                a.id.name
                for a in production.actions
                if isinstance(a, MakeAction) and isinstance(a.id, Var)
                and isinstance(a.attr, Const) and a.attr.value == "operator"
                and a.preference == "+"
            )
        )
        return cls(
            production,
            tuple(indexes),
            production.support,
            production.actions,
            make_ids,
            cond_masks=masks,
            proposal_ids=proposals,
        )


#: Compiling a right-hand side costs about as much as a few hundred interpreted firings,
#: so only productions that keep firing are compiled.
COMPILE_AFTER = 100


def interpret_actions(
    actions: Sequence[MakeAction | CallAction],
    agent: object,
    bindings: dict[str, Symbol],
    inst: Instantiation,
    o_support: bool,
    operators: Sequence[object],
) -> None:
    """What a compiled program does (`compile_actions`), by walking the actions."""
    bindings = dict(bindings)  # new identifiers are bound for this firing only
    prefs = inst.prefs
    for action in actions:
        try:
            if type(action) is MakeAction:
                pref = _make_preference(agent, action, bindings, inst)
                if o_support and pref.id not in operators:
                    pref.o_supported = True
                prefs.append(pref)
            else:
                _call(agent, action.call, bindings, inst)  # type: ignore[union-attr]
        except (Abandoned, SoarError) as error:
            _report(agent, inst, error)


class Abandoned(Exception):  # noqa: N818 -- not an error: one already reported
    """A function call given a failed argument, and so the action holding it: the kernel
    evaluates every argument of a call (each failure prints its error), then calls nothing
    and drops the action, silently (measured: ``(write (+ a 1) (/ 1 0))`` prints two errors
    and writes nothing)."""


def _report(agent: object, inst: Instantiation, error: Exception) -> None:
    """Print a failed action's error, unless it was printed already (`Abandoned`)."""
    if type(error) is not Abandoned:
        agent._report_rhs_error(inst, error)  # type: ignore[attr-defined]


def not_an_identifier(action: MakeAction, bound: Container[str], ident: Symbol) -> SoarRuntimeError:
    """The kernel's error for an action whose identifier is bound to a constant, raised as
    soon as the identifier is known (the attribute and value are not evaluated). It shows
    the action as the kernel stores it: a variable of the left-hand side as ``[RETE-loc]``,
    any other as ``<unbound-variable>``, floats as ``%f``, the preference and referent."""

    def shown(node: RhsValue) -> str:
        kind = type(node)
        if kind is Var:
            return "[RETE-loc]" if node.name in bound else "<unbound-variable>"  # type: ignore[union-attr]
        if kind is FuncCall:
            return "(" + " ".join([node.name, *map(shown, node.args)]) + ")"  # type: ignore[union-attr]
        return kernel_shown(node.value)  # type: ignore[union-attr]

    text = f"{shown(action.id)} ^{shown(action.attr)} {shown(action.value)} {action.preference}"
    if action.referent is not None:
        text += " " + shown(action.referent)
    return SoarRuntimeError(
        f"RHS of action           ({text}) makes a preference for {kernel_shown(ident)}"
        " (not an identifier)"
    )


def _make_preference(
    agent: object, action: MakeAction, bindings: dict[str, Symbol], inst: Instantiation
) -> Preference:
    ident = _value(agent, action.id, bindings, inst)
    if type(ident) is not Identifier:
        raise not_an_identifier(action, inst.match.bindings, ident)  # type: ignore[attr-defined]
    # A new identifier in the attribute, value or referent starts at the level of the
    # identifier it augments, as in the kernel (``execute_action``): made on a superstate,
    # it is a result at once, and so is all of its structure made by the same firing.
    level = agent._level_of(ident)  # type: ignore[attr-defined]
    attr = _value(agent, action.attr, bindings, inst, level)
    value = _value(agent, action.value, bindings, inst, level)
    referent = None
    if action.referent is not None:
        referent = _value(agent, action.referent, bindings, inst, level)
    ptype = action.preference
    if referent is not None:
        ptype = preference_type(ptype, referent)
    return Preference(ptype, ident, attr, value, referent, inst)


def _value(
    agent: object, value: RhsValue, bindings: dict[str, Symbol], inst: Instantiation,
    level: int | None = None,
) -> Symbol:
    """The symbol a right-hand-side value stands for; an unbound variable makes a new
    identifier at ``level`` (default: the instantiation's goal's)."""
    kind = type(value)
    if kind is Var:
        bound = bindings.get(value.name)  # type: ignore[union-attr]
        if bound is None:  # an unbound variable names a new identifier
            at = inst.goal.level if level is None else level
            bound = agent._new_id(rhs_id_hint(value.name), at)  # type: ignore[attr-defined, union-attr]
            bindings[value.name] = bound  # type: ignore[union-attr]
        return bound
    if kind is Const:
        return value.value  # type: ignore[union-attr]
    if kind is FuncCall:
        result = _call(agent, value, bindings, inst, level)  # type: ignore[arg-type]
        if result is None:
            raise SoarRuntimeError(f"({value.name}) returns no value")  # type: ignore[union-attr]
        return result
    raise SoarRuntimeError(f"cannot evaluate {value!r}")


def _call(
    agent: object, call: FuncCall, bindings: dict[str, Symbol], inst: Instantiation,
    level: int | None = None,
) -> Symbol | None:
    function = FUNCTIONS.get(call.name)
    if function is None:
        raise SoarRuntimeError(f"unknown RHS function ({call.name})")
    args = []
    failed = False
    for arg in call.args:  # a loop is no slower than a list comprehension in CPython 3.11
        try:
            args.append(_value(agent, arg, bindings, inst, level))
        except (Abandoned, SoarError) as error:
            _report(agent, inst, error)
            failed = True
    if failed:
        raise Abandoned
    return function(agent, args)  # type: ignore[arg-type]


def compile_actions(
    name: str, actions: Sequence[MakeAction | CallAction], bound: Container[str] = ()
) -> RhsProgram:
    """Compile a production's actions into one Python function.

    Interpreting the actions cost more than anything else in firing; the compiled form
    does the same steps in the same order: per make-action the identifier, attribute,
    value and referent are evaluated (an unbound variable becomes a new identifier at its
    first evaluation, named after the variable; an identifier that is not one is an error
    at once, `not_an_identifier`), then a preference is made. A `SoarError` in an action is
    reported by the agent (``_report_rhs_error``) and drops that action only; a failed
    argument of a function call is reported and the call's other arguments are still
    evaluated, then the action is dropped (`Abandoned`). Error handling costs nothing until
    an error: the code after a failure is generated separately, in the ``except`` blocks.

    ``bound`` names the variables every match binds (the left-hand side's: the same for
    all matches of a production); reading them needs no check for a new identifier."""
    return _RhsCompiler(name, bound).build(actions)


class _RhsCompiler:
    """Generates the source of `compile_actions`'s function, straight-line per action so
    that evaluation order (and so identifier numbering and output) is the interpreter's."""

    def __init__(self, name: str, bound: Container[str]) -> None:
        self.name = name
        self.bound = bound
        #: The level a new identifier gets where it is made (an expression of the program).
        self.level = "level"
        self.namespace: dict[str, object] = {
            "Preference": Preference,
            "NEW": object.__new__,
            "Identifier": Identifier,
            "SoarError": SoarError,
            "SoarRuntimeError": SoarRuntimeError,
            "Abandoned": Abandoned,
            "report": _report,
            "not_an_identifier": not_an_identifier,
            "preference_type": preference_type,
        }
        self.locals: dict[str, str] = {}  # variable name -> local holding its value
        self.temps = 0

    def build(self, actions: Sequence[MakeAction | CallAction]) -> RhsProgram:
        body: list[str] = []
        for action in actions:
            body.append("    try:")
            if type(action) is MakeAction:
                self._make(action, body)
            else:
                self._call(action.call, body, "        ", check=False)  # type: ignore[union-attr]
            body.append("    except (Abandoned, SoarError) as error:")
            body.append("        report(agent, inst, error)")
        head = [
            "def program(agent, b, inst, o_support, operators):",
            "    append = inst.prefs.append",
            "    level = inst.goal.level",
            "    new_id = agent._new_id",
        ]
        for var, local in self.locals.items():
            reader = "b[{}]" if var in self.bound else "b.get({})"
            head.append(f"    {local} = {reader.format(self._const(var))}")
        return define(head + body, self.namespace, "program", f"<actions of {self.name}>")

    def _const(self, value: object) -> str:
        key = f"K{len(self.namespace)}"
        self.namespace[key] = value
        return key

    def _make(self, action: MakeAction, out: list[str]) -> None:
        ind = "        "
        ident = self._value(action.id, out, ind)
        out.append(f"{ind}if type({ident}) is not Identifier:")
        out.append(
            f"{ind}    raise not_an_identifier({self._const(action)},"
            f" {self._const(self.bound)}, {ident})"
        )
        # new identifiers after the first start at the level of the augmented identifier
        # (see _make_preference)
        self.level = f"agent._level_of({ident})"
        attr = self._value(action.attr, out, ind)
        value = self._value(action.value, out, ind)
        ptype = self._const(action.preference)
        referent = "None"
        if action.referent is not None:
            referent = self._value(action.referent, out, ind)
            ptype = f"preference_type({ptype}, {referent})"
        self.level = "level"
        if NATIVE:  # mypyc's native Preference: its constructor is C, object.__new__ refused
            out += [
                f"{ind}p = Preference({ptype}, {ident}, {attr}, {value}, {referent}, inst)",
                f"{ind}p.o_supported = o_support and {ident} not in operators",
                f"{ind}append(p)",
            ]
            return
        out += [
            # Preference.__init__, inline: CPython 3.11 runs a class's Python __init__
            # through a C call into a new interpreter frame
            f"{ind}p = NEW(Preference); p.type = {ptype}; p.id = {ident}; p.attr = {attr}",
            f"{ind}p.value = {value}; p.referent = {referent}; p.inst = inst",
            f"{ind}p.o_supported = o_support and {ident} not in operators",
            f"{ind}p.slot = None; p.live = False",
            f"{ind}append(p)",
        ]

    def _value(self, node: RhsValue, out: list[str], ind: str) -> str:
        """An expression naming the node's value, after the statements that compute it."""
        kind = type(node)
        if kind is Var:
            local = self.locals.get(node.name)  # type: ignore[union-attr]
            if local is None:
                local = self.locals[node.name] = f"v{len(self.locals)}"  # type: ignore[union-attr]
            if node.name not in self.bound:  # type: ignore[union-attr]
                out.append(f"{ind}if {local} is None:")
                hint = self._const(rhs_id_hint(node.name))  # type: ignore[union-attr]
                out.append(f"{ind}    {local} = new_id({hint}, {self.level})")
            return local
        if kind is Const:
            return self._const(node.value)  # type: ignore[union-attr]
        if kind is FuncCall:
            return self._call(node, out, ind, check=True)  # type: ignore[arg-type]
        out.append(f"{ind}raise SoarRuntimeError({self._const(f'cannot evaluate {node!r}')})")
        return "None"

    def _call(self, call: FuncCall, out: list[str], ind: str, check: bool) -> str:
        """A function call; as a value (``check``) it must return one."""
        function = FUNCTIONS.get(call.name)
        if function is None:
            message = f"unknown RHS function ({call.name})"
            out.append(f"{ind}raise SoarRuntimeError({self._const(message)})")
            return "None"
        args = []
        for index, arg in enumerate(call.args):
            if type(arg) is not FuncCall:  # a variable or constant: cannot fail
                args.append(self._value(arg, out, ind))
                continue
            out.append(f"{ind}try:")
            args.append(self._value(arg, out, ind + "    "))
            out.append(f"{ind}except (Abandoned, SoarError) as error:")
            out.append(f"{ind}    report(agent, inst, error)")
            self._evaluate_rest(call.args[index + 1 :], out, ind + "    ")
            out.append(f"{ind}    raise Abandoned")
        temp = f"t{self.temps}"
        self.temps += 1
        generic = f"{self._const(function)}(agent, [{', '.join(args)}])"
        if call.name in ("+", "-") and len(args) == 2:
            self._int_arithmetic(call, args, temp, generic, out, ind)
        else:
            out.append(f"{ind}{temp} = {generic}")
        if check:
            message = f"({call.name}) returns no value"
            out.append(f"{ind}if {temp} is None:")
            out.append(f"{ind}    raise SoarRuntimeError({self._const(message)})")
        return temp

    @staticmethod
    def _int_arithmetic(call: FuncCall, args: list[str], temp: str, generic: str,
                        out: list[str], ind: str) -> None:
        """``(+ a b)`` or ``(- a b)`` of two integers (``(+ <k> 1)``, the usual counter)
        without the generic function's argument list and calls: the result when it fits
        the kernel's 64 bits. Anything else (a float, a non-number, an overflow) goes to the
        generic function, which mixes, complains or wraps around as the kernel does."""
        checks = [f"type({arg}) is int" for arg, node in zip(args, call.args, strict=True)
                  if type(node) is not Const or type(node.value) is not int]
        test = " and ".join(checks) or "True"
        out.append(f"{ind}{temp} = {args[0]} {call.name} {args[1]} if {test} else None")
        out.append(f"{ind}if {temp} is None or not {-(1 << 63)} <= {temp} < {1 << 63}:")
        out.append(f"{ind}    {temp} = {generic}")

    def _evaluate_rest(self, args: Sequence[RhsValue], out: list[str], ind: str) -> None:
        """After a failed argument, the call's other arguments, for their errors and new
        identifiers only (the kernel evaluates them all)."""
        for arg in args:
            if type(arg) is FuncCall:
                out.append(f"{ind}try:")
                self._value(arg, out, ind + "    ")
                out.append(f"{ind}except (Abandoned, SoarError) as error:")
                out.append(f"{ind}    report(agent, inst, error)")
            else:
                self._value(arg, out, ind)


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
        "source",
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
        # a justification's substate: its retraction is that goal's (see Agent)
        self.source: Goal | None = None

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


#: ``is_o_supported``'s answer for a match that elaborates the operator it tests and also
#: applies it: the kernel warns and gives all its preferences i-support (measured).
MIXED = "mixed"


def is_o_supported(
    info: ProductionInfo, wmes: tuple[WME | None, ...], goal: Identifier, match: object = None
) -> bool | str:
    """Whether this match fires as an o-assertion (PE) rather than an i-assertion (IE).

    It does when the match tests the selected operator of its goal and some action is not an
    elaboration of that operator -- unless another action is one: then it is ``MIXED``, an
    i-assertion with the kernel's warning."""
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
    bindings: dict[str, Symbol] = (
        match.bindings if match is not None else {})  # type: ignore[attr-defined]
    if info.proposal_ids and _proposes_on_a_state(info, bindings):
        return False
    applies = elaborates = False
    for name in make_ids:
        value = bindings.get(name)
        if value is None:
            applies = True
        elif type(value) is Identifier:
            if value in operators:  # identifiers are equal only to themselves
                elaborates = True
            else:
                applies = True
        elif any(value is op for op in operators):
            elaborates = True
        else:
            applies = True
    if applies and elaborates:
        return MIXED
    return applies


def _proposes_on_a_state(info: ProductionInfo, bindings: dict) -> bool:
    """Whether the match proposes an operator on a state. The kernel gives such a match
    i-support even when it tests the selected operator (measured in soar_sml: a rule
    testing ^operator.name go that proposes another operator on its own state or on
    the superstate fires as IE, its preferences without :O; a proposal on a non-state
    identifier, or a lone better preference, still fires as PE)."""
    for name in info.proposal_ids:
        ident = bindings.get(name)
        if type(ident) is Identifier and ident.level is not None:
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
