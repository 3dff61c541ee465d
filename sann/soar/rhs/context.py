"""What every family of right-hand-side functions shares: the part of the agent a function may
touch (`RhsContext`), the function type, the error that starts on a fresh line, and the
argument checks and C integer conversions several families use.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable, Iterable, Sequence
from typing import Protocol

from sann.soar.errors import SoarRuntimeError
from sann.soar.memory import WME, Identifier, Symbol
from sann.soar.text import format_symbol


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


class FreshLineError(SoarRuntimeError):
    """An RHS error whose kernel message starts on a fresh line: after a newline unless the
    output is already at the start of one (measured for ``trim``, ``capitalize-symbol``,
    ``dont-learn``, ``force-learn`` and ``log``; the other functions' messages follow
    whatever was printed last, ``xError: ...``). Both end with a newline."""

    fresh_line = True


def one(name: str, args: Sequence[Symbol]) -> Symbol:
    if len(args) != 1:
        raise SoarRuntimeError(f"({name}): needs exactly one argument")
    return args[0]


def four(name: str, args: Sequence[Symbol]) -> Sequence[Symbol]:
    if len(args) != 4:
        raise SoarRuntimeError(f"'{name}' takes exactly 4 arguments.")
    return args


#: The bits of a 32-bit word (C's unsigned int).
WORD = 0xFFFFFFFF


def int64(value: int | float) -> int | float:
    """The kernel's integers are 64-bit and wrap around (measured:
    ``(+ 9223372036854775807 1)`` is -9223372036854775808); floats are left alone."""
    if type(value) is int and not -(1 << 63) <= value < 1 << 63:
        return ((value + (1 << 63)) & ((1 << 64) - 1)) - (1 << 63)
    return value


def c_int64(value: int | float) -> int:
    """C's ``static_cast<int64_t>``: floats truncate toward zero; NaN, infinities and floats
    out of range give INT64_MIN, as x86 does."""
    if type(value) is int:
        return value
    if math.isfinite(value) and -(2.0**63) <= value < 2.0**63:
        return int(value)
    return -(1 << 63)


def kernel_number(name: str, value: Symbol) -> int | float:
    """A number argument, with the kernel's complaint for anything else."""
    if type(value) is int or type(value) is float:
        return value  # type: ignore[return-value]
    raise SoarRuntimeError(f"non-number ({format_symbol(value)}) passed to - {name}")


#: The NaN x86 makes of an invalid operation (``sqrt(-1)``, ``inf * 0``): sign bit set.
X86_NAN = -math.nan
