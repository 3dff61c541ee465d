"""The parsed form of Soar productions: plain, frozen dataclasses.

This is the contract between the parser (`syntax.py`), the printer (`printer.py`) and the
matcher/decision process (`rete.py`, `agent.py`). The parser normalises Soar's surface syntax
the way the real kernel does, so the engine never sees paths or grouped attributes:

- ``(<s> ^a <x> ^b <y>)`` becomes two conditions with the same identifier test;
- ``^a.b.c <v>`` becomes a chain of conditions through fresh variables ``<a*1>``, ``<b*2>``;
- ``^a v1 v2`` (multi-valued) becomes one condition per value;
- ``-^a v`` becomes a negated condition; ``-{ ... }`` a conjunctive negation;
- on the right-hand side ``(<s> ^a.b c)`` becomes ``(<s> ^a <a*1>) (<a*1> ^b c)`` and a
  production's several preferences on one value become several actions.

Constants: a symbolic constant is a ``str`` (``abc`` and ``|abc|`` are the same symbol),
integers are ``int``, floats are ``float``; ``|12|`` is the *string* ``"12"``, which is
why constants carry their Python type.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

Constant = str | int | float

#: Relations allowed in a relational test. ``=`` is the plain equality test and is never
#: stored as a Relational (an equality test is just a Const or a Var).
RELATIONS = ("<>", "<", ">", "<=", ">=", "<=>", "@", "!@")


@dataclass(frozen=True)
class Var:
    """A variable ``<name>``; ``name`` is stored without the angle brackets."""

    name: str


@dataclass(frozen=True)
class Const:
    """A constant test or value: symbol (str), int or float."""

    value: Constant


@dataclass(frozen=True)
class Relational:
    """``<op> operand`` such as ``> 3`` or ``<> <x>``."""

    op: str
    operand: Var | Const


@dataclass(frozen=True)
class Disjunction:
    """``<< a b c >>``: the value equals one of the constants."""

    values: tuple[Const, ...]


@dataclass(frozen=True)
class Conjunction:
    """``{ <x> > 3 <> 7 }``: every test holds."""

    tests: tuple[Test, ...]


Test = Var | Const | Relational | Disjunction | Conjunction


@dataclass(frozen=True)
class Condition:
    """One ``(id ^attr value)`` test, positive or negated.

    ``goal`` is ``"state"`` or ``"impasse"`` when the identifier was written with that
    keyword (it must then be a state), else ``None``. ``acceptable`` is the ``+`` test that
    matches acceptable operator preferences instead of the selected operator.
    """

    id_test: Test
    attr_test: Test
    value_test: Test
    negated: bool = False
    acceptable: bool = False
    goal: Literal["state", "impasse"] | None = None


@dataclass(frozen=True)
class ConjunctiveNegation:
    """``-{ ... }``: no consistent match of all the inner conditions exists."""

    conditions: tuple[ConditionElement, ...]


ConditionElement = Condition | ConjunctiveNegation


@dataclass(frozen=True)
class FuncCall:
    """A right-hand-side function call ``(name arg ...)``, e.g. ``(+ <x> 1)``."""

    name: str
    args: tuple[RhsValue, ...]


RhsValue = Var | Const | FuncCall

#: Unary preferences: acceptable, reject, require, prohibit, reconsider, best, worst,
#: indifferent. Binary (with a referent): better ``>``, worse ``<``, indifferent ``=``;
#: numeric indifferent is ``=`` with a numeric Const referent.
UNARY_PREFERENCES = ("+", "-", "!", "~", "@", ">", "<", "=")
BINARY_PREFERENCES = (">", "<", "=")


@dataclass(frozen=True)
class MakeAction:
    """``(id ^attr value preference [referent])``; ``preference`` defaults to ``+``."""

    id: Var
    attr: RhsValue
    value: RhsValue
    preference: str = "+"
    referent: RhsValue | None = None


@dataclass(frozen=True)
class CallAction:
    """A stand-alone function call on the right-hand side: ``(write ...)``, ``(halt)``."""

    call: FuncCall


Action = MakeAction | CallAction


@dataclass(frozen=True)
class SourceLocation:
    """Where a production or command was written (for error messages)."""

    file: str
    line: int
    column: int


@dataclass(frozen=True)
class Production:
    """``sp {name "doc" :flags conditions --> actions}``.

    ``support`` is ``"o-support"``/``"i-support"`` when a ``:o-support``/``:i-support``
    flag forces it, else ``None`` (computed as in Soar 9). ``flags`` keeps every flag as
    written (``default``, ``chunk``, ``template``, ``interrupt``, ...).
    """

    name: str
    conditions: tuple[ConditionElement, ...]
    actions: tuple[Action, ...]
    doc: str | None = None
    flags: tuple[str, ...] = ()
    location: SourceLocation | None = field(default=None, compare=False)

    @property
    def support(self) -> str | None:
        for flag in self.flags:
            if flag in ("o-support", "i-support"):
                return flag
        return None


@dataclass(frozen=True)
class Command:
    """A top-level command of an agent file: ``source x.soar``, ``watch 1``, ..."""

    name: str
    args: tuple[str, ...]
    location: SourceLocation | None = field(default=None, compare=False)
