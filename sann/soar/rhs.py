"""Right-hand-side functions, with the Soar 9.6 kernel's arithmetic and text conventions.

Integer operations on integers stay integers; any float makes the result a float; ``/``
always returns a float; ``div`` and ``mod`` truncate toward zero like C. Floats print as
C's ``%f`` (``3.500000``), which is what ``write`` and ``concat`` produce in the kernel.
"""

from __future__ import annotations

import datetime
import math
from collections.abc import Callable, Sequence
from typing import Protocol

from .errors import SoarRuntimeError
from .memory import Identifier, Symbol


class RhsContext(Protocol):
    """What an RHS function may touch in the agent."""

    def write_output(self, text: str) -> None: ...
    def request_halt(self) -> None: ...
    def request_interrupt(self) -> None: ...
    def decision_count(self) -> int: ...
    def gensym(self, prefix: str) -> str: ...


RhsFunction = Callable[[RhsContext, Sequence[Symbol]], Symbol | None]

#: Value returned by ``(crlf)``: a symbol holding a newline, as in the kernel.
CRLF = "\n"


def format_value(value: Symbol) -> str:
    """A symbol as ``write``/``concat`` render it: identifiers by name, floats as ``%f``."""
    if isinstance(value, Identifier):
        return value.name
    if isinstance(value, float):
        return _format_float(value)
    return str(value)


def _format_float(value: float) -> str:
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    if math.isnan(value):
        return "nan"
    return f"{value:f}"


def _number(name: str, value: Symbol) -> int | float:
    kind = type(value)
    if kind is int or kind is float:  # the usual case, without building a union type
        return value  # type: ignore[return-value]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SoarRuntimeError(f"({name}): {format_value(value)} is not a number")
    return value


def _numbers(name: str, args: Sequence[Symbol]) -> list[int | float]:
    return [_number(name, a) for a in args]


def _int64(value: int | float) -> int | float:
    """The kernel's integers are 64-bit and wrap around (measured:
    ``(+ 9223372036854775807 1)`` is -9223372036854775808); floats are left alone."""
    if type(value) is int and not -(1 << 63) <= value < 1 << 63:
        return ((value + (1 << 63)) & ((1 << 64) - 1)) - (1 << 63)
    return value


def _plus(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return _int64(sum(_numbers("+", args), 0))


def _times(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return _int64(math.prod(_numbers("*", args)))


def _minus(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    nums = _numbers("-", args)
    if not nums:
        raise SoarRuntimeError("(-): needs at least one argument")
    if len(nums) == 1:
        return _int64(-nums[0])
    result = nums[0]
    for n in nums[1:]:
        result -= n
    return _int64(result)


def _divide(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    nums = [float(n) for n in _numbers("/", args)]
    if not nums:
        raise SoarRuntimeError("(/): needs at least one argument")
    if len(nums) == 1:
        nums.insert(0, 1.0)
    result = nums[0]
    for n in nums[1:]:
        if n == 0:
            raise SoarRuntimeError("(/): attempt to divide by zero")
        result /= n
    return result


def _int_pair(name: str, args: Sequence[Symbol]) -> tuple[int, int]:
    if len(args) != 2 or not all(isinstance(a, int) and not isinstance(a, bool) for a in args):
        raise SoarRuntimeError(f"({name}): needs two integer arguments")
    a, b = args
    assert isinstance(a, int) and isinstance(b, int)
    if b == 0:
        raise SoarRuntimeError(f"({name}): attempt to divide by zero")
    return a, b


def _div(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    a, b = _int_pair("div", args)
    quotient = abs(a) // abs(b)
    return quotient if (a >= 0) == (b >= 0) else -quotient


def _mod(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    a, b = _int_pair("mod", args)
    return int(math.fmod(a, b))


def _one(name: str, args: Sequence[Symbol]) -> Symbol:
    if len(args) != 1:
        raise SoarRuntimeError(f"({name}): needs exactly one argument")
    return args[0]


def _abs(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return abs(_number("abs", _one("abs", args)))


def _to_int(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    value = _one("int", args)
    if isinstance(value, str):
        try:
            return int(float(value)) if "." in value or "e" in value.lower() else int(value)
        except ValueError as exc:
            raise SoarRuntimeError(f"(int): cannot convert {value!r} to an integer") from exc
    return int(_number("int", value))


def _to_float(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    value = _one("float", args)
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError as exc:
            raise SoarRuntimeError(f"(float): cannot convert {value!r} to a float") from exc
    return float(_number("float", value))


def _sqrt(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return math.sqrt(_number("sqrt", _one("sqrt", args)))


def _min(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return _extreme("min", min, args)


def _max(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return _extreme("max", max, args)


def _extreme(name: str, pick: Callable[[list], Symbol], args: Sequence[Symbol]) -> Symbol:
    """As in the kernel (measured): a float among the arguments makes the result a float,
    ``(max 3 1.5)`` is 3.0."""
    nums = _numbers(name, args)
    if not nums:
        raise SoarRuntimeError(f"({name}): needs at least one argument")
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
    if len(args) != 2:
        raise SoarRuntimeError("(round-off): needs a number and a precision")
    value, step = _numbers("round-off", args)
    if step == 0:
        raise SoarRuntimeError("(round-off): precision must not be zero")
    if isinstance(step, int):
        return _round_int(int(value), step)
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


def _concat(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return "".join(format_value(a) for a in args)


def _make_constant_symbol(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    prefix = "".join(format_value(a) for a in args) or "constant"
    return ctx.gensym(prefix)


def _timestamp(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    now = datetime.datetime.now()
    return now.strftime("%Y-%m-%d %H:%M:%S.") + f"{now.microsecond // 1000:03d}"


def _write(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    ctx.write_output("".join(format_value(a) for a in args))
    return None


def _crlf(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return CRLF


def _halt(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    ctx.request_halt()
    return None


def _interrupt(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    ctx.request_interrupt()
    return None


def _dc(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return ctx.decision_count()


def _ifeq(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    if len(args) != 4:
        raise SoarRuntimeError("(ifeq): needs four arguments")
    a, b, then, other = args
    same = a is b if isinstance(a, Identifier) else (type(a) is type(b) and a == b)
    return then if same else other


def _trim(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return format_value(_one("trim", args)).strip()


def _strlen(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return len(format_value(_one("strlen", args)))


def _trig(name: str, fn: Callable[[float], float]) -> RhsFunction:
    def call(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
        return fn(float(_number(name, _one(name, args))))

    return call


def _atan2(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    if len(args) != 2:
        raise SoarRuntimeError("(atan2): needs two arguments")
    y, x = _numbers("atan2", args)
    return math.atan2(y, x)


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
    "concat": _concat,
    "make-constant-symbol": _make_constant_symbol,
    "timestamp": _timestamp,
    "write": _write,
    "crlf": _crlf,
    "halt": _halt,
    "interrupt": _interrupt,
    "dc": _dc,
    "ifeq": _ifeq,
    "trim": _trim,
    "strlen": _strlen,
}
