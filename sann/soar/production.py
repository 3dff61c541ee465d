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


# ----- duplicate productions ------------------------------------------------------------------


def shape(item: object) -> object:
    """``item`` with every variable replaced by one placeholder: equal shapes are what a
    variable renaming can make equal (hashable, for indexing productions)."""
    if isinstance(item, Var):
        return Var
    if isinstance(item, Conjunction):  # its tests in any order
        return (Conjunction, tuple(sorted(repr(shape(test)) for test in item.tests)))
    if isinstance(item, tuple):
        return tuple(shape(part) for part in item)
    if hasattr(item, "__dataclass_fields__"):
        return (type(item), *(shape(getattr(item, name))
                              for name in item.__dataclass_fields__))  # type: ignore[attr-defined]
    return item


def duplicate_key(production: Production) -> tuple:
    """What two duplicates share: the conditions' shapes in any order, the actions' in
    order (see :func:`same_production`). Worked out once per production object (by
    identity: parsed rules are shared, so every agent loading them asks again)."""
    hit = _DUPLICATE_KEYS.get(id(production))
    if hit is not None and hit[0] is production:
        return hit[1]
    if len(_DUPLICATE_KEYS) >= _DUPLICATE_KEYS_SIZE:
        _DUPLICATE_KEYS.clear()
    key = (tuple(sorted(map(repr, map(shape, production.conditions)))),
           shape(production.actions))
    _DUPLICATE_KEYS[id(production)] = (production, key)
    return key


_DUPLICATE_KEYS: dict[int, tuple[Production, tuple]] = {}
_DUPLICATE_KEYS_SIZE = 4096


def same_production(a: Production, b: Production) -> bool:
    """Whether the kernel would refuse ``b`` as a duplicate of ``a`` (measured with
    soar_sml 9.6): the same conditions in any order (and the tests of a ``{ }`` conjunction in
    any order) and the same actions in the same order, up to a consistent renaming of
    variables; name, documentation and flags (even ``:o-support``) do not count."""
    if duplicate_key(a) != duplicate_key(b):
        return False
    mapping: dict[str, str] = {}
    reverse: dict[str, str] = {}
    if not _match_elements(list(a.conditions), list(b.conditions), mapping, reverse):
        return False
    return _unify(a.actions, b.actions, mapping, reverse)


def _match_elements(left: list, right: list, mapping: dict[str, str],
                    reverse: dict[str, str]) -> bool:
    """Pair every element of ``left`` with one of ``right`` (any order) under one variable
    renaming, extending ``mapping``/``reverse`` in place on success (backtracking)."""
    if not left:
        return not right
    first, rest = left[0], left[1:]
    wanted = shape(first)
    for k, candidate in enumerate(right):
        if shape(candidate) != wanted:
            continue
        trial, trial_reverse = dict(mapping), dict(reverse)
        if isinstance(first, ConjunctiveNegation):
            paired = _match_elements(list(first.conditions), list(candidate.conditions),
                                     trial, trial_reverse)
        else:
            paired = _unify(first, candidate, trial, trial_reverse)
        if paired and _match_elements(rest, right[:k] + right[k + 1:], trial, trial_reverse):
            mapping.update(trial)
            reverse.update(trial_reverse)
            return True
    return False


def _unify(a: object, b: object, mapping: dict[str, str], reverse: dict[str, str]) -> bool:
    """Whether ``a`` and ``b`` are equal up to the renaming, extending it (a bijection)."""
    if isinstance(a, Var) and isinstance(b, Var):
        if mapping.setdefault(a.name, b.name) != b.name:
            return False
        return reverse.setdefault(b.name, a.name) == a.name
    if type(a) is not type(b):
        return False
    if isinstance(a, Conjunction):
        return _match_elements(list(a.tests), list(b.tests), mapping,  # type: ignore[attr-defined]
                               reverse)
    if isinstance(a, tuple):
        return len(a) == len(b) and all(  # type: ignore[arg-type]
            _unify(x, y, mapping, reverse) for x, y in zip(a, b, strict=True))  # type: ignore[call-overload]
    if hasattr(a, "__dataclass_fields__"):
        return all(_unify(getattr(a, name), getattr(b, name), mapping, reverse)
                   for name in a.__dataclass_fields__)  # type: ignore[attr-defined]
    return a == b and type(a) is type(b)
