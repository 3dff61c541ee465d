"""Functions about the run rather than its data: ``halt`` and ``interrupt`` (they ask the agent
to stop), ``wait``, ``dc`` and ``timestamp`` (its clocks), and ``count``, ``dont-learn`` and
``force-learn``, which mark a state for ``chunk except`` / ``chunk only``.
"""

from __future__ import annotations

import datetime
import time
from collections.abc import Sequence

from sann.soar.memory import Identifier, Symbol
from sann.soar.rhs.context import FreshLineError, RhsContext, RhsFunction, one
from sann.soar.text import format_symbol


def _halt(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    ctx.request_halt()
    return None


def _interrupt(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    ctx.request_interrupt()
    return None


def _wait(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    """``(wait <ms>)`` sleeps that many milliseconds; any other argument, a float included,
    is ignored (measured: ``(wait 1500)`` takes 1.5 s, ``(wait 1000.0)`` no time)."""
    delay = one("wait", args)
    if type(delay) is int and delay > 0:
        time.sleep(delay / 1000)
    return None


def _dc(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return ctx.decision_count()


def _timestamp(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    now = datetime.datetime.now()
    return now.strftime("%Y-%m-%d %H:%M:%S.") + f"{now.microsecond // 1000:03d}"


def _count(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    """The kernel's ``count`` changes nothing one can see, in output or memory (measured)."""
    return None


def _learning(name: str) -> RhsFunction:
    """``dont-learn``/``force-learn``: the kernel checks the state and marks it for
    ``chunk except`` / ``chunk only`` (measured: no output)."""

    def call(ctx: RhsContext, args: Sequence[Symbol]) -> None:
        state = one(name, args)
        if type(state) is not Identifier:
            raise FreshLineError(
                f"non-identifier ({format_symbol(state)}) passed to {name} function."
            )
        if not state.is_state:
            raise FreshLineError(f"identifier passed to {name} is not a state: {state}.")
        ctx.mark_learning(name, state)
        return None

    return call


#: This family's functions, by the name a rule calls them with.
FUNCTIONS: dict[str, RhsFunction] = {
    "timestamp": _timestamp,
    "halt": _halt,
    "interrupt": _interrupt,
    "dc": _dc,
    "dont-learn": _learning("dont-learn"),
    "force-learn": _learning("force-learn"),
    "count": _count,
    "wait": _wait,
}
