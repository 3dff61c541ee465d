"""Functions that make or read symbols (``rhs_functions.cpp``): ``concat``,
``make-constant-symbol``, ``capitalize-symbol``, ``string``, ``strlen``, ``trim`` and
``ifeq``. They render symbols as ``write`` does (`text.format_value`).
"""

from __future__ import annotations

from collections.abc import Sequence

from sann.soar.errors import SoarRuntimeError
from sann.soar.memory import Identifier, Symbol
from sann.soar.rhs.context import FreshLineError, RhsContext, RhsFunction, one
from sann.soar.text import format_symbol, format_value, string_text


def _concat(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return "".join(format_value(a) for a in args)


def _make_constant_symbol(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    prefix = "".join(format_value(a) for a in args) or "constant"
    return ctx.gensym(prefix)


def _capitalize_symbol(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The first character upper-cased, in the C locale: ``|éa|`` stays as it is."""
    value = one("capitalize-symbol", args)
    if type(value) is not str:
        raise FreshLineError(
            f"non-symbol ({format_symbol(value)}) passed to capitalize-symbol function."
        )
    if value and "a" <= value[0] <= "z":
        return value[0].upper() + value[1:]
    return value


def _string(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """Any symbol as a string; a float with 17 decimals, as the kernel writes it
    (``(string 0.1)`` is ``0.10000000000000001``), not as ``write`` does."""
    return string_text(one("string", args))


def _strlen(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return len(format_value(one("strlen", args)))


def _trim(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """A string without its leading and trailing spaces; anything else is an error."""
    value = one("trim", args)
    if type(value) is not str:
        raise FreshLineError(f"non-symbol ({format_symbol(value)}) passed to 'trim' function.")
    return value.strip()


def _ifeq(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    if len(args) != 4:
        raise SoarRuntimeError("(ifeq): needs four arguments")
    a, b, then, other = args
    same = a is b if isinstance(a, Identifier) else (type(a) is type(b) and a == b)
    return then if same else other


#: This family's functions, by the name a rule calls them with.
FUNCTIONS: dict[str, RhsFunction] = {
    "concat": _concat,
    "make-constant-symbol": _make_constant_symbol,
    "ifeq": _ifeq,
    "trim": _trim,
    "strlen": _strlen,
    "capitalize-symbol": _capitalize_symbol,
    "string": _string,
}
