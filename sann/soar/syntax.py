"""Parse Soar 9.6 rule files into the dataclasses of `sann.soar.production`.

API: `parse` (a file's productions and commands, in order), `parse_partial` (what precedes
the first error, and the error: how the kernel loads a file), `parse_file`,
`parse_production`, and `KNOWN_RHS_FUNCTIONS`.

The grammar lives in ``grammars/soar.lark`` (LALR(1), contextual lexer). This module holds
what a grammar cannot say:

- a post-lexer that makes newlines and ``;`` white space inside braces (commands end at a
  newline or ``;``, productions span lines);
- an inline transformer, one small method per grammar rule, that normalises Soar's surface
  syntax as the kernel does: ``^a.b.c`` paths become chains through fresh variables named
  like the kernel's (``<a*1>``, ``<b*1>``: the first letter of the attribute and a counter per
  letter that skips names the production already uses), a missing value or identifier test
  becomes a fresh variable, ``^a v1 v2`` one condition per value, ``-( ... )`` of several
  conditions a conjunctive negation, several preferences on one value several actions, and
  preferences other than ``+``/``-`` off ``^operator`` are dropped with a `SoarWarning`;
- the kernel's load-time rewriting of conditions: a relational test of a positive condition
  on a variable nothing binds is dropped (`_drop_unbound_relations`), and the negation of one
  conjunctive negation is its conditions; and its warnings (`rete.load_warnings`: identifiers
  not connected to a state, conditions not all connected);
- the checks the kernel makes when it loads a production: no root for the match and
  relational tests of negated conditions on unbound variables (`rete.kernel_refusals`),
  ``(state <s>)`` with no attribute
  test, RHS actions whose identifier is not grounded, unbound function arguments, binary
  preferences off ``^operator``, numbers out of range, RHS functions called where they may
  not be (a value-only function as a stand-alone action or the reverse) or with the wrong
  number of arguments — plus our own refusal of unknown RHS functions (the kernel would turn
  them into ``exec``), of ``exec``/``cmd``, ``accept`` and ``link-stm-to-ltm``
  (see `REFUSED_RHS_FUNCTIONS`) and of Soar-RL ``:template`` rules;
- the kernel's order of the actions (`_reorder_actions`): an action that reads a variable
  another action makes comes after it, as the kernel runs and prints them;
- the translation of Lark's exceptions into `SoarSyntaxError` with file, line, column,
  the source line and the expected tokens in words. No Lark exception escapes `parse`.

Known difference from the kernel's naming: the kernel also adds a fresh equality variable to
an attribute or value test that has none (``^b << x y >>`` prints as ``^b { << x y >> <b*1> }``)
which shifts its counters; we keep such tests as written.
"""

from __future__ import annotations

import dataclasses
import re
import sys
import threading
import warnings
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from lark import Lark, Token, Transformer
from lark.exceptions import (
    LarkError,
    UnexpectedCharacters,
    UnexpectedEOF,
    UnexpectedInput,
    UnexpectedToken,
)

from sann.soar.errors import SoarSemanticError, SoarSyntaxError, SoarWarning
from sann.soar.matching.variables import equality_vars
from sann.soar.parsing.checks import kernel_refusals, load_warnings
from sann.soar.printer import format_action, format_rhs_value
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
    SourceLocation,
    Test,
    Var,
)

__all__ = [
    "GRAMMAR_PATH",
    "KNOWN_RHS_FUNCTIONS",
    "REFUSED_RHS_FUNCTIONS",
    "STAND_ALONE_RHS_FUNCTIONS",
    "VALUE_RHS_FUNCTIONS",
    "RhsNames",
    "parse",
    "parse_file",
    "parse_partial",
    "parse_production",
]

GRAMMAR_PATH = Path(__file__).resolve().parents[2] / "grammars" / "soar.lark"


class RhsNames(frozenset[str]):
    """RHS function names without the kernel's rules for calling them: a parse given these
    checks only that each called function exists, not where it is called nor with how many
    arguments. Any other collection of names gets the kernel's checks (see `parse`)."""


#: The right-hand-side functions a production may call when text is parsed without an engine
#: (a subset of what the agent's rhs.py implements; the agent passes its own).
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

_SHELL = "a rule file never runs shell commands or Python"

#: Kernel functions a rule file may not call here, and why.
_REFUSALS: dict[str, str] = {
    "exec": _SHELL,
    "cmd": _SHELL,
    "accept": "it reads a line from standard input, and a rule file never waits for input",
    "link-stm-to-ltm": "semantic memory is not part of this engine",
}

#: Functions that would run shell commands or read input, or that this engine lacks the
#: memories for: never allowed in a rule file.
REFUSED_RHS_FUNCTIONS: frozenset[str] = frozenset(_REFUSALS)

# Fresh variables get a temporary name no user variable can have (NUL is not a constituent
# character) and are renamed to the kernel's `<a*1>` names once the whole production is known,
# so that the final names skip every name the production already uses.
_TEMPORARY = "\0"


# ------------------------------------------------------------------------------- the parser


class _BraceNewlines:
    """Post-lexer: a newline or `;` ends a command only outside braces; inside them both are
    white space (the kernel reads ``^a b;c`` as two values)."""

    always_accept = ("_NL", "SEMICOLON")

    def process(self, stream: Iterator[Token]) -> Iterator[Token]:
        depth = 0
        for token in stream:
            if token.type == "LBRACE":
                depth += 1
            elif token.type == "RBRACE":
                depth = max(0, depth - 1)
            elif token.type in self.always_accept and depth:
                continue
            yield token


@lru_cache(maxsize=1)
def _parser() -> tuple[Lark, _ToDataclasses]:
    """Build the LALR parser once per process (about 0.1 s).

    The transformer runs inline, called by the parser at each reduction, so no parse tree is
    ever built (twice as fast as transforming a tree). Its per-parse state is reset by
    `parse` under `_LOCK`, which makes parsing thread-safe.
    """
    transformer = _ToDataclasses()
    parser = Lark(
        GRAMMAR_PATH.read_text(encoding="utf-8"),
        parser="lalr",
        lexer="contextual",
        postlex=_BraceNewlines(),
        transformer=transformer,
        maybe_placeholders=False,
    )
    return parser, transformer


_LOCK = threading.Lock()


# ----------------------------------------------------------------- intermediate structures


@dataclass(frozen=True)
class _Goal:
    keyword: str


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


# ----------------------------------------------------------------------- the transformer


def _first_letter(value: object) -> str:
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
                return _first_letter(test)
    return "v"


def _unescape(body: str) -> str:
    return re.sub(r"\\(.)", r"\1", body, flags=re.S)


def _argument(item: str) -> str:
    """A command argument as plain text: a word, a "string" unquoted, or a {braced} group."""
    if isinstance(item, Token) and item.type == "DQSTRING":
        return _unescape(item[1:-1])
    return str(item)


class _ToDataclasses(Transformer):
    """Grammar rules -> production dataclasses, one small method per rule.

    Used as Lark's inline transformer: the LALR parser calls a method at each reduction with
    the already-transformed children, so no parse tree is built."""

    def __init__(self) -> None:
        super().__init__()
        self.reset("", "<string>", KNOWN_RHS_FUNCTIONS)

    def reset(self, text: str, file: str, functions: Collection[str]) -> None:
        """Start a new parse (the instance is shared: see `_parser`)."""
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
        name = f"{_TEMPORARY}{self._fresh}{_TEMPORARY}{letter}"
        self._fresh_names.append(name)
        return Var(name)

    def _syntax_error(self, message: str, line: int, column: int) -> SoarSyntaxError:
        return _syntax_error(self.text, self.file, message, line, column)

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
        raise self._syntax_error(f"'{name}' is refused: {_SHELL}", name.line, name.column)

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
        return self._syntax_error(f"bad number '{token}': {problem}", token.line, token.column)

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
        return _Goal(str(items[0]))

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
        goal = items.pop(0).keyword if items and isinstance(items[0], _Goal) else None
        has_id = bool(items) and not isinstance(items[0], _AttrValueTests)
        letter = "i" if goal == "impasse" else "s"
        id_test = items.pop(0) if has_id else self._fresh_variable(letter)
        if goal and not items:
            raise self._syntax_error(
                f"expected an attribute test after '({goal}': add one such as "
                "'^type state' or '^superstate nil'",
                close.line,
                close.column,
            )
        elements: list[ConditionElement] = []
        for avt in items:
            elements.extend(self._expand_tests(id_test, goal, avt))
        return elements

    def _expand_tests(
        self, id_test: Test, goal: str | None, avt: _AttrValueTests
    ) -> list[ConditionElement]:
        """One attribute test with its path and values -> conditions (kernel order)."""
        chain: list[Condition] = []
        ident: Test = id_test
        for step in avt.path[:-1]:
            link = self._fresh_variable(_first_letter(step))
            chain.append(Condition(ident, step, link, goal=goal if ident is id_test else None))
            ident = link
        attr = avt.path[-1]
        values = avt.values or ((self._fresh_variable(_first_letter(attr)), False),)
        step_goal = goal if ident is id_test else None
        last = [Condition(ident, attr, v, acceptable=plus, goal=step_goal) for v, plus in values]
        return _negate([*chain, *last]) if avt.negated else [*chain, *last]

    def condition(self, items: list) -> list[ConditionElement]:
        return items[0]

    def condition_group(self, items: list) -> list[ConditionElement]:
        return [element for group in items for element in group]

    def negated_condition(self, items: list) -> list[ConditionElement]:
        return _negate(items[1])

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

    def _item_error(self, item: object, expected: str) -> SoarSyntaxError:
        token = item.token if isinstance(item, _Preference) else item
        return self._syntax_error(
            f"unexpected '{token}' in an action: expected {expected}", token.line, token.column
        )

    def make_action(self, items: list) -> list[Action]:
        ident, *makes = items
        actions: list[Action] = []
        for make in makes:
            actions.extend(self._expand_make(ident, make))
        return actions

    def _expand_make(self, ident: Var, make: _AttrValueMake) -> list[Action]:
        actions: list[Action] = []
        for step in make.path[:-1]:
            link = self._fresh_variable(_first_letter(step))
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
        Binary preferences stay, for `_check_binary_preferences` to refuse."""
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
            raise self._syntax_error(
                f"production name '{token}' looks like an identifier (a letter and digits); "
                "Soar refuses it: choose another name",
                token.line,
                token.column,
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
            _drop_unbound_relations(tuple(conditions), set(), self._fresh_variable),
            tuple(actions),
            doc,
            tuple(flags),
            self._location(sp),
        )
        if self._fresh_names:
            names = _fresh_names(self._fresh_names, self._used)
            production = dataclasses.replace(
                production,
                conditions=tuple(_rename_element(c, names) for c in production.conditions),
                actions=tuple(_rename_action(a, names) for a in production.actions),
            )
        self._fresh_names.clear()
        self._used.clear()
        production = _check_production(production, self.functions)
        self._warnings.extend(load_warnings(production))
        self.warnings.extend(_where(production) + message for message in self._warnings)
        self._warnings.clear()
        self.completed.append(production)
        return production


# --------------------------------------------------------------------- normalisation helpers


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


def _negate(elements: list[ConditionElement]) -> list[ConditionElement]:
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


def _drop_unbound_relations(
    elements: tuple[ConditionElement, ...], outer: set[str], fresh: Callable[[str], Var]
) -> tuple[ConditionElement, ...]:
    """The conditions without the relational tests of positive conditions on variables that
    no positive condition of their scope binds: the kernel drops them silently (measured in
    soar_sml 9.6: ``(state <s> ^c < <y>)`` with ``<y>`` bound nowhere, or only inside a
    negation, loads and prints as ``(state <s> ^c <c*1>)``, and matches any ``^c``). A field
    left with no test gets a fresh variable, as the kernel's does. Negated conditions keep
    theirs: the kernel refuses those (`rete.check_production`)."""
    bound = outer | _lhs_bound(elements)
    kept: list[ConditionElement] = []
    for element in elements:
        if isinstance(element, ConjunctiveNegation):
            inner = _drop_unbound_relations(element.conditions, bound, fresh)
            kept.append(ConjunctiveNegation(inner))
        elif element.negated:
            kept.append(element)
        else:
            letter = _first_letter(element.attr_test)
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


def _fresh_names(temporary: list[str], used: set[str]) -> dict[str, str]:
    """The kernel's names for fresh variables: ``<letter*n>``, n counting per letter from 1
    in creation order and skipping names the production already uses."""
    counters: dict[str, int] = {}
    names: dict[str, str] = {}
    for name in temporary:
        letter = name.rsplit(_TEMPORARY, 1)[1]
        while True:
            counters[letter] = counters.get(letter, 0) + 1
            candidate = f"{letter}*{counters[letter]}"
            if candidate not in used:
                break
        names[name] = candidate
    return names


# Renaming is written out per type: it runs on most productions (every path and missing value
# makes a fresh variable), and a generic walk over dataclass fields costs several times more.


def _rename_test(test: Test, names: dict[str, str]) -> Test:
    if isinstance(test, Var):
        return Var(names[test.name]) if test.name in names else test
    if isinstance(test, Conjunction):
        return Conjunction(tuple(_rename_test(t, names) for t in test.tests))
    if isinstance(test, Relational) and isinstance(test.operand, Var):
        return Relational(test.op, _rename_test(test.operand, names))  # type: ignore[arg-type]
    return test


def _rename_element(element: ConditionElement, names: dict[str, str]) -> ConditionElement:
    if isinstance(element, ConjunctiveNegation):
        return ConjunctiveNegation(tuple(_rename_element(c, names) for c in element.conditions))
    return Condition(
        _rename_test(element.id_test, names),
        _rename_test(element.attr_test, names),
        _rename_test(element.value_test, names),
        element.negated,
        element.acceptable,
        element.goal,
    )


def _rename_value(value: Any, names: dict[str, str]) -> Any:
    if isinstance(value, Var):
        return Var(names[value.name]) if value.name in names else value
    if isinstance(value, FuncCall):
        return FuncCall(value.name, tuple(_rename_value(a, names) for a in value.args))
    return value


def _rename_action(action: Action, names: dict[str, str]) -> Action:
    if isinstance(action, CallAction):
        return CallAction(_rename_value(action.call, names))
    return MakeAction(
        _rename_value(action.id, names),
        _rename_value(action.attr, names),
        _rename_value(action.value, names),
        action.preference,
        _rename_value(action.referent, names),
    )


# ----------------------------------------------------------------------- semantic checks


def _check_production(production: Production, functions: Collection[str]) -> Production:
    """The load-time checks of the kernel (and our refusal of exec/cmd and templates); the
    production comes back with its actions in the kernel's order (`_reorder_actions`)."""
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
    actions = _reorder_actions(production)
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


def _lhs_bound(elements: tuple[ConditionElement, ...]) -> set[str]:
    """Variables bound by equality tests of the positive conditions of one scope."""
    bound: set[str] = set()
    for element in elements:
        if isinstance(element, Condition) and not element.negated:
            for test in (element.id_test, element.attr_test, element.value_test):
                bound.update(equality_vars(test))
    return bound


def _reorder_actions(production: Production) -> tuple[Action, ...]:
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
    bound = _lhs_bound(production.conditions)
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


# -------------------------------------------------------------------------------- errors

#: Lark terminal names -> words for "expected ..." in error messages.
_READABLE = {
    "SP": "'sp'", "STATE": "'state'", "IMPASSE": "'impasse'", "ARROW": "'-->'",
    "LPAR": "'('", "RPAR": "')'", "LBRACE": "'{'", "RBRACE": "'}'", "CIRCUMFLEX": "'^'",
    "DOT": "'.'", "COMMA": "','", "SEMICOLON": "';'", "BANG": "'!'", "TILDE": "'~'",
    "MINUS": "'-'", "PLUS": "'+'", "LT": "'<'", "GT": "'>'", "EQ": "'='", "NE": "'<>'",
    "LE": "'<='", "GE": "'>='", "LEG": "'<=>'", "LTLT": "'<<'", "GTGT": "'>>'", "AT": "'@'",
    "NOTAT": "'!@'", "FLAG": "flag (:o-support, :i-support, :default, ...)",
    "VARIABLE": "variable", "SYMBOL": "symbol", "IDLIKE": "symbol", "INT": "integer",
    "FLOAT": "float", "QSTRING": "|string|", "DQSTRING": '"string"',
    "COMMAND_NAME": "command", "SHELL_COMMAND": "command", "WORD": "argument",
    "_NL": "end of line", "$END": "end of input",
}  # fmt: skip


_CONSTANTS = {"symbol", "integer", "float", "|string|"}
_RELATIONS = {"'<>'", "'<'", "'>'", "'<='", "'>='", "'<=>'", "'@'", "'!@'", "'='"}


def _readable(names: Collection[str]) -> tuple[str, ...]:
    """Terminal names -> words, with the usual groups said once ("constant", "relation")."""
    words = {_READABLE.get(name, name) for name in names}
    if _CONSTANTS <= words:
        words = (words - _CONSTANTS) | {"constant"}
    if _RELATIONS <= words:
        words = (words - _RELATIONS) | {"relation (<> < > <= >= <=> = @ !@)"}
    return tuple(sorted(words))


def _source_line(text: str, line: int) -> str:
    lines = text.splitlines()
    return lines[line - 1] if 1 <= line <= len(lines) else ""


def _syntax_error(
    text: str, file: str, message: str, line: int, column: int, expected: tuple[str, ...] = ()
) -> SoarSyntaxError:
    line, column = max(1, line), max(1, column)
    return SoarSyntaxError(message, file, line, column, _source_line(text, line), expected)


def _end_position(text: str) -> tuple[int, int]:
    """Where "unexpected end of input" points: just after the last non-blank character, so
    the message shows the unfinished line rather than an empty one."""
    end = len(text.rstrip())
    line_start = text.rfind("\n", 0, end) + 1
    return text.count("\n", 0, end) + 1, end - line_start + 1


# Terminals that only the root lexer can produce inside a production: when the parser's
# state accepts none of its terminals, Lark retries with every terminal and these long
# command-word patterns win, so the token's text is not what the user wrote as one word.
_FALLBACK_TYPES = ("COMMAND_NAME", "WORD", "SHELL_COMMAND", "SP")


def _describe_token(token: Token) -> str:
    if token.type == "$END":
        return "end of input"
    if token.type == "_NL":
        return "end of line"
    text = str(token)
    if token.type in _FALLBACK_TYPES:  # the root lexer's guess: only its first character counts
        text = text[:1]
    shown = f"'{text}'" if text.isprintable() and "'" not in text else repr(text)
    kind = _READABLE.get(token.type, "")
    if kind.startswith("'") or token.type in ("COMMAND_NAME", "WORD"):
        return shown
    return f"{kind} {shown}"


def _from_lark(error: UnexpectedInput, text: str, file: str) -> SoarSyntaxError:
    """Translate any Lark parse error into a SoarSyntaxError with a position."""
    if isinstance(error, UnexpectedToken) and error.token.type != "$END":
        token = error.token
        expected = _readable(error.accepts or error.expected)
        message = f"unexpected {_describe_token(token)}"
        if token.type in _FALLBACK_TYPES and token[:1] in '|"':
            message = f"unterminated string: no closing {token[:1]}"
        return _syntax_error(text, file, message, token.line or 1, token.column or 1, expected)
    if isinstance(error, UnexpectedCharacters):
        char = text[error.pos_in_stream] if error.pos_in_stream < len(text) else ""
        expected = _readable(error.allowed or ())
        message = f"unexpected character {char!r}"
        return _syntax_error(text, file, message, error.line, error.column, expected)
    expected = _readable(getattr(error, "expected", None) or ())
    line, column = _end_position(text)
    return _syntax_error(text, file, "unexpected end of input", line, column, expected)


def _caller_stacklevel() -> int:
    """The warnings stack level of the first frame outside this module (the user's call)."""
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_code.co_filename == __file__:
        frame, level = frame.f_back, level + 1
    return level


# ---------------------------------------------------------------------------- public API


def parse(
    text: str, file: str = "<string>", functions: Collection[str] = KNOWN_RHS_FUNCTIONS
) -> list[Production | Command]:
    """Parse a rule file: its productions and commands in file order.

    ``functions`` is the set of RHS function names a production may call. Unless it is an
    `RhsNames` (as the default is), each call of a function the kernel knows is also checked
    as the kernel checks it: stand-alone or value, and the number of arguments. Raises
    SoarSyntaxError (with file, line, column) or SoarSemanticError (naming the production);
    the first error stops the parse, as in the kernel.
    """
    items, error = parse_partial(text, file, functions)
    if error is not None:
        raise error
    return items


def parse_partial(
    text: str, file: str = "<string>", functions: Collection[str] = KNOWN_RHS_FUNCTIONS
) -> tuple[list[Production | Command], SoarSyntaxError | SoarSemanticError | None]:
    """Parse up to the first error: the items complete before it, and the error (or None).

    This is what the kernel does with a file: everything before the first error is loaded,
    then the error is reported. (An item counts as complete once the parser has seen the
    token after it, so text right after a closing brace that cannot even be lexed also
    withholds that production.)
    """
    parser, transformer = _parser()
    if text.startswith("\ufeff"):  # a byte-order mark: white space, so columns stay right
        text = " " + text[1:]
    key = (text, file, frozenset(functions), isinstance(functions, RhsNames))
    with _LOCK:
        done = _PARSED.get(key)
        if done is not None:
            return list(done), None
        transformer.reset(text, file, functions)
        try:
            items = parser.parse(text)
            if not transformer.warnings:  # a file that warns warns again when re-read
                _remember(key, tuple(items))
            return items, None
        except (UnexpectedToken, UnexpectedCharacters, UnexpectedEOF) as error:
            return transformer.completed, _from_lark(error, text, file)
        except (SoarSyntaxError, SoarSemanticError) as error:
            return transformer.completed, error
        except LarkError as error:  # defensive: any other Lark failure still gets a position
            line, column = _end_position(text)
            message = f"cannot parse: {error}"
            return transformer.completed, _syntax_error(text, file, message, line, column)
        finally:
            pending, transformer.warnings = transformer.warnings, []
            transformer.completed = []
            for message in pending:
                warnings.warn(message, SoarWarning, stacklevel=_caller_stacklevel())


# Parsed texts (productions and commands are frozen dataclasses, so agents can share them):
# re-sourcing an unchanged file, as a notebook re-run does, skips the parser.
_PARSED: dict[tuple[str, str, frozenset[str], bool], tuple[Production | Command, ...]] = {}
_PARSED_LIMIT = 256


def _remember(key: tuple[str, str, frozenset[str], bool], items: tuple) -> None:
    if len(_PARSED) >= _PARSED_LIMIT:
        del _PARSED[next(iter(_PARSED))]  # the oldest
    _PARSED[key] = items


def parse_file(path: str | Path, functions: Collection[str] = KNOWN_RHS_FUNCTIONS) -> list:
    """Parse a rule file from disk; errors name the file."""
    path = Path(path)
    return parse(path.read_text(encoding="utf-8"), str(path), functions)


def parse_production(
    text: str, file: str = "<string>", functions: Collection[str] = KNOWN_RHS_FUNCTIONS
) -> Production:
    """Parse text that holds exactly one ``sp {...}`` and nothing else."""
    items = parse(text, file, functions)
    if len(items) != 1 or not isinstance(items[0], Production):
        kinds = ", ".join(type(item).__name__ for item in items) or "nothing"
        location = next((i.location for i in items if i.location), None)
        line, column = (location.line, location.column) if location else (1, 1)
        raise _syntax_error(
            text, file, f"expected exactly one production, found {kinds}", line, column
        )
    return items[0]
