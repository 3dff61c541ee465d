"""The load-time checks of a production's right-hand side, and the kernel's order of its
actions.

What the kernel checks when it loads a production (measured in soar_sml 9.6): RHS actions
whose identifier is not grounded, binary preferences off ``^operator``, RHS functions called
where they may not be (a value-only function as a stand-alone action or the reverse) or with
the wrong number of arguments; plus our own refusal of unknown RHS functions (the kernel would
turn them into ``exec``), of ``exec``/``cmd``, ``accept`` and ``link-stm-to-ltm`` (see
`REFUSED_RHS_FUNCTIONS`) and of Soar-RL ``:template`` rules. The checks of the left-hand side
(a root for the match, connected conditions) are `rete.kernel_refusals` and
`rete.load_warnings`.

The kernel's order of the actions (`reorder_actions`): an action that reads a variable another
action makes comes after it, as the kernel runs and prints them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Iterator

from sann.soar.errors import SoarSemanticError
from sann.soar.parsing.checks import kernel_refusals
from sann.soar.parsing.normalise import lhs_bound
from sann.soar.printer import format_action
from sann.soar.production import Action, CallAction, Const, FuncCall, MakeAction, Production, Var

__all__ = [
    "KNOWN_RHS_FUNCTIONS",
    "REFUSED_RHS_FUNCTIONS",
    "SHELL_REFUSAL",
    "STAND_ALONE_RHS_FUNCTIONS",
    "VALUE_RHS_FUNCTIONS",
    "RhsNames",
    "check_production",
    "reorder_actions",
]


class RhsNames(frozenset[str]):
    """RHS function names without the kernel's rules for calling them: a parse given these
    checks only that each called function exists, not where it is called nor with how many
    arguments. Any other collection of names gets the kernel's checks (see `parse`)."""


#: The right-hand-side functions a production may call when text is parsed without an engine
#: (a subset of what the agent's `sann.soar.rhs` implements; the agent passes its own).
KNOWN_RHS_FUNCTIONS: RhsNames = RhsNames(
    {
        "write", "crlf", "halt", "interrupt",
        "+", "-", "*", "/", "div", "mod", "abs", "int", "float",
        "concat", "make-constant-symbol", "timestamp",
    }
)  # fmt: skip

#: The kernel's functions that only make a value, with the number of arguments each takes
#: (None: any number). Measured in soar_sml 9.6: as a stand-alone action each is refused
#: with "Function X cannot be used as a stand-alone action", a wrong count with "Wrong
#: number of arguments to function X (expected N)".
VALUE_RHS_FUNCTIONS: dict[str, int | None] = {
    "+": None, "-": None, "*": None, "/": None, "div": 2, "mod": 2, "abs": 1, "int": 1,
    "float": 1, "sqrt": 1, "sin": 1, "cos": 1, "atan2": 2, "min": None, "max": None,
    "round-off": 2, "concat": None, "make-constant-symbol": None, "timestamp": 0, "crlf": 0,
    "dc": 0, "ifeq": 4, "trim": 1, "strlen": 1, "rand-int": None, "rand-float": None,
    "capitalize-symbol": 1, "string": 1, "size": 1, "deep-copy": 1, "compute-heading": 4,
    "compute-range": 4, "round-off-heading": 2, "accept": 0, "set-count": None,
    "sum": 1, "product": 1, "set-sum": None, "set-multiply": None, "set-min": None,
    "set-max": None, "set-range": None, "set-mean": None, "set-stdev": None, "haversine": 4,
    "compute-dice-probability": 4, "extrapolate-x-position": 4, "extrapolate-y-position": 4,
}  # fmt: skip

#: The kernel's functions that may only be stand-alone actions ("Function X can only be
#: used as a stand-alone action" inside a value), with their numbers of arguments.
STAND_ALONE_RHS_FUNCTIONS: dict[str, int | None] = {
    "write": None, "halt": 0, "interrupt": 0, "dont-learn": 1, "force-learn": 1,
    "log": None, "link-stm-to-ltm": 2, "count": None, "wait": 1,
}  # fmt: skip

#: Why ``exec``, ``cmd`` and the shell commands of a rule file are refused.
SHELL_REFUSAL = "a rule file never runs shell commands or Python"

#: Kernel functions a rule file may not call here, and why.
_REFUSALS: dict[str, str] = {
    "exec": SHELL_REFUSAL,
    "cmd": SHELL_REFUSAL,
    "accept": "it reads a line from standard input, and a rule file never waits for input",
    "link-stm-to-ltm": "semantic memory is not part of this engine",
}

#: Functions that would run shell commands or read input, or that this engine lacks the
#: memories for: never allowed in a rule file.
REFUSED_RHS_FUNCTIONS: frozenset[str] = frozenset(_REFUSALS)


def check_production(production: Production, functions: Collection[str]) -> Production:
    """The load-time checks of the kernel (and our refusal of exec/cmd and templates); the
    production comes back with its actions in the kernel's order (`reorder_actions`)."""
    if "template" in production.flags:
        raise SoarSemanticError(
            production.name,
            "':template' (a Soar-RL template) is not supported: reinforcement learning is not "
            "part of this engine",
            production.location,
        )
    checked = not isinstance(functions, RhsNames)
    for action in production.actions:
        stand_alone = action.call if isinstance(action, CallAction) else None
        for call in _calls(action):
            _check_function(production, call, functions)
            if checked:
                _check_signature(production, call, call is stand_alone)
            _check_refusal(production, call)
    kernel_refusals(production)
    actions = reorder_actions(production)
    _check_binary_preferences(production)
    if actions != production.actions:
        production = dataclasses.replace(production, actions=actions)
    return production


def _check_function(production: Production, call: FuncCall, functions: Collection[str]) -> None:
    if call.name not in functions and call.name not in _REFUSALS:
        known = " ".join(sorted(functions))
        raise SoarSemanticError(
            production.name,
            f"unknown RHS function '{call.name}' (known functions: {known})",
            production.location,
        )


def _check_refusal(production: Production, call: FuncCall) -> None:
    reason = _REFUSALS.get(call.name)
    if reason is not None:
        _refuse_call(production, f"RHS function '{call.name}' is refused: {reason}")


def _check_signature(production: Production, call: FuncCall, stand_alone: bool) -> None:
    """The kernel's checks, in its order: where the function is called, then how many
    arguments it has. Functions the kernel does not know are not checked."""
    name = call.name
    if name in STAND_ALONE_RHS_FUNCTIONS:
        expected = STAND_ALONE_RHS_FUNCTIONS[name]
        if not stand_alone:
            _refuse_call(production, f"Function {name} can only be used as a stand-alone action")
    elif name in VALUE_RHS_FUNCTIONS:
        expected = VALUE_RHS_FUNCTIONS[name]
        if stand_alone:
            _refuse_call(production, f"Function {name} cannot be used as a stand-alone action")
    else:
        return
    if expected is not None and len(call.args) != expected:
        _refuse_call(
            production, f"Wrong number of arguments to function {name} (expected {expected})"
        )


def _refuse_call(production: Production, message: str) -> None:
    raise SoarSemanticError(production.name, message, production.location)


def reorder_actions(production: Production) -> tuple[Action, ...]:
    """The kernel's order of the actions (reorder.cpp's ``reorder_action_list``), which is
    the order it executes them in and prints them: again and again, the first remaining
    action that can run is taken. An action can run when the variables it reads are bound
    (tested in a positive condition, or made by an action taken before): a make-action
    reads its identifier and the variables inside its function calls; a function-call
    action all its variables. Once taken, a make-action binds every variable it holds (an
    unbound attribute, value or referent is a new identifier). Measured in soar_sml 9.6:
    ``(write 1) (<s> ^a (+ 1 <n>)) (write 2) (<s> ^b <n>)`` runs and prints as ``(write 1)
    (write 2) (<s> ^b <n>) (<s> ^a (+ 1 <n>))``, the WMEs' timetags in that order. An
    action that never can run is the kernel's "ungrounded action" refusal."""
    bound = lhs_bound(production.conditions)
    remaining = list(production.actions)
    ordered: list[Action] = []
    while remaining:
        action = next((a for a in remaining if not _ungrounded(a, bound)), None)
        if action is None:
            action = remaining[0]
            raise SoarSemanticError(
                production.name,
                f"the action {_describe_action(action)} uses <{_ungrounded(action, bound)[0]}>, "
                "which is neither tested in a positive condition on the LHS nor created by "
                "another action",
                production.location,
            )
        remaining.remove(action)
        ordered.append(action)
        if type(action) is MakeAction:
            for value in (action.id, action.attr, action.value, action.referent):
                if type(value) is Var:
                    bound.add(value.name)
    return tuple(ordered)


def _ungrounded(action: Action, grounded: set[str]) -> list[str]:
    if isinstance(action, MakeAction) and action.id.name not in grounded:
        return [action.id.name]
    return [
        arg.name
        for call in _calls(action)
        for arg in call.args
        if isinstance(arg, Var) and arg.name not in grounded
    ]


def _describe_action(action: Action) -> str:
    return format_action(action)


def _check_binary_preferences(production: Production) -> None:
    for action in production.actions:
        if (
            isinstance(action, MakeAction)
            and action.referent is not None
            and action.attr != Const("operator")
        ):
            raise SoarSemanticError(
                production.name,
                f"binary preference '{action.preference}' in {_describe_action(action)}: "
                "binary preferences are legal only on ^operator",
                production.location,
            )


def _calls(value: object) -> Iterator[FuncCall]:
    """Every function call in an action or RHS value, outermost first."""
    if isinstance(value, CallAction):
        yield from _calls(value.call)
    elif isinstance(value, MakeAction):
        for part in (value.attr, value.value, value.referent):
            yield from _calls(part)
    elif isinstance(value, FuncCall):
        yield value
        for arg in value.args:
            yield from _calls(arg)
