"""The grammar's rules turned into the dataclasses of `sann.soar.production`, one small method
per rule of ``soar.lark``.

The transformer normalises Soar's surface syntax as the kernel does: ``^a.b.c`` paths become
chains through fresh variables (named once the production is complete: `normalise`), a
missing value or identifier test becomes a fresh variable, ``^a v1 v2`` one condition per
value, ``-( ... )`` of several conditions a conjunctive negation, several preferences on one
value several actions, and preferences other than ``+``/``-`` off ``^operator`` are dropped
with a `SoarWarning`. A finished production then gets the kernel's load-time checks
(`actions.check_production`, `rete.kernel_refusals`) and warnings (`rete.load_warnings`).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Collection, Iterator
from dataclasses import dataclass
from typing import Literal

from lark import Token, Transformer

from sann.soar.errors import SoarSyntaxError
from sann.soar.parsing.actions import KNOWN_RHS_FUNCTIONS, SHELL_REFUSAL, check_production
from sann.soar.parsing.checks import load_warnings
from sann.soar.parsing.errors import syntax_error
from sann.soar.parsing.normalise import (
    TEMPORARY,
    drop_unbound_relations,
    first_letter,
    fresh_names,
    negate,
    rename_action,
    rename_element,
)
from sann.soar.printer import format_rhs_value
from sann.soar.production import (
    Action,
    CallAction,
    Command,
    Condition,
    ConditionElement,
    Conjunction,
    Const,
    Disjunction,
    FuncCall,
    MakeAction,
    Production,
    Relational,
    RhsValue,
    SourceLocation,
    Test,
    Var,
)

__all__ = ["ToDataclasses"]

GoalKeyword = Literal["state", "impasse"]


# ----------------------------------------------------------------- intermediate structures


@dataclass(frozen=True)
class _Goal:
    keyword: GoalKeyword


@dataclass(frozen=True)
class _AttrValueTests:
    """One ``-^a.b v1 v2 +`` inside a parenthesised condition, before normalisation."""

    negated: bool
    path: tuple[Test, ...]
    values: tuple[tuple[Test, bool], ...]


@dataclass(frozen=True)
class _Preference:
    op: str
    token: Token


@dataclass(frozen=True)
class _AttrValueMake:
    """One ``^a.b v1 > v2 v3 -`` of an action: the path and each value's preferences."""

    path: tuple[RhsValue, ...]
    values: tuple[tuple[RhsValue, tuple[tuple[str, RhsValue | None], ...]], ...]


def _unescape(body: str) -> str:
    return re.sub(r"\\(.)", r"\1", body, flags=re.S)


def _argument(item: str) -> str:
    """A command argument as plain text: a word, a "string" unquoted, or a {braced} group."""
    if isinstance(item, Token) and item.type == "DQSTRING":
        return _unescape(item[1:-1])
    return str(item)


class ToDataclasses(Transformer):
    """Grammar rules -> production dataclasses, one small method per rule.

    Used as Lark's inline transformer: the LALR parser calls a method at each reduction with
    the already-transformed children, so no parse tree is built."""

    def __init__(self) -> None:
        super().__init__()
        self.reset("", "<string>", KNOWN_RHS_FUNCTIONS)

    def reset(self, text: str, file: str, functions: Collection[str]) -> None:
        """Start a new parse (the instance is shared: see `parser._parser`)."""
        self.text = text
        self.file = file
        self.functions = functions
        self._fresh = 0
        self._fresh_names: list[str] = []  # this production's fresh variables, in order
        self._used: set[str] = set()  # this production's own variable names
        self._warnings: list[str] = []  # this production's, until its name is known
        self.warnings: list[str] = []  # issued by `parse` to its caller
        self.completed: list[Production | Command] = []  # for `parse_partial` on an error

    # -- helpers

    def _fresh_variable(self, letter: str) -> Var:
        self._fresh += 1
        name = f"{TEMPORARY}{self._fresh}{TEMPORARY}{letter}"
        self._fresh_names.append(name)
        return Var(name)

    def _syntax_error(self, message: str, line: int, column: int) -> SoarSyntaxError:
        return syntax_error(self.text, self.file, message, line, column)

    def _location(self, token: Token) -> SourceLocation:
        return SourceLocation(self.file, token.line or 1, token.column or 1)

    # -- file and commands

    def start(self, items: list) -> list:
        return list(items)

    def command(self, items: list) -> Command:
        name, *args = items
        command = Command(str(name), tuple(_argument(arg) for arg in args), self._location(name))
        self.completed.append(command)
        return command

    def shell_command(self, items: list) -> None:
        name = items[0]
        raise self._token_error(name, f"'{name}' is refused: {SHELL_REFUSAL}")

    def braced(self, items: list) -> str:
        """A {braced} argument is its text between the braces, verbatim (as in Soar's CLI)."""
        return self.text[items[0].end_pos : items[-1].start_pos]

    # -- constants and tests

    def variable(self, items: list) -> Var:
        name = items[0][1:-1]
        self._used.add(name)
        return Var(name)

    def symbol(self, items: list) -> Const:
        return Const(str(items[0]))

    def idlike(self, items: list) -> Const:
        return Const(str(items[0]).upper())

    def qstring(self, items: list) -> Const:
        return Const(_unescape(items[0][1:-1]))

    def integer(self, items: list) -> Const:
        value = int(items[0])
        if not -(2**63) <= value < 2**63:  # the kernel says "bad integer" and stores garbage
            raise self._number_error(items[0], "integer does not fit in 64 bits")
        return Const(value)

    def float(self, items: list) -> Const:
        value = float(_float_text(items[0]))
        if value in (float("inf"), float("-inf")):
            raise self._number_error(items[0], "float is too large")
        return Const(value)

    def _number_error(self, token: Token, problem: str) -> SoarSyntaxError:
        return self._token_error(token, f"bad number '{token}': {problem}")

    def _token_error(self, token: Token, message: str) -> SoarSyntaxError:
        return self._syntax_error(message, token.line or 1, token.column or 1)

    def relation(self, items: list) -> str:
        return str(items[0])

    def relational_test(self, items: list) -> Test:
        op, operand = items
        return operand if op == "=" else Relational(op, operand)

    def disjunction_test(self, items: list) -> Disjunction:
        return Disjunction(tuple(items[1:-1]))

    def conjunctive_test(self, items: list) -> Test:
        return items[0] if len(items) == 1 else Conjunction(tuple(items))

    # -- conditions

    def goal(self, items: list) -> _Goal:
        return _Goal("impasse" if items[0] == "impasse" else "state")  # the grammar's only two

    def attr_path(self, items: list) -> tuple[Test, ...]:
        return tuple(items)

    def value_test(self, items: list) -> tuple[Test, bool]:
        return items[0], len(items) == 2

    def attr_value_tests(self, items: list) -> _AttrValueTests:
        negated = isinstance(items[0], Token) and items[0].type == "MINUS"
        path, *values = items[1:] if negated else items
        return _AttrValueTests(negated, path, tuple(values))

    def conds_for_one_id(self, items: list) -> list[ConditionElement]:
        close = items.pop()
        del items[0]
        goal: GoalKeyword | None = None
        if items and isinstance(items[0], _Goal):
            goal = items.pop(0).keyword
        has_id = bool(items) and not isinstance(items[0], _AttrValueTests)
        letter = "i" if goal == "impasse" else "s"
        id_test = items.pop(0) if has_id else self._fresh_variable(letter)
        if goal and not items:
            raise self._token_error(
                close,
                f"expected an attribute test after '({goal}': add one such as "
                "'^type state' or '^superstate nil'",
            )
        elements: list[ConditionElement] = []
        for avt in items:
            elements.extend(self._expand_tests(id_test, goal, avt))
        return elements

    def _expand_tests(
        self, id_test: Test, goal: GoalKeyword | None, avt: _AttrValueTests
    ) -> list[ConditionElement]:
        """One attribute test with its path and values -> conditions (kernel order)."""
        chain: list[Condition] = []
        ident: Test = id_test
        for step in avt.path[:-1]:
            link = self._fresh_variable(first_letter(step))
            chain.append(Condition(ident, step, link, goal=goal if ident is id_test else None))
            ident = link
        attr = avt.path[-1]
        values = avt.values or ((self._fresh_variable(first_letter(attr)), False),)
        step_goal = goal if ident is id_test else None
        last = [Condition(ident, attr, v, acceptable=plus, goal=step_goal) for v, plus in values]
        return negate([*chain, *last]) if avt.negated else [*chain, *last]

    def condition(self, items: list) -> list[ConditionElement]:
        return items[0]

    def condition_group(self, items: list) -> list[ConditionElement]:
        return [element for group in items for element in group]

    def negated_condition(self, items: list) -> list[ConditionElement]:
        return negate(items[1])

    # -- actions

    def preference(self, items: list) -> _Preference:
        return _Preference(str(items[0]), items[0])

    def value_item(self, items: list) -> object:
        return items[0]

    def rhs_path(self, items: list) -> tuple[RhsValue, ...]:
        return tuple(items)

    def attr_value_make(self, items: list) -> _AttrValueMake:
        path, *rest = items
        return _AttrValueMake(path, tuple(self._resolve_preferences(rest)))

    def _resolve_preferences(
        self, items: list
    ) -> Iterator[tuple[RhsValue, tuple[tuple[str, RhsValue | None], ...]]]:
        """Soar's rule: a binary sign (``> < =``) takes the next item as its referent when
        that is a value, else it is unary (``< -`` is worse-than-all, then reject);
        ``+ - ! ~`` are always unary; one comma may follow a value or a preference."""
        i = 0
        while i < len(items):
            value = items[i]
            if isinstance(value, Token | _Preference):
                raise self._item_error(value, "a value before the preference")
            i += 1
            if i < len(items) and _is_comma(items[i]):
                i += 1  # the kernel reads `^a b, +` like `^a b +`
            prefs: list[tuple[str, RhsValue | None]] = []
            while i < len(items) and isinstance(items[i], _Preference):
                pref = items[i]
                following = items[i + 1] if i + 1 < len(items) else None
                if pref.op in "><=" and following is not None and _is_value(following):
                    prefs.append((pref.op, following))
                    i += 2
                else:
                    prefs.append((pref.op, None))
                    i += 1
                if i < len(items) and _is_comma(items[i]):
                    i += 1
            yield value, tuple(prefs) or (("+", None),)

    def _item_error(self, item: Token | _Preference, expected: str) -> SoarSyntaxError:
        token = item.token if isinstance(item, _Preference) else item
        return self._token_error(token, f"unexpected '{token}' in an action: expected {expected}")

    def make_action(self, items: list) -> list[Action]:
        ident, *makes = items
        actions: list[Action] = []
        for make in makes:
            actions.extend(self._expand_make(ident, make))
        return actions

    def _expand_make(self, ident: Var, make: _AttrValueMake) -> list[Action]:
        actions: list[Action] = []
        for step in make.path[:-1]:
            link = self._fresh_variable(first_letter(step))
            actions.append(MakeAction(ident, step, link))
            ident = link
        attr = make.path[-1]
        for value, prefs in make.values:
            if attr != Const("operator"):
                prefs = self._non_operator_preferences(attr, prefs)
            for op, referent in prefs:
                actions.append(MakeAction(ident, attr, value, op, referent))
        return actions

    def _non_operator_preferences(
        self, attr: RhsValue, prefs: tuple[tuple[str, RhsValue | None], ...]
    ) -> tuple[tuple[str, RhsValue | None], ...]:
        """The kernel's rule off ``^operator``: each ``-`` is a reject; every other unary sign
        counts as ``+`` (with a warning), and one acceptable is made only if nothing rejects.
        Binary preferences stay, for `actions.check_production` to refuse."""
        for op, referent in prefs:
            if referent is None and op not in "+-":
                self._warnings.append(
                    f"preference '{op}' on the non-operator attribute ^{format_rhs_value(attr)} "
                    "is ignored, as in Soar (only + and - apply there)"
                )
        binary = tuple(p for p in prefs if p[1] is not None)
        rejects = tuple(p for p in prefs if p == ("-", None))
        return binary + (rejects or (("+", None),))

    def function_name(self, items: list) -> str:
        token = items[0]
        return str(token).upper() if token.type == "IDLIKE" else str(token)

    def function_call(self, items: list) -> FuncCall:
        return FuncCall(items[0], tuple(items[1:]))

    def call_action(self, items: list) -> list[Action]:
        return [CallAction(items[0])]

    # -- productions

    def production_name(self, items: list) -> Token:
        token = items[0]
        if token.type == "IDLIKE":
            raise self._token_error(
                token,
                f"production name '{token}' looks like an identifier (a letter and digits); "
                "Soar refuses it: choose another name",
            )
        return token

    def doc(self, items: list) -> tuple[str]:
        return (_unescape(items[0][1:-1]),)

    def flag(self, items: list) -> str:
        return str(items[0])[1:]

    def production(self, items: list) -> Production:
        sp, name_token, *rest = items
        name = str(name_token)
        if name_token.type == "QSTRING":
            name = _unescape(name[1:-1])
        doc = rest.pop(0)[0] if rest and isinstance(rest[0], tuple) else None
        flags = []
        while rest and isinstance(rest[0], str):
            flags.append(rest.pop(0))
        arrow = next(i for i, item in enumerate(rest) if isinstance(item, Token))
        conditions = [c for group in rest[:arrow] for c in group]
        actions = [a for group in rest[arrow + 1 :] for a in group]
        production = Production(
            name,
            drop_unbound_relations(tuple(conditions), set(), self._fresh_variable),
            tuple(actions),
            doc,
            tuple(flags),
            self._location(sp),
        )
        if self._fresh_names:
            names = fresh_names(self._fresh_names, self._used)
            production = dataclasses.replace(
                production,
                conditions=tuple(rename_element(c, names) for c in production.conditions),
                actions=tuple(rename_action(a, names) for a in production.actions),
            )
        self._fresh_names.clear()
        self._used.clear()
        production = check_production(production, self.functions)
        self._warnings.extend(load_warnings(production))
        self.warnings.extend(_where(production) + message for message in self._warnings)
        self._warnings.clear()
        self.completed.append(production)
        return production


def _float_text(text: str) -> str:
    """Soar accepts ``1.5e`` and ``2.e+``: an exponent without digits counts as none."""
    return re.sub(r"[eE][+-]?$", "", text)


def _where(production: Production) -> str:
    location = production.location
    prefix = f"{location.file}:{location.line}: " if location else ""
    return f"{prefix}production {production.name}: "


def _is_value(item: object) -> bool:
    return not isinstance(item, Token | _Preference)


def _is_comma(item: object) -> bool:
    return isinstance(item, Token) and item.type == "COMMA"
