"""The kernel's arithmetic (``rhs_functions_math.cpp``): ``+ - * /``, ``div``, ``mod``,
``abs``, ``int``, ``float``, ``sqrt``, ``sin``, ``cos``, ``atan2``, ``min``, ``max`` and
``round-off``.

Integer operations on integers stay integers (64-bit, wrapping); any float makes the result a
float; ``/`` always returns a float; ``div`` and ``mod`` truncate toward zero like C. Where
the kernel takes a bad argument without a word we do too, with its value: ``int`` and
``float`` read any string as C's ``strtol``/``strtod`` (``(int a)`` is 0), ``(sqrt -1)`` is
``-nan``, ``(min)`` is 0.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence
from fractions import Fraction

from sann.soar.errors import SoarRuntimeError
from sann.soar.memory import Symbol
from sann.soar.rhs.context import X86_NAN, RhsContext, RhsFunction, c_int64, int64, one
from sann.soar.text import format_symbol


def _number(name: str, value: Symbol) -> int | float:
    """A number argument of ``+ - * / min max``, or the kernel's complaint."""
    kind = type(value)
    if kind is int or kind is float:
        return value  # type: ignore[return-value]
    raise SoarRuntimeError(f"non-number ({format_symbol(value)}) passed to {name} function")


def _numbers(name: str, args: Sequence[Symbol]) -> list[int | float]:
    return [_number(name, a) for a in args]


def _plus(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return int64(sum(_numbers("+", args), 0))


def _times(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return int64(math.prod(_numbers("*", args)))


def _minus(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    nums = _numbers("-", args)
    if not nums:
        raise SoarRuntimeError("'-' function called with no arguments")
    if len(nums) == 1:
        return int64(-nums[0])
    result = nums[0]
    for n in nums[1:]:
        result -= n
    return int64(result)


def _divide(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """Every argument is checked before any division (measured: ``(/ 0 a)`` and ``(/ a 0)``
    both complain of ``a``); ``(/ x)`` is ``1 / x``."""
    nums = [float(n) for n in _numbers("/", args)]
    if not nums:
        raise SoarRuntimeError("'/' function called with no arguments")
    if len(nums) == 1:
        nums.insert(0, 1.0)
    result = nums[0]
    for n in nums[1:]:
        if n == 0:
            raise SoarRuntimeError("attempt to divide ('/') by zero.")
        result /= n
    return result


def _int_pair(name: str, args: Sequence[Symbol]) -> tuple[int, int]:
    """Both arguments integers, checked before the divisor (measured: ``(div 1.5 0)``
    complains of 1.5, ``(div 1 0)`` of the zero)."""
    if len(args) != 2:
        raise SoarRuntimeError(f"({name}): needs two integer arguments")
    for arg in args:
        if type(arg) is not int:
            raise SoarRuntimeError(f"non-integer ({format_symbol(arg)}) passed to {name} function")
    a, b = args
    if b == 0:
        raise SoarRuntimeError(f"attempt to divide ('{name}') by zero.")
    return a, b  # type: ignore[return-value]


def _div(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    a, b = _int_pair("div", args)
    quotient = abs(a) // abs(b)
    return quotient if (a >= 0) == (b >= 0) else -quotient


def _mod(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    a, b = _int_pair("mod", args)
    return int(math.fmod(a, b))


def _math_number(name: str, value: Symbol) -> int | float:
    """A number argument of ``abs``, ``sqrt``, ``sin`` and ``cos``, or the kernel's complaint."""
    if type(value) is int or type(value) is float:
        return value  # type: ignore[return-value]
    raise SoarRuntimeError(
        f"'{name}' function called with non-numeric argument {format_symbol(value)}"
    )


def _abs(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(abs -9223372036854775808)`` stays itself, as C's ``llabs`` leaves it (measured)."""
    return int64(abs(_math_number("abs", one("abs", args))))


def _to_int(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The kernel's ``int`` (all measured): a float truncated as C's cast (NaN, infinities
    and out of range give -9223372036854775808); a string read by C's ``strtol``, base 10:
    what leading spaces, a sign and digits spell, 0 if nothing (``|12abc|`` is 12, ``|1e5|``
    1, ``|a|`` 0), an error only when out of 64-bit range; an identifier is an error."""
    value = one("int", args)
    kind = type(value)
    if kind is int:
        return value
    if kind is float:
        return c_int64(value)  # type: ignore[arg-type]
    if kind is str:
        number = _strtol(value)  # type: ignore[arg-type]
        if number is None:
            raise SoarRuntimeError(
                f"bad integer ({format_symbol(value)}) given to 'int' RHS function"
            )
        return number
    raise SoarRuntimeError(f"identifier ({format_symbol(value)}) passed to 'int' RHS function.")


def _to_float(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The kernel's ``float``: a string read by C's ``strtod`` (what its longest prefix
    spells, 0.0 if nothing: ``|2.5x|`` is 2.5, ``|0x1p3|`` 8.0, ``|a|`` 0.0), an error when
    the number is out of range (``|1e999|``, ``|1e-320|``); an identifier is an error."""
    value = one("float", args)
    kind = type(value)
    if kind is float:
        return value
    if kind is int:
        return float(value)  # type: ignore[arg-type]
    if kind is str:
        number = _strtod(value)  # type: ignore[arg-type]
        if number is None:
            raise SoarRuntimeError(
                f"bad float ({format_symbol(value)}) given to 'float' RHS function"
            )
        return number
    raise SoarRuntimeError(f"identifier ({format_symbol(value)}) passed to 'float' RHS function.")


#: What C's ``strtol`` (base 10) and ``strtod`` read, after the spaces ``isspace`` skips.
_STRTOL = re.compile(r"[ \t\n\v\f\r]*([+-]?[0-9]+)")


_STRTOD = re.compile(
    r"""[ \t\n\v\f\r]*([+-]?)(?:
        0[xX](?P<hex>(?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)(?:[pP][+-]?[0-9]+)?)
      | (?P<dec>(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)
      | (?P<inf>[iI][nN][fF])
      | (?P<nan>[nN][aA][nN])
    )""",
    re.VERBOSE,
)


_DBL_MIN = 2.2250738585072014e-308


def _strtol(text: str) -> int | None:
    """C's ``strtol(text, NULL, 10)`` for a 64-bit long; None where it sets ``ERANGE``."""
    match = _STRTOL.match(text)
    if match is None:
        return 0
    number = int(match.group(1))
    return number if -(1 << 63) <= number < 1 << 63 else None


def _strtod(text: str) -> float | None:
    """glibc's ``strtod``; None where it sets ``ERANGE``: a finite number that overflows,
    or one that is not zero, below the smallest normal double and not exactly a double
    (measured: ``|0x1p-1074|`` reads, ``|1e-320|`` and ``|2.2250738585072012e-308|`` do not;
    a NaN keeps its sign, ``|-nan|`` writes ``-nan``)."""
    match = _STRTOD.match(text)
    if match is None:
        return 0.0
    sign, hex_digits, decimal = match.group(1), match.group("hex"), match.group("dec")
    if match.group("inf") is not None:
        return -math.inf if sign == "-" else math.inf
    if match.group("nan") is not None:
        return -math.nan if sign == "-" else math.nan
    if hex_digits is not None:
        try:
            number = float.fromhex("0x" + hex_digits)
        except OverflowError:
            return None
        mantissa = hex_digits.lower().partition("p")[0]
    else:
        number = float(decimal)
        mantissa = decimal.lower().partition("e")[0]
    if math.isinf(number):
        return None
    if number == 0.0:
        if mantissa.strip("0."):
            return None  # not zero, yet read as zero
    elif number <= _DBL_MIN:
        if hex_digits is not None:
            whole, _, fraction = mantissa.partition(".")
            exponent = int(hex_digits.lower().partition("p")[2] or 0) - 4 * len(fraction)
            exact = Fraction(int(whole + fraction, 16)) * Fraction(2) ** exponent
        else:
            exact = Fraction(decimal)
        if exact < _DBL_MIN and Fraction(number) != exact:
            return None
    return -number if sign == "-" else number


def _sqrt(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """C's ``sqrt``: below zero it is ``-nan`` (measured), ``(sqrt -0.0)`` is ``-0.0``."""
    value = float(_math_number("sqrt", one("sqrt", args)))
    if value < 0:
        return X86_NAN
    return math.sqrt(value)


def _min(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return _extreme("min", min, args)


def _max(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return _extreme("max", max, args)


def _extreme(
    name: str, pick: Callable[[list[int | float]], int | float], args: Sequence[Symbol]
) -> Symbol:
    """As in the kernel (measured): a float among the arguments makes the result a float,
    ``(max 3 1.5)`` is 3.0; with no argument it is 0."""
    nums = _numbers(name, args)
    if not nums:
        return 0
    best = pick(nums)
    return float(best) if any(type(n) is float for n in nums) else best


def _round_off(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The kernel's ``round-off`` (measured in soar_sml 9.6): the nearest multiple of the
    precision, ties away from zero, computed in one of three ways by the precision's type.

    - integer precision: the value is first truncated to an integer, the result is an
      integer (``(round-off 3.7 1)`` is 3, ``(round-off 37 10)`` is 40);
    - float precision below 1 in magnitude: the kernel works in tenths, truncating both the
      value and the precision to tenths (``(round-off 1.25 0.25)`` is 1.2);
    - any other float precision: in floating point (``(round-off 2.5 1.0)`` is 3.0).

    A float precision below 0.1 truncates to zero tenths and the kernel returns NaN; we
    round in floating point instead (``(round-off 3.14159 0.01)`` is 3.14)."""
    return rounded("round-off", args)


def rounded(name: str, args: Sequence[Symbol]) -> int | float:
    """`_round_off` under the name of the function that asked (round-off-heading too)."""
    if len(args) != 2:
        raise SoarRuntimeError(f"({name}): needs a number and a precision")
    value, step = args
    if type(value) is not int and type(value) is not float:
        value = 0  # the kernel reads anything else as 0 (measured: (round-off a 1) is 0)
    if type(step) is not float:
        if type(step) is not int or step == 0:
            # the kernel divides by an integer 0 here and dies (SIGFPE); we report it
            raise SoarRuntimeError(f"attempt to divide ('{name}') by zero.")
        return _round_int(int(value), step)  # type: ignore[arg-type]
    if step == 0:
        return X86_NAN  # measured: (round-off 1.5 0.0) is -nan
    if abs(step) < 1 and int(step * 10) != 0:
        return _round_tenths(int(value * 10), int(step * 10))
    return _round_float(float(value), step)


def _round_int(value: int, step: int) -> int:
    """C's ``(value +- step/2) / step * step`` with division truncating toward zero."""
    half = _c_div(step, 2)
    return _c_div(value + half if value >= 0 else value - half, step) * step


def _c_div(a: int, b: int) -> int:
    quotient = abs(a) // abs(b)
    return quotient if (a >= 0) == (b >= 0) else -quotient


def _round_tenths(value: int, step: int) -> float:
    """`_round_int` in tenths, the half-step an integer, the quotient a C double."""
    half = _c_div(step, 2)
    return _scaled(value + half if value >= 0 else value - half, step) / 10


def _round_float(value: float, step: float) -> float:
    """The float form of `_round_int`."""
    return _scaled(value + step / 2 if value >= 0 else value - step / 2, step)


def _scaled(shifted: float, step: float) -> float:
    """``trunc(shifted / step) * step``. A zero result is ``-0.0`` only when the quotient
    is a negative zero and the step is positive: the kernel prints ``-0.000000`` for
    ``(round-off -1.25 3.0)`` but ``0.000000`` for ``(round-off 0.3 -0.5)`` and
    ``(round-off -1.29 -1.5)`` (measured), which no plain product gives."""
    quotient = math.modf(shifted / step)[1]
    if quotient:
        return quotient * step
    return -0.0 if step > 0 and math.copysign(1.0, quotient) < 0 else 0.0


def _trig(name: str, fn: Callable[[float], float]) -> RhsFunction:
    """``sin``/``cos``; of an infinity C gives ``-nan`` (measured) where Python raises."""

    def call(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
        try:
            return fn(float(_math_number(name, one(name, args))))
        except ValueError:
            return X86_NAN

    return call


def _atan2(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    if len(args) != 2:
        raise SoarRuntimeError("(atan2): needs two arguments")
    for arg in args:
        if type(arg) is not int and type(arg) is not float:
            raise SoarRuntimeError(f"non-number ({format_symbol(arg)}) passed to atan2")
    return math.atan2(*args)  # type: ignore[arg-type]


#: This family's functions, by the name a rule calls them with.
FUNCTIONS: dict[str, RhsFunction] = {
    "+": _plus,
    "-": _minus,
    "*": _times,
    "/": _divide,
    "div": _div,
    "mod": _mod,
    "abs": _abs,
    "int": _to_int,
    "float": _to_float,
    "sqrt": _sqrt,
    "sin": _trig("sin", math.sin),
    "cos": _trig("cos", math.cos),
    "atan2": _atan2,
    "min": _min,
    "max": _max,
    "round-off": _round_off,
}
