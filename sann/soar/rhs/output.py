"""The agent's output: ``write`` and ``log`` print symbols as `text.format_value` renders
them; ``(crlf)`` is the newline they print.
"""

from __future__ import annotations

from collections.abc import Sequence

from sann.soar.memory import Symbol
from sann.soar.rhs.context import FreshLineError, RhsContext, RhsFunction
from sann.soar.text import format_symbol, format_value

#: Value returned by ``(crlf)``: a symbol holding a newline, as in the kernel.
CRLF = "\n"


def _write(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    ctx.write_output("".join(format_value(a) for a in args))
    return None


def _crlf(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    return CRLF


_LOG_CHANNELS = 100


def _log(ctx: RhsContext, args: Sequence[Symbol]) -> None:
    """``(log <channel> text...)``: the text, as ``write`` prints it, on the agent's output;
    the channel must be an integer from 1 to 100 (measured, message included)."""
    channel = args[0] if args else None
    if type(channel) is not int or not 1 <= channel <= _LOG_CHANNELS:
        shown = "(none)" if channel is None else format_symbol(channel)
        raise FreshLineError(
            "First argument of agent's (log) rhs-function must be an integer channel number"
            f" between 1 and {_LOG_CHANNELS}.  {shown} is invalid."
        )
    ctx.write_output("".join(format_value(a) for a in args[1:]))
    return None


#: This family's functions, by the name a rule calls them with.
FUNCTIONS: dict[str, RhsFunction] = {
    "write": _write,
    "crlf": _crlf,
    "log": _log,
}
