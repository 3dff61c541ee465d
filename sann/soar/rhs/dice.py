"""``compute-dice-probability``: the chance that a face shows on so many of a number of fair
dice, exactly (the kernel's own arithmetic breaks down beyond about 50 dice).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from fractions import Fraction

from sann.soar.errors import SoarRuntimeError
from sann.soar.memory import Symbol
from sann.soar.rhs.context import RhsContext, RhsFunction, c_int64, four
from sann.soar.text import format_symbol

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
    *numbers, last = four("compute-dice-probability", args)
    roles = ("dice", "sides", "count")
    dice, sides, count = (c_int64(_dice_number(r, a)) for r, a in zip(roles, numbers, strict=True))
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
        f"non-number ({format_symbol(value)}) passed as '{role}' to - compute-dice-probability"
    )


def _dice_predicate(value: Symbol) -> str:
    if type(value) is not str:
        raise SoarRuntimeError(
            f"non-string ({format_symbol(value)}) passed as 'pred' to - compute-dice-probability"
        )
    if value not in _DICE_PREDICATES:
        raise SoarRuntimeError(
            f"invalid string ({format_symbol(value)}) passed as 'pred' to"
            " - compute-dice-probability"
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


#: This family's functions, by the name a rule calls them with.
FUNCTIONS: dict[str, RhsFunction] = {
    "compute-dice-probability": _compute_dice_probability,
}
