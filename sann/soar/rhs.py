"""Right-hand-side functions, with the Soar 9.6 kernel's arithmetic and text conventions.

Integer operations on integers stay integers; any float makes the result a float; ``/``
always returns a float; ``div`` and ``mod`` truncate toward zero like C. Floats print as
C's ``%f`` (``3.500000``), which is what ``write`` and ``concat`` produce in the kernel.

``rand-int`` and ``rand-float`` draw from the agent's one generator, the one indifferent
selection uses, as the kernel's do: Soar has a single Mersenne Twister for both (measured:
after ``srand 7`` an indifferent choice takes the first draw and ``(rand-int)`` gets the
second). `kernel_random` builds the generator in the state ``srand N`` puts the kernel's in;
the draws are the kernel's (``getrandbits(32)`` is MT19937's 32-bit output), and
``Agent.srand`` uses it: after the same ``srand`` the random functions give the kernel's very
numbers (until an indifferent choice, whose draws follow our own selection code).

Which functions may be called where, and with how many arguments, is checked when a rule is
loaded (`sann.soar.syntax`); the functions still check their arguments, for direct calls.

A function given bad arguments raises `SoarRuntimeError` with the kernel's very text
(measured in soar_sml 9.6, ``kernel_shown`` showing symbols as the kernel's messages do); the
agent prints it as ``Error: <text>`` and a newline where the output stands, or on a fresh
line for a `FreshLineError`, and drops the action. Where the kernel takes a bad argument
without a word we do too, with its value: ``int`` and ``float`` read any string as C's
``strtol``/``strtod`` (``(int a)`` is 0), ``(sqrt -1)`` is ``-nan``, ``(min)`` is 0.
"""

from __future__ import annotations

import datetime
import math
import random
import re
import struct
import time
from collections.abc import Callable, Iterable, Sequence
from fractions import Fraction
from typing import Any, Protocol

from .errors import SoarRuntimeError
from .memory import WME, Identifier, Symbol, float_text
from .preferences import Preference
from .printer import format_constant


class Seeded(Protocol):
    """The agent's exploration settings: they hold its seeded generator (``srand``)."""

    rng: random.Random | None


class RhsContext(Protocol):
    """What an RHS function may touch in the agent."""

    exploration: Seeded
    #: The instantiation being fired (`deep-copy` adds its preferences to it).
    firing: object

    def write_output(self, text: str) -> None: ...
    def request_halt(self) -> None: ...
    def request_interrupt(self) -> None: ...
    def decision_count(self) -> int: ...
    def gensym(self, prefix: str) -> str: ...
    def mark_learning(self, function: str, state: Identifier) -> None: ...
    def wmes(self) -> Iterable[WME]: ...


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


#: C's ``%f``: a NaN with its sign bit set is ``-nan`` (measured: ``(sqrt -1)``).
_format_float = float_text


#: The NaN x86 makes of an invalid operation (``sqrt(-1)``, ``inf * 0``): sign bit set.
_X86_NAN = -math.nan


class FreshLineError(SoarRuntimeError):
    """An RHS error whose kernel message starts on a fresh line: after a newline unless the
    output is already at the start of one (measured for ``trim``, ``capitalize-symbol``,
    ``dont-learn``, ``force-learn`` and ``log``; the other functions' messages follow
    whatever was printed last, ``xError: ...``). Both end with a newline."""

    fresh_line = True


def _number(name: str, value: Symbol) -> int | float:
    """A number argument of ``+ - * / min max``, or the kernel's complaint."""
    kind = type(value)
    if kind is int or kind is float:
        return value  # type: ignore[return-value]
    raise SoarRuntimeError(f"non-number ({kernel_shown(value)}) passed to {name} function")


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
        raise SoarRuntimeError("'-' function called with no arguments")
    if len(nums) == 1:
        return _int64(-nums[0])
    result = nums[0]
    for n in nums[1:]:
        result -= n
    return _int64(result)


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
            raise SoarRuntimeError(f"non-integer ({kernel_shown(arg)}) passed to {name} function")
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


def _one(name: str, args: Sequence[Symbol]) -> Symbol:
    if len(args) != 1:
        raise SoarRuntimeError(f"({name}): needs exactly one argument")
    return args[0]


def _math_number(name: str, value: Symbol) -> int | float:
    """A number argument of ``abs``, ``sqrt``, ``sin`` and ``cos``, or the kernel's complaint."""
    if type(value) is int or type(value) is float:
        return value  # type: ignore[return-value]
    raise SoarRuntimeError(
        f"'{name}' function called with non-numeric argument {kernel_shown(value)}"
    )


def _abs(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(abs -9223372036854775808)`` stays itself, as C's ``llabs`` leaves it (measured)."""
    return _int64(abs(_math_number("abs", _one("abs", args))))


def _to_int(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The kernel's ``int`` (all measured): a float truncated as C's cast (NaN, infinities
    and out of range give -9223372036854775808); a string read by C's ``strtol``, base 10:
    what leading spaces, a sign and digits spell, 0 if nothing (``|12abc|`` is 12, ``|1e5|``
    1, ``|a|`` 0), an error only when out of 64-bit range; an identifier is an error."""
    value = _one("int", args)
    kind = type(value)
    if kind is int:
        return value
    if kind is float:
        return _c_int64(value)  # type: ignore[arg-type]
    if kind is str:
        number = _strtol(value)  # type: ignore[arg-type]
        if number is None:
            raise SoarRuntimeError(
                f"bad integer ({kernel_shown(value)}) given to 'int' RHS function"
            )
        return number
    raise SoarRuntimeError(f"identifier ({kernel_shown(value)}) passed to 'int' RHS function.")


def _to_float(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The kernel's ``float``: a string read by C's ``strtod`` (what its longest prefix
    spells, 0.0 if nothing: ``|2.5x|`` is 2.5, ``|0x1p3|`` 8.0, ``|a|`` 0.0), an error when
    the number is out of range (``|1e999|``, ``|1e-320|``); an identifier is an error."""
    value = _one("float", args)
    kind = type(value)
    if kind is float:
        return value
    if kind is int:
        return float(value)  # type: ignore[arg-type]
    if kind is str:
        number = _strtod(value)  # type: ignore[arg-type]
        if number is None:
            raise SoarRuntimeError(
                f"bad float ({kernel_shown(value)}) given to 'float' RHS function"
            )
        return number
    raise SoarRuntimeError(f"identifier ({kernel_shown(value)}) passed to 'float' RHS function.")


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
    value = float(_math_number("sqrt", _one("sqrt", args)))
    if value < 0:
        return _X86_NAN
    return math.sqrt(value)


def _min(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return _extreme("min", min, args)


def _max(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return _extreme("max", max, args)


def _extreme(name: str, pick: Callable[[list], Symbol], args: Sequence[Symbol]) -> Symbol:
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
    return _rounded("round-off", args)


def _rounded(name: str, args: Sequence[Symbol]) -> int | float:
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
        return _X86_NAN  # measured: (round-off 1.5 0.0) is -nan
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
    """A string without its leading and trailing spaces; anything else is an error."""
    value = _one("trim", args)
    if type(value) is not str:
        raise FreshLineError(f"non-symbol ({kernel_shown(value)}) passed to 'trim' function.")
    return value.strip()


def _strlen(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return len(format_value(_one("strlen", args)))


def _trig(name: str, fn: Callable[[float], float]) -> RhsFunction:
    """``sin``/``cos``; of an infinity C gives ``-nan`` (measured) where Python raises."""

    def call(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
        try:
            return fn(float(_math_number(name, _one(name, args))))
        except ValueError:
            return _X86_NAN

    return call


def _atan2(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    if len(args) != 2:
        raise SoarRuntimeError("(atan2): needs two arguments")
    for arg in args:
        if type(arg) is not int and type(arg) is not float:
            raise SoarRuntimeError(f"non-number ({kernel_shown(arg)}) passed to atan2")
    return math.atan2(*args)  # type: ignore[arg-type]


# ------------------------------------------------------------------ random numbers

_MT_SIZE = 624
_WORD = 0xFFFFFFFF


def kernel_random(seed: int) -> random.Random:
    """A generator in the state ``srand seed`` leaves the kernel's in, so that it draws the
    kernel's very numbers: Soar seeds its Mersenne Twister with MT19937's ``init_genrand``
    (Python's ``seed`` uses ``init_by_array``, another state), the seed taken modulo 2**32
    (measured: ``srand -1`` reports seed 4294967295)."""
    state = [seed & _WORD]
    for i in range(1, _MT_SIZE):
        prev = state[-1]
        state.append((1812433253 * (prev ^ (prev >> 30)) + i) & _WORD)
    rng = random.Random()
    rng.setstate((3, (*state, _MT_SIZE), None))  # index 624: the next draw regenerates
    return rng


def _rng(ctx: RhsContext) -> random.Random:
    """The agent's generator: the one ``srand`` seeds and indifferent selection draws from."""
    exploration = ctx.exploration
    if exploration.rng is None:
        exploration.rng = random.Random(0)
    return exploration.rng


def _c_int64(value: int | float) -> int:
    """C's ``static_cast<int64_t>``: floats truncate toward zero; NaN, infinities and floats
    out of range give INT64_MIN, as x86 does."""
    if type(value) is int:
        return value
    if math.isfinite(value) and -(2.0**63) <= value < 2.0**63:
        return int(value)
    return -(1 << 63)


def _kernel_number(name: str, value: Symbol) -> int | float:
    """A number argument, with the kernel's complaint for anything else."""
    if type(value) is int or type(value) is float:
        return value  # type: ignore[return-value]
    raise SoarRuntimeError(f"non-number ({kernel_shown(value)}) passed to - {name}")


def _rand_int(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The kernel's ``rand-int`` (measured): with no argument or one that is not positive, a
    32-bit random integer; with ``n`` > 0, an integer in [0, n] (n taken modulo 2**32, a
    float truncated). Arguments after the first are ignored, as in the kernel."""
    limit = _c_int64(_kernel_number("rand-int", args[0])) if args else 0
    rng = _rng(ctx)
    if limit <= 0:
        return rng.getrandbits(32)
    return kernel_rand_int(rng, limit & _WORD)


def kernel_rand_int(rng: random.Random, limit: int) -> int:
    """MTRand's ``randInt(n)`` (the kernel's ``SoarRandInt``), an integer in [0, n]: 32-bit
    draws masked to n's bit length until one is at most n. Python's ``randrange`` takes the
    high bits instead, so it would draw other numbers (and choose other candidates)."""
    mask = limit
    for shift in (1, 2, 4, 8, 16):
        mask |= mask >> shift
    while True:
        draw = rng.getrandbits(32) & mask
        if draw <= limit:
            return draw


def _rand_float(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The kernel's ``rand-float`` (measured): a draw over 2**32 - 1, in [0, 1], scaled by the
    argument when it is positive; arguments after the first are ignored."""
    scale = float(_kernel_number("rand-float", args[0])) if args else 0.0
    fraction = _rng(ctx).getrandbits(32) * (1.0 / 4294967295.0)
    return fraction * scale if scale > 0 else fraction


# ----------------------------------------------------------------------- symbols


def _capitalize_symbol(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The first character upper-cased, in the C locale: ``|éa|`` stays as it is."""
    value = _one("capitalize-symbol", args)
    if type(value) is not str:
        raise FreshLineError(
            f"non-symbol ({kernel_shown(value)}) passed to capitalize-symbol function."
        )
    if value and "a" <= value[0] <= "z":
        return value[0].upper() + value[1:]
    return value


def _string(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """Any symbol as a string; a float with 17 decimals, as the kernel writes it
    (``(string 0.1)`` is ``0.10000000000000001``), not as ``write`` does."""
    value = _one("string", args)
    if type(value) is float:
        return f"{value:.17f}"
    return format_value(value)


# ---------------------------------------------------------------- working memory

#: Augmentations the kernel's architecture puts on a state outside its slots: ``size`` and
#: ``set-count`` do not see them (measured: ``(size <s>)`` on the top state is 3, its
#: ``^reward-link``, ``^epmem`` and ``^smem``, which the memory modules make in slots).
_GOAL_ATTRIBUTES = frozenset(
    {
        "type", "superstate", "attribute", "impasse", "choices", "quiescence",
        "item", "item-count", "non-numeric", "non-numeric-count",
    }
)  # fmt: skip


def _slot_index(ctx: RhsContext) -> dict[Identifier, list[WME]]:
    """Each identifier's WMEs as the kernel's slots hold them: no acceptable operator
    preferences, no goal or impasse augmentations, nothing of the io link or of input
    (measured: ``size`` and ``set-count`` give 0 on the input-link whatever it holds).

    Rule-made WMEs with a goal attribute on a state, or inside the input-link, are left out
    too: our public view of working memory does not tell who made a WME."""
    index: dict[Identifier, list[WME]] = {}
    io_links: list[Symbol] = []
    for wme in ctx.wmes():
        ident = wme.id
        if wme.acceptable:
            continue
        if ident.level is not None:
            if wme.attr in _GOAL_ATTRIBUTES:
                continue
            if wme.attr == "io" and ident.level == 1:
                io_links.append(wme.value)
                continue
        index.setdefault(ident, []).append(wme)
    for ident in _input_side(index, io_links):
        index.pop(ident, None)
    return index


def _input_side(index: dict[Identifier, list[WME]], io_links: list[Symbol]) -> set[Symbol]:
    """The io identifiers and everything reachable from their input-links."""
    side = set(io_links)
    todo = [w.value for io in io_links for w in _with_attr(index, io, "input-link")]
    while todo:
        ident = todo.pop()
        if type(ident) is Identifier and ident not in side:
            side.add(ident)
            todo.extend(w.value for w in index.get(ident, ()))
    return side


def _size(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """How many augmentations an identifier has, as the kernel counts them (`_slot_index`)."""
    value = _one("size", args)
    if type(value) is not Identifier:
        raise SoarRuntimeError(f"non-symbol ({kernel_shown(value)}) passed to size function")
    return len(_slot_index(ctx).get(value, ()))


#: What the kernel's ``set-count`` returns for a first argument that is not an identifier:
#: a symbol whose text includes the vertical bars (measured).
SET_COUNT_ERROR = "|ERROR: First parameter needs to be an identifier.|"


def _set_count(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(set-count <id> a b ...)``: how many WMEs the path ``<id>.a.b...`` reaches, a WME
    counted once per path to it; with no attribute, 0 (all measured). Without arguments the
    kernel crashes; we answer as for a non-identifier."""
    if not args or type(args[0]) is not Identifier:
        return SET_COUNT_ERROR
    if len(args) == 1:
        return 0
    index = _slot_index(ctx)
    reached: list[Symbol] = [args[0]]
    count = 0
    for attr in args[1:]:
        found = [w for ident in reached for w in _with_attr(index, ident, attr)]
        count = len(found)
        reached = [w.value for w in found]
    return count


def _with_attr(index: dict[Identifier, list[WME]], ident: Symbol, attr: Symbol) -> list[WME]:
    if type(ident) is not Identifier:
        return []
    return [w for w in index.get(ident, ()) if type(w.attr) is type(attr) and w.attr == attr]


# ------------------------------------------------------ arithmetic over working memory


def kernel_shown(value: Symbol) -> str:
    """A symbol as the kernel's error messages show it: a string that would read as a number
    in bars (measured: ``non-number (|2|) passed as 'count'``), floats as ``%f``."""
    if type(value) is str:
        return format_constant(value)
    return format_value(value)


def _int32(value: int) -> int:
    """The low 32 bits of an integer, as a C ``int``."""
    return ((value + (1 << 31)) & _WORD) - (1 << 31)


def _int_view(name: str, value: Symbol) -> int:
    """What the kernel's ``sum`` and ``product`` read from a value: the symbol's value field
    taken as a 32-bit ``int`` whatever the symbol is (all measured): an integer's low 32 bits
    (``10000000000`` reads 1410065408), a float's low 32 bits of its IEEE double (``2.0``
    reads 0, ``0.1`` -1717986918), an identifier's number (``I4`` reads 4). A string reads
    the bits of a pointer, a different number on each run: we refuse it instead."""
    kind = type(value)
    if kind is int:
        return _int32(value)  # type: ignore[arg-type]
    if kind is float:
        return _int32(struct.unpack("<q", struct.pack("<d", value))[0])
    if kind is Identifier:
        return _int32(value.number)  # type: ignore[union-attr]
    raise SoarRuntimeError(
        f"({name}): the kernel reads a memory address for the string value"
        f" {kernel_shown(value)}; this engine refuses it"
    )


def _wme_values(name: str, ctx: RhsContext, args: Sequence[Symbol]) -> list[int]:
    ident = _one(name, args)
    if type(ident) is not Identifier:
        raise SoarRuntimeError(f"non-symbol ({kernel_shown(ident)}) passed to {name} function")
    return [_int_view(name, w.value) for w in _slot_index(ctx).get(ident, ())]


def _sum(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(sum <id>)``: the values of ``<id>``'s WMEs (those ``size`` counts) added as C
    ``int``s, wrapping at 32 bits (measured: 2147483647 + 1 is -2147483648; see `_int_view`
    for what a value reads as)."""
    total = 0
    for value in _wme_values("sum", ctx, args):
        total = _int32(total + value)
    return total


def _product(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(product <id>)``: as `_sum`, multiplied (65536 * 65536 is 0; no WMEs give 1)."""
    total = 1
    for value in _wme_values("product", ctx, args):
        total = _int32(total * value)
    return total


#: What the kernel's ``set-*`` statistics return when the path reaches no number: a string.
SET_NAN = "NaN"


def _set_numbers(ctx: RhsContext, args: Sequence[Symbol]) -> list[float] | str:
    """The numbers ``set-count``'s path reaches (a WME once per path to it), as floats, in
    working-memory order; or `SET_COUNT_ERROR` when the first argument is no identifier."""
    if not args or type(args[0]) is not Identifier:
        return SET_COUNT_ERROR
    if len(args) == 1:
        return []
    index = _slot_index(ctx)
    reached: list[Symbol] = [args[0]]
    for attr in args[1:]:
        reached = [w.value for ident in reached for w in _with_attr(index, ident, attr)]
    return [float(v) for v in reached if type(v) is int or type(v) is float]


def _set_statistic(reduce: Callable[[list[float]], float]) -> RhsFunction:
    """A ``set-*`` function: ``(set-sum <id> a b ...)`` follows the path as ``set-count``
    does and reduces the numbers it reaches, ignoring other values, to a float; with no
    number the kernel returns the string ``NaN`` (all measured)."""

    def call(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
        numbers = _set_numbers(ctx, args)
        if type(numbers) is str:
            return numbers
        return reduce(numbers) if numbers else SET_NAN  # type: ignore[arg-type]

    return call


def _running_sum(numbers: list[float]) -> float:
    total = 0.0
    for n in numbers:
        total += n
    return total


def _running_product(numbers: list[float]) -> float:
    total = 1.0
    for n in numbers:
        total *= n
    return total


def _mean(numbers: list[float]) -> float:
    return _running_sum(numbers) / len(numbers)


def _stdev(numbers: list[float]) -> float:
    """The population standard deviation (measured: 1, 2, 3 give 0.816497)."""
    mean = _mean(numbers)
    return math.sqrt(_running_sum([(n - mean) * (n - mean) for n in numbers]) / len(numbers))


# -------------------------------------------------------------------- positions

#: The kernel's pi for ``haversine`` and the ``extrapolate-*`` functions: with ``math.pi``
#: 5 of 63 measured distances differ in the last digits, with 3.141592653589 none do.
_GEO_PI = 3.141592653589
_EARTH_KM = 6371.0


def _haversine(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(haversine lat1 lon1 lat2 lon2)``: the great-circle distance in km between two
    points given in degrees, computed as the kernel does to the last bit (63 cases)."""
    lat1, lon1, lat2, lon2 = (_geo_number(a) for a in _four("haversine", args))
    rad = _GEO_PI / 180
    phi1, phi2 = lat1 * rad, lat2 * rad
    half_lat = math.sin((phi2 - phi1) / 2)
    half_lon = math.sin((lon2 * rad - lon1 * rad) / 2)
    a = half_lat * half_lat + math.cos(phi1) * math.cos(phi2) * half_lon * half_lon
    return _EARTH_KM * (2 * math.atan2(math.sqrt(a), math.sqrt(1 - a)))


def _four(name: str, args: Sequence[Symbol]) -> Sequence[Symbol]:
    if len(args) != 4:
        raise SoarRuntimeError(f"'{name}' takes exactly 4 arguments.")
    return args


def _geo_number(value: Symbol) -> float:
    if type(value) is int or type(value) is float:
        return float(value)  # type: ignore[arg-type]
    raise SoarRuntimeError(f"non int/float ({kernel_shown(value)}) passed to haversine function.")


def _extrapolate(name: str, trig: Callable[[float], float]) -> RhsFunction:
    """``(extrapolate-x-position x heading speed time)`` and its ``y`` twin: where a thing
    at ``x`` moving ``speed`` along ``heading`` (degrees clockwise from +y) is after
    ``time``. All measured: integers only; ``speed * time`` wraps at 64 bits, the move is
    rounded to a C ``int`` (out of range: -2147483648), then added with 64-bit wrapping;
    y grows downwards: the move along cos(heading) is subtracted (``(extrapolate-y-position
    10 0 5 2)`` is 0, and a move out of range makes y 2147483648 more)."""
    sign = -1 if name == "extrapolate-y-position" else 1

    def call(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
        start, heading, speed, time_ = (_whole(name, a) for a in _four(name, args))
        distance = float(_int64(speed * time_)) * trig(heading * _GEO_PI / 180)
        return _int64(start + sign * _c_int32(math.floor(distance + 0.5)))

    return call


def _whole(name: str, value: Symbol) -> int:
    if type(value) is int:
        return value  # type: ignore[return-value]
    raise SoarRuntimeError(f"non int({kernel_shown(value)}) passed to {name} function.")


def _c_int32(value: float) -> int:
    """C's ``(int)`` of a double on x86: out of range or NaN gives -2147483648."""
    if math.isfinite(value) and -(2.0**31) <= value < 2.0**31:
        return int(value)
    return -(1 << 31)


# ------------------------------------------------------------------------ dice

_DICE_PREDICATES = ("eq", "ne", "lt", "gt", "le", "ge")

#: The kernel answers 0 for any probability below this (measured: 2.0027e-5 is kept,
#: 9.5367e-6 and smaller give 0.000000).
_DICE_FLOOR = 1e-5


def _compute_dice_probability(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(compute-dice-probability dice sides count pred)``: the chance that, of ``dice``
    fair ``sides``-sided dice, the number showing a given face compares to ``count`` by
    ``pred`` (eq ne lt gt le ge). Numbers are truncated to integers; no dice, no sides or
    a count out of range count as impossible; a result below 1e-5 is 0 (all measured).

    We compute the binomial exactly and round once; the kernel's own arithmetic is a few
    units in the last place off (invisible in ``write``'s six decimals) and breaks down
    beyond about 50 dice (-nan from 500 dice on), which we do not copy."""
    *numbers, last = _four("compute-dice-probability", args)
    roles = ("dice", "sides", "count")
    dice, sides, count = (_c_int64(_dice_number(r, a)) for r, a in zip(roles, numbers, strict=True))
    pred = _dice_predicate(last)
    if pred in ("eq", "ne"):
        chance = _dice_exactly(dice, sides, count)
    else:
        chance = _dice_at_least(dice, sides, count + (pred in ("gt", "le")))
    if pred in ("ne", "lt", "le"):
        chance = 1 - chance
    return 0.0 if chance < _DICE_FLOOR else float(chance)


def _dice_number(role: str, value: Symbol) -> int | float:
    if type(value) is int or type(value) is float:
        return value  # type: ignore[return-value]
    raise SoarRuntimeError(
        f"non-number ({kernel_shown(value)}) passed as '{role}' to - compute-dice-probability"
    )


def _dice_predicate(value: Symbol) -> str:
    if type(value) is not str:
        raise SoarRuntimeError(
            f"non-string ({kernel_shown(value)}) passed as 'pred' to - compute-dice-probability"
        )
    if value not in _DICE_PREDICATES:
        raise SoarRuntimeError(
            f"invalid string ({kernel_shown(value)}) passed as 'pred' to - compute-dice-probability"
        )
    return value


def _dice_exactly(dice: int, sides: int, count: int) -> Fraction:
    if sides <= 0 or not 0 <= count <= dice:
        return Fraction(0)
    return Fraction(math.comb(dice, count) * (sides - 1) ** (dice - count), sides**dice)


def _dice_at_least(dice: int, sides: int, count: int) -> Fraction:
    """At least ``count`` matches: certain for a count of 0 or less, whatever the dice."""
    if count <= 0:
        return Fraction(1)
    if sides <= 0 or count > dice:
        return Fraction(0)
    ways = sum(math.comb(dice, i) * (sides - 1) ** (dice - i) for i in range(count, dice + 1))
    return Fraction(ways, sides**dice)


# ---------------------------------------------------------------------- headings

#: The kernel's value of pi for headings: with ``math.pi``, 32 of 316 measured headings
#: differ; with 3.14159 none do (``(compute-heading 0 0 1 1)`` is 44).
_HEADING_PI = 3.14159


def _coordinates(name: str, args: Sequence[Symbol]) -> list[int | float]:
    if len(args) != 4:
        raise SoarRuntimeError(f"'{name}' takes exactly 4 arguments.")
    return [_kernel_number(name, a) for a in args]


def _compute_heading(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """Degrees clockwise from +y of the way from (x1, y1) to (x2, y2), in (-180, 180],
    truncated; the coordinates are truncated to integers first (all as the kernel does:
    ``(compute-heading 3 -0.5 2 1)`` is -45, ``(compute-heading 0 0 0 -1)`` is -179)."""
    x1, y1, x2, y2 = (_c_int64(v) for v in _coordinates("compute-heading", args))
    heading = math.atan2(y2 - y1, x2 - x1) - _HEADING_PI / 2
    if heading < 0.0:
        heading += 2 * _HEADING_PI
    heading = 2 * _HEADING_PI - heading
    if heading > _HEADING_PI:
        heading -= 2 * _HEADING_PI
    return _c_int64(heading * 180 / _HEADING_PI)


def _compute_range(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The distance from (x1, y1) to (x2, y2), in floating point, truncated to an integer."""
    x1, y1, x2, y2 = (float(v) for v in _coordinates("compute-range", args))
    dx, dy = x2 - x1, y2 - y1
    return _c_int64(math.sqrt(dx * dx + dy * dy))


def _round_off_heading(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``round-off``, then brought into (-180, 180] (measured: ``(round-off-heading 175 10)``
    is 180, ``(round-off-heading -175 10)`` 180, ``(round-off-heading 185 10)`` -170). The
    kernel crashes on a zero integer precision; we report it as ``round-off`` does."""
    return _heading_range(_rounded("round-off-heading", args))


def _heading_range(value: int | float) -> int | float:
    """The kernel's loops ``while h > 180: h -= 360``, ``while h <= -180: h += 360``, with one
    exact remainder (a loop would take forever on 1e18); a multiple of 360 ends as +0."""
    if -180 < value <= 180:
        return value
    if type(value) is float:
        rest: int | float = math.fmod(value, 360.0) + 0.0  # + 0.0 turns -0.0 into 0.0
    else:
        rest = value % 360  # exact for integers of any size
    if rest > 180:
        return rest - 360
    if rest <= -180:
        return rest + 360
    return rest


# --------------------------------------------------------------- stand-alone actions


def _learning(name: str) -> RhsFunction:
    """``dont-learn``/``force-learn``: the kernel checks the state and marks it for
    ``chunk except`` / ``chunk only`` (measured: no output)."""

    def call(ctx: RhsContext, args: Sequence[Symbol]) -> None:
        state = _one(name, args)
        if type(state) is not Identifier:
            raise FreshLineError(
                f"non-identifier ({kernel_shown(state)}) passed to {name} function."
            )
        if not state.is_state:
            raise FreshLineError(f"identifier passed to {name} is not a state: {state}.")
        ctx.mark_learning(name, state)
        return None

    return call


_LOG_CHANNELS = 100


def _log(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    """``(log <channel> text...)``: the text, as ``write`` prints it, on the agent's output;
    the channel must be an integer from 1 to 100 (measured, message included)."""
    channel = args[0] if args else None
    if type(channel) is not int or not 1 <= channel <= _LOG_CHANNELS:
        shown = "(none)" if channel is None else kernel_shown(channel)
        raise FreshLineError(
            "First argument of agent's (log) rhs-function must be an integer channel number"
            f" between 1 and {_LOG_CHANNELS}.  {shown} is invalid."
        )
    ctx.write_output("".join(format_value(a) for a in args[1:]))
    return None


def _count(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    """The kernel's ``count`` changes nothing one can see, in output or memory (measured)."""
    return None


def _wait(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    """``(wait <ms>)`` sleeps that many milliseconds; any other argument, a float included,
    is ignored (measured: ``(wait 1500)`` takes 1.5 s, ``(wait 1000.0)`` no time)."""
    delay = _one("wait", args)
    if type(delay) is int and delay > 0:
        time.sleep(delay / 1000)
    return None


# -------------------------------------------------------------------------- deep-copy

#: What ``deep-copy`` returns for an argument that is not an identifier (measured).
DEEP_COPY_NOT_ID = "*symbol not id*"

#: A state's architecture WMEs that the memory modules keep in slots; the others
#: (``^type``, ``^superstate``, impasse augmentations) are not copied.
_MODULE_LINKS = ("reward-link", "epmem", "smem")


class DeepCopies:
    """The firing instantiation, while ``deep-copy`` has preferences waiting for it.

    The kernel adds a copy's preferences to the instantiation right after the preference of
    the action that called ``deep-copy`` (measured: ``(S1 ^copy D1)`` takes the timetag
    before the copy's WMEs, the action's next preference the one after them). A function
    runs before its action's preference exists, so the copies wait here, with the number
    of preferences the instantiation had then, and `settle` puts them in place once the
    rule's actions are done (the agent calls it when ``firing`` is no longer the
    instantiation it set)."""

    __slots__ = ("inst", "groups")

    def __init__(self, inst: object) -> None:
        self.inst = inst
        self.groups: list[tuple[int, list[Preference]]] = []

    def settle(self) -> None:
        prefs: list[Preference] = self.inst.prefs  # type: ignore[attr-defined]
        for index, copies in reversed(self.groups):  # later groups first: indices stay valid
            if index < len(prefs):
                ptype = prefs[index].type
                for pref in copies:  # the copies take the action's preference type
                    pref.type = ptype
            prefs[index + 1 : index + 1] = copies
        self.groups = []


def _deep_copy(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(deep-copy <id>)``: a new identifier (letter D) holding a copy of everything
    reachable from ``<id>``, each identifier copied once (shared structure and cycles stay
    so) under a new one of its own letter, at ``<id>``'s level. The copies are preferences
    of the firing rule, with its support. Walked as the kernel walks them (all measured):
    depth first, a WME after the identifiers below it, an identifier's slots newest first
    and their WMEs newest first, then its input WMEs newest first; a state's ``^type``,
    ``^superstate`` and impasse augmentations and its acceptable operator preferences are
    left out, its ``^io``, ``^reward-link``, ``^epmem``, ``^smem`` and selected operator
    copied."""
    base = _one("deep-copy", args)
    if type(base) is not Identifier:
        return DEEP_COPY_NOT_ID
    agent: Any = ctx
    firing = agent.firing
    if type(firing) is not DeepCopies:
        firing = agent.firing = DeepCopies(firing)
    inst: Any = firing.inst
    level = agent._level_of(base)
    new_id = agent._new_id
    root = new_id("D", level)
    made: list[tuple[Identifier, Symbol, Symbol]] = []
    copied: dict[Identifier, Identifier] = {}
    views = _KernelSlots(agent)

    def copy_of(ident: Identifier) -> Identifier:
        twin = copied.get(ident)
        if twin is None:
            twin = new_id(ident.letter, level)
        walk(ident, twin)
        return twin

    def walk(ident: Identifier, twin: Identifier) -> None:
        if ident in copied:
            return
        copied[ident] = twin
        for wme in views.of(ident):
            attr, value = wme.attr, wme.value
            if type(attr) is Identifier:
                attr = copy_of(attr)
            if type(value) is Identifier:
                value = copy_of(value)
            made.append((twin, attr, value))

    walk(base, root)
    o_supported = bool(inst.o_support)
    prefs = []
    for ident, attr, value in made:
        pref = Preference("+", ident, attr, value, None, inst)
        pref.o_supported = o_supported
        prefs.append(pref)
    firing.groups.append((len(inst.prefs), prefs))
    return root


class _KernelSlots:
    """An identifier's WMEs in the order the kernel's ``deep-copy`` visits them: its slots
    newest first (a state's module links are in slots made before its operator slot), the
    WMEs of a slot newest first, then its input WMEs (``^io``, the io link's, the
    environment's) newest first."""

    def __init__(self, agent: Any) -> None:
        self.agent = agent
        self.modules: set[Symbol] = set()
        for ident in agent._goals:
            for wme in agent._arch.get(ident, ()):
                if wme.attr in _MODULE_LINKS:
                    self.modules.add(wme.value)

    def of(self, ident: Identifier) -> list[WME]:
        agent = self.agent
        slots: dict[Symbol, list[WME]] = {}
        inputs: list[WME] = []
        is_goal = ident in agent._goals
        for wme in agent._arch.get(ident, ()):
            if is_goal and wme.attr in _GOAL_ATTRIBUTES:
                continue
            if (is_goal and wme.attr != "io") or ident in self.modules:
                slots.setdefault(_slot_key(wme.attr), []).append(wme)
            else:
                inputs.append(wme)
        for key, slot in agent._slots.get(ident, {}).items():
            if slot.wmes:
                slots.setdefault(key, []).extend(slot.wmes.values())
        out: list[WME] = []
        for wmes in reversed(slots.values()):
            out.extend(sorted(wmes, key=_timetag, reverse=True))
        out.extend(sorted(inputs, key=_timetag, reverse=True))
        return out


def _slot_key(attr: Symbol) -> object:
    return attr if type(attr) is not float else (float, attr)


def _timetag(wme: WME) -> int:
    return wme.timetag


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
    "rand-int": _rand_int,
    "rand-float": _rand_float,
    "capitalize-symbol": _capitalize_symbol,
    "string": _string,
    "size": _size,
    "set-count": _set_count,
    "sum": _sum,
    "product": _product,
    "set-sum": _set_statistic(_running_sum),
    "set-multiply": _set_statistic(_running_product),
    "set-min": _set_statistic(min),
    "set-max": _set_statistic(max),
    "set-range": _set_statistic(lambda numbers: max(numbers) - min(numbers)),
    "set-mean": _set_statistic(_mean),
    "set-stdev": _set_statistic(_stdev),
    "haversine": _haversine,
    "extrapolate-x-position": _extrapolate("extrapolate-x-position", math.sin),
    "extrapolate-y-position": _extrapolate("extrapolate-y-position", math.cos),
    "compute-dice-probability": _compute_dice_probability,
    "compute-heading": _compute_heading,
    "compute-range": _compute_range,
    "round-off-heading": _round_off_heading,
    "dont-learn": _learning("dont-learn"),
    "force-learn": _learning("force-learn"),
    "log": _log,
    "count": _count,
    "wait": _wait,
    "deep-copy": _deep_copy,
}
