"""Functions that read working memory: ``size`` and ``set-count`` count augmentations,
``sum`` and ``product`` combine an identifier's values as C ``int``s, and the ``set-*``
statistics reduce the numbers a path reaches. They see working memory as the kernel's slots
hold it (`slot_index`).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Sequence

from sann.soar.errors import SoarRuntimeError
from sann.soar.memory import WME, Identifier, Symbol
from sann.soar.rhs.context import WORD, RhsContext, RhsFunction, one
from sann.soar.text import format_symbol

#: Augmentations the kernel's architecture puts on a state outside its slots: ``size`` and
#: ``set-count`` do not see them (measured: ``(size <s>)`` on the top state is 3, its
#: ``^reward-link``, ``^epmem`` and ``^smem``, which the memory modules make in slots).
GOAL_ATTRIBUTES = frozenset(
    {
        "type", "superstate", "attribute", "impasse", "choices", "quiescence",
        "item", "item-count", "non-numeric", "non-numeric-count",
    }
)  # fmt: skip


def slot_index(ctx: RhsContext) -> dict[Identifier, list[WME]]:
    """Each identifier's WMEs as the kernel's slots hold them: no acceptable operator
    preferences, no goal or impasse augmentations, nothing of the io link or of input
    (measured: ``size`` and ``set-count`` give 0 on the input-link whatever it holds).

    Rule-made WMEs with a goal attribute on a state, or inside the input-link, are left out
    too: our public view of working memory does not tell who made a WME."""
    index: dict[Identifier, list[WME]] = {}
    io_links: list[Identifier] = []
    for wme in ctx.wmes():
        ident = wme.id
        if wme.acceptable:
            continue
        if ident.level is not None:
            if wme.attr in GOAL_ATTRIBUTES:
                continue
            if wme.attr == "io" and ident.level == 1:
                if type(wme.value) is Identifier:
                    io_links.append(wme.value)
                continue
        index.setdefault(ident, []).append(wme)
    for linked in _input_side(index, io_links):
        index.pop(linked, None)
    return index


def _input_side(
    index: dict[Identifier, list[WME]], io_links: list[Identifier]
) -> set[Identifier]:
    """The io identifiers and everything reachable from their input-links."""
    side = set(io_links)
    todo: list[Symbol] = [w.value for io in io_links for w in with_attr(index, io, "input-link")]
    while todo:
        ident = todo.pop()
        if type(ident) is Identifier and ident not in side:
            side.add(ident)
            todo.extend(w.value for w in index.get(ident, ()))
    return side


def _size(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """How many augmentations an identifier has, as the kernel counts them (`slot_index`)."""
    value = one("size", args)
    if type(value) is not Identifier:
        raise SoarRuntimeError(f"non-symbol ({format_symbol(value)}) passed to size function")
    return len(slot_index(ctx).get(value, ()))


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
    index = slot_index(ctx)
    reached: list[Symbol] = [args[0]]
    count = 0
    for attr in args[1:]:
        found = [w for ident in reached for w in with_attr(index, ident, attr)]
        count = len(found)
        reached = [w.value for w in found]
    return count


def with_attr(index: dict[Identifier, list[WME]], ident: Symbol, attr: Symbol) -> list[WME]:
    if type(ident) is not Identifier:
        return []
    return [w for w in index.get(ident, ()) if type(w.attr) is type(attr) and w.attr == attr]


def _int32(value: int) -> int:
    """The low 32 bits of an integer, as a C ``int``."""
    return ((value + (1 << 31)) & WORD) - (1 << 31)


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
        f" {format_symbol(value)}; this engine refuses it"
    )


def _wme_values(name: str, ctx: RhsContext, args: Sequence[Symbol]) -> list[int]:
    ident = one(name, args)
    if type(ident) is not Identifier:
        raise SoarRuntimeError(f"non-symbol ({format_symbol(ident)}) passed to {name} function")
    return [_int_view(name, w.value) for w in slot_index(ctx).get(ident, ())]


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
    index = slot_index(ctx)
    reached: list[Symbol] = [args[0]]
    for attr in args[1:]:
        reached = [w.value for ident in reached for w in with_attr(index, ident, attr)]
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


#: This family's functions, by the name a rule calls them with.
FUNCTIONS: dict[str, RhsFunction] = {
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
}
