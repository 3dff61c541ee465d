"""Soar symbols as the matcher compares them: equality, Soar's total order, relational tests.

Matching follows the real Soar 9.6 kernel (checked with ``soar_sml``):

- constants and variables compare as Soar symbols: ``1``, ``1.0`` and ``|1|`` are three
  different symbols (equality requires the same Python type);
- ``< > <= >=`` between two variables use Soar's total order: identifiers (by letter, then
  number) before numbers (compared numerically, ints with floats) before strings (compared
  as strings); against a constant, values of another kind pass ``<``/``<=`` and fail
  ``>``/``>=`` (the kernel's constant tests do that: both ``abc < 5`` and ``5 < abc``);
- ``<>`` is symbol inequality, ``<=>`` "same type", ``@`` never holds and ``!@`` always holds
  (there are no long-term identifiers here).
"""

from __future__ import annotations

from collections.abc import Callable

from sann.soar.memory import Identifier, Symbol


def same_symbol(a: object, b: object) -> bool:
    """Soar symbol equality: same type and same value (identifiers by identity)."""
    return type(a) is type(b) and a == b


def _rank(value: object) -> int:
    cls = type(value)
    if cls is Identifier:
        return 0
    if cls is int or cls is float:
        return 1
    return 2


def symbol_order_less(a: Symbol, b: Symbol) -> bool:
    """``a < b`` in the Soar 9.6 kernel's total order of symbols."""
    ra, rb = _rank(a), _rank(b)
    if ra != rb:
        return ra < rb
    if ra == 0:
        return (a.letter, a.number) < (b.letter, b.number)  # type: ignore[union-attr]
    return a < b  # type: ignore[operator]


def _less_equal(a: Symbol, b: Symbol) -> bool:
    return not symbol_order_less(b, a)


def _relation(op: str) -> Callable[[Symbol, Symbol], bool]:
    """The predicate ``value <op> operand`` as a two-argument function."""
    return RELATIONS[op]


def _const_order(mixed: bool, holds: Callable[[Symbol, Symbol], bool]
                 ) -> Callable[[Symbol, Symbol], bool]:
    """An ordering test against a constant as the kernel runs it: numbers with numbers,
    strings with strings, and otherwise ``mixed`` whatever the values."""

    def test(value: Symbol, constant: Symbol) -> bool:
        if _rank(value) != _rank(constant):
            return mixed
        return holds(value, constant)

    return test


#: Relational tests as the 9.6 kernel's Rete runs them on the tested WME's value and the
#: other symbol (a constant, or a variable's value): numbers with numbers, strings with
#: strings; when the two are of different kinds (number, string, identifier), ``<`` and
#: ``<=`` hold and ``>`` and ``>=`` do not — so both ``abc < 5`` and ``5 < abc`` hold, as
#: soar_sml shows (for a variable too: ``-{(<y> ^p > <v>)}`` with <v> 1.5 is not blocked
#: by ^p |changed|, ``-{(<y> ^p < <v>)}`` is). The kernel's reorderer may move a test on a
#: variable bound later into that variable's condition, inverted, and run it there on that
#: WME's value: the agent hands the matcher its productions so arranged
#: (``reorder.with_kernel_relations``).
RELATIONS: dict[str, Callable[[Symbol, Symbol], bool]] = {
    "<>": lambda a, b: not (type(a) is type(b) and a == b),
    "<": _const_order(True, symbol_order_less),
    ">": _const_order(False, lambda a, b: symbol_order_less(b, a)),
    "<=": _const_order(True, _less_equal),
    ">=": _const_order(False, lambda a, b: _less_equal(b, a)),
    "<=>": lambda a, b: type(a) is type(b),
    "@": lambda a, b: False,
    "!@": lambda a, b: True,
}
