"""Print productions and commands back in canonical Soar syntax, as the kernel's ``print``.

The layout follows Soar 9.6's ``print <name>``: the name on the ``sp {`` line, the
documentation string and the flags on their own lines, one parenthesised condition per
identifier (consecutive conditions on the same identifier are grouped, negated ones as
``-^attr value``), conjunctive negations as ``-{ ... }``, then ``-->`` and the actions,
grouped the same way. Unlike the kernel we do not reorder conditions, and floats are printed
with every digit they have (the kernel prints six decimals, which loses precision), so that
``parse(format_production(p)) == [p]`` for every production the parser can produce.
The actions come in the kernel's order (the parser puts them so); the kernel gathers every
make-action on one identifier into one group, we only consecutive ones, which keeps the
order of the actions when the text is read back.
"""

from __future__ import annotations

import re

from sann.soar.production import (
    Action,
    CallAction,
    Command,
    Condition,
    ConditionElement,
    Conjunction,
    ConjunctiveNegation,
    Const,
    Disjunction,
    FuncCall,
    MakeAction,
    Production,
    Relational,
    RhsValue,
    Test,
    Var,
)
from sann.soar.text import format_constant

__all__ = [
    "format_action",
    "format_command",
    "format_condition",
    "format_production",
    "format_rhs_value",
    "format_test",
]

INDENT = "    "


def format_test(test: Test, keyword_safe: bool = False) -> str:
    """One test: ``<x>``, ``abc``, ``> 3``, ``<< a b >>``, ``{ <x> <> 3 }``."""
    if isinstance(test, Var):
        return f"<{test.name}>"
    if isinstance(test, Const):
        return format_constant(test.value, keyword_safe)
    if isinstance(test, Relational):
        return f"{test.op} {format_test(test.operand)}"
    if isinstance(test, Disjunction):
        return " ".join(["<<", *(format_constant(c.value) for c in test.values), ">>"])
    if isinstance(test, Conjunction):
        return "{ " + " ".join(format_test(t) for t in test.tests) + " }"
    raise TypeError(f"not a Soar test: {test!r}")


def _attribute_test(condition: Condition) -> str:
    sign = "-" if condition.negated else ""
    plus = " +" if condition.acceptable else ""
    attr, value = format_test(condition.attr_test), format_test(condition.value_test)
    return f"{sign}^{attr} {value}{plus}"


def _condition_group(conditions: list[Condition]) -> str:
    first = conditions[0]
    head = f"{first.goal} " if first.goal else ""
    ident = format_test(first.id_test, keyword_safe=True)
    tests = " ".join(_attribute_test(c) for c in conditions)
    text = f"({head}{ident} {tests})"
    if len(conditions) == 1 and first.negated:  # -(<x> ^a b) reads better than (<x> -^a b)
        text = "-" + text.replace(" -^", " ^", 1)
    return text


def _same_group(a: ConditionElement, b: ConditionElement) -> bool:
    return (
        isinstance(a, Condition)
        and isinstance(b, Condition)
        and a.id_test == b.id_test
        and a.goal == b.goal
    )


def _groups(items: tuple) -> list[list]:
    """Split into runs that share an identifier (and goal keyword, for conditions)."""
    runs: list[list] = []
    for item in items:
        if runs and _joinable(runs[-1][-1], item):
            runs[-1].append(item)
        else:
            runs.append([item])
    return runs


def _joinable(a: object, b: object) -> bool:
    if isinstance(a, MakeAction) and isinstance(b, MakeAction):
        return a.id == b.id
    return _same_group(a, b)  # type: ignore[arg-type]


def _condition_lines(elements: tuple[ConditionElement, ...], indent: str) -> list[str]:
    lines: list[str] = []
    for run in _groups(elements):
        if isinstance(run[0], ConjunctiveNegation):
            inner = _condition_lines(run[0].conditions, indent + "  ")
            inner[0] = indent[:-1] + "-{ " + inner[0].lstrip()
            inner[-1] += "}"
            lines.extend(inner)
        else:
            lines.append(indent + _condition_group(run))
    return lines


def format_condition(element: ConditionElement) -> str:
    """One condition element on its own (for messages and traces)."""
    return "\n".join(line.strip() for line in _condition_lines((element,), INDENT))


def format_rhs_value(value: RhsValue) -> str:
    """A right-hand-side value: a variable, a constant or a function call."""
    if isinstance(value, FuncCall):
        args = "".join(" " + format_rhs_value(arg) for arg in value.args)
        return f"({value.name}{args})"
    return format_test(value)


def _make_text(action: MakeAction) -> str:
    text = f"^{format_rhs_value(action.attr)} {format_rhs_value(action.value)}"
    # Like the kernel: `+` is written on ^operator (a proposal), implied elsewhere.
    if action.preference != "+" or action.attr == Const("operator"):
        text += f" {action.preference}"
    if action.referent is not None:
        text += f" {format_rhs_value(action.referent)}"
    return text


def _action_group(run: list[Action]) -> str:
    first = run[0]
    if isinstance(first, CallAction):
        return format_rhs_value(first.call)
    makes = " ".join(_make_text(action) for action in run)  # type: ignore[arg-type]
    return f"(<{first.id.name}> {makes})"  # type: ignore[union-attr]


def format_action(action: Action) -> str:
    """One action: ``(<s> ^a b +)`` or ``(write |hi|)``."""
    return _action_group([action])


def format_production(production: Production) -> str:
    """The production in canonical Soar syntax; parsing it gives the same production."""
    lines = ["sp {" + format_constant(production.name)]
    if production.doc is not None:
        doc = production.doc.replace("\\", "\\\\").replace('"', '\\"')
        lines.append(f'{INDENT}"{doc}"')
    lines.extend(f"{INDENT}:{flag}" for flag in production.flags)
    lines.extend(_condition_lines(production.conditions, INDENT))
    lines.append(f"{INDENT}-->")
    lines.extend(INDENT + _action_group(run) for run in _groups(production.actions))
    lines.append("}")
    return "\n".join(lines)


def _format_argument(arg: str) -> str:
    if arg and re.fullmatch(r'[^\s;{}"#]+', arg):
        return arg
    return '"' + arg.replace("\\", "\\\\").replace('"', '\\"') + '"'


def format_command(command: Command) -> str:
    """A command line: ``watch 1``, ``source "my rules.soar"``."""
    return " ".join([command.name, *(_format_argument(arg) for arg in command.args)])
