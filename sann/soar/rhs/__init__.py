"""Right-hand-side functions, with the Soar 9.6 kernel's arithmetic and text conventions, by
family: `arithmetic`, `symbols`, `output` (``write``, ``crlf``, ``log``), `control` (``halt``,
``interrupt``, ``wait``, clocks), `rand` (the kernel's random generator), `wm` (functions that
read working memory), `geometry`, `dice` and `deep_copy`; `context` is what they share.
`FUNCTIONS` below is the registry the agent calls them through.

Which functions may be called where, and with how many arguments, is checked when a rule is
loaded (`sann.soar.parsing.actions`); the functions still check their arguments, for direct
calls.

A function given bad arguments raises `SoarRuntimeError` with the kernel's very text
(measured in soar_sml 9.6, symbols shown as the kernel's messages show them,
`text.format_symbol`); the agent prints it as ``Error: <text>`` and a newline where the
output stands, or on a fresh line for a `context.FreshLineError`, and drops the action.
"""

from __future__ import annotations

from sann.soar.rhs import (
    arithmetic,
    control,
    deep_copy,
    dice,
    geometry,
    output,
    rand,
    symbols,
    wm,
)
from sann.soar.rhs.context import RhsFunction

__all__ = ["FUNCTIONS"]

#: Every right-hand-side function, by the name a rule calls it with.
FUNCTIONS: dict[str, RhsFunction] = {
    **arithmetic.FUNCTIONS,
    **symbols.FUNCTIONS,
    **output.FUNCTIONS,
    **control.FUNCTIONS,
    **rand.FUNCTIONS,
    **wm.FUNCTIONS,
    **geometry.FUNCTIONS,
    **dice.FUNCTIONS,
    **deep_copy.FUNCTIONS,
}
