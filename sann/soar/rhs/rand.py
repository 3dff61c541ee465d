"""``rand-int`` and ``rand-float``, and the kernel's random generator.

Both draw from the agent's one generator, the one indifferent selection uses, as the kernel's
do: Soar has a single Mersenne Twister for both (measured: after ``srand 7`` an indifferent
choice takes the first draw and ``(rand-int)`` gets the second). `kernel_random` builds the
generator in the state ``srand N`` puts the kernel's in; the draws are the kernel's
(``getrandbits(32)`` is MT19937's 32-bit output), and ``Agent.srand`` uses it: after the same
``srand`` the random functions give the kernel's very numbers (until an indifferent choice,
whose draws follow our own selection code).
"""

from __future__ import annotations

import random
from collections.abc import Sequence

from sann.soar.memory import Symbol
from sann.soar.rhs.context import WORD, RhsContext, RhsFunction, c_int64, kernel_number

_MT_SIZE = 624


def kernel_random(seed: int) -> random.Random:
    """A generator in the state ``srand seed`` leaves the kernel's in, so that it draws the
    kernel's very numbers: Soar seeds its Mersenne Twister with MT19937's ``init_genrand``
    (Python's ``seed`` uses ``init_by_array``, another state), the seed taken modulo 2**32
    (measured: ``srand -1`` reports seed 4294967295)."""
    state = [seed & WORD]
    for i in range(1, _MT_SIZE):
        prev = state[-1]
        state.append((1812433253 * (prev ^ (prev >> 30)) + i) & WORD)
    rng = random.Random()
    rng.setstate((3, (*state, _MT_SIZE), None))  # index 624: the next draw regenerates
    return rng


def _rng(ctx: RhsContext) -> random.Random:
    """The agent's generator: the one ``srand`` seeds and indifferent selection draws from."""
    exploration = ctx.exploration
    if exploration.rng is None:
        exploration.rng = random.Random(0)
    return exploration.rng


def _rand_int(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The kernel's ``rand-int`` (measured): with no argument or one that is not positive, a
    32-bit random integer; with ``n`` > 0, an integer in [0, n] (n taken modulo 2**32, a
    float truncated). Arguments after the first are ignored, as in the kernel."""
    limit = c_int64(kernel_number("rand-int", args[0])) if args else 0
    rng = _rng(ctx)
    if limit <= 0:
        return rng.getrandbits(32)
    return kernel_rand_int(rng, limit & WORD)


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
    scale = float(kernel_number("rand-float", args[0])) if args else 0.0
    fraction = _rng(ctx).getrandbits(32) * (1.0 / 4294967295.0)
    return fraction * scale if scale > 0 else fraction


#: This family's functions, by the name a rule calls them with.
FUNCTIONS: dict[str, RhsFunction] = {
    "rand-int": _rand_int,
    "rand-float": _rand_float,
}
