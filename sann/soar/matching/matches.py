"""What a matcher reports: matches (instantiations) and the changes since the last look."""

from __future__ import annotations

from sann.soar.memory import WME, Symbol, mypyc_attr
from sann.soar.production import Production


@mypyc_attr(native_class=False)  # made and read by generated code
class Match:
    """One instantiation of a production.

    Compared and hashed by identity: the object reported as retracted is the same object
    that was reported when the match appeared.  ``wmes`` has one entry per top-level
    condition element in written order (``None`` for negations); ``bindings`` maps every
    variable bound by the positive conditions (name without brackets) to its value;
    ``newest`` is the timetag of the newest matched WME and the first written index it is
    at (``(0, -1)`` without any): the order of match creation in the kernel's Rete.

    Plain slots, filled when the match is made (the Rete's generated ``Layout.match_lines``):
    most matches are fired, and CPython 3.11 reads a property through a C call into a new
    interpreter frame, several times the cost of the slot read."""

    __slots__ = ("production", "wmes", "newest", "bindings")

    def __init__(self, production: Production, wmes: tuple[WME | None, ...],
                 bindings: dict[str, Symbol]) -> None:
        self.production = production
        self.wmes = wmes
        self.bindings = bindings
        self.newest = _newest_of(wmes)

    def __repr__(self) -> str:
        return f"Match({self.production.name}, {list(self.wmes)})"


def _newest_of(wmes: tuple[WME | None, ...]) -> tuple[int, int]:
    """``Match.newest`` from the WMEs in written order."""
    newest, index = 0, -1
    for i, wme in enumerate(wmes):
        if wme is not None and wme.timetag > newest:
            newest, index = wme.timetag, i
    return newest, index


class Changes:
    """New and retracted matches since the last ``take_changes``; an appear/retract pair
    inside one interval cancels out."""

    __slots__ = ("added", "removed", "mark", "blocked")

    def __init__(self) -> None:
        self.added: dict[Match, None] = {}
        self.removed: dict[Match, None] = {}
        # how many retractions came before the first WME removal (``mark_removals``): the
        # ones new WMEs made, by blocking a negation; ``blocked`` is it for the last take
        # (-1: no removal was marked)
        self.mark = -1
        self.blocked = -1

    def mark_removals(self) -> None:
        if self.mark < 0:
            self.mark = len(self.removed)

    def appear(self, match: Match) -> None:
        self.added[match] = None

    def retract(self, match: Match) -> None:
        if match in self.added:
            del self.added[match]
        else:
            self.removed[match] = None

    def take(self) -> tuple[list[Match], list[Match]]:
        mark, self.mark = self.mark, -1
        if not self.added and not self.removed:
            return [], []
        self.blocked = mark
        added, removed = list(self.added), list(self.removed)
        self.added.clear()
        self.removed.clear()
        return added, removed
