"""Which preferences of a substate are results, found the way the Soar 9.6 kernel finds them.

A rule that fires in a substate and makes a preference on a superstate identifier makes a
*result*. The kernel (``get_results_for_instantiation``) then follows the identifiers that
result links to, as long as they are still at the substate's level, and takes as results
every preference of that substate found in their slots, whichever of its instantiations made
it and whenever: a problem built locally over several decisions becomes a result, all of
it, the moment one rule links it to the superstate (measured in soar_sml: ``(S1 ^problem
P1)`` made by one rule is justified together with ``(P1 ^first 3)`` and ``(P1 ^second
4)`` made by two earlier ones, all in ``justify1``). Without them, the structure would leave
with the substate, whose instantiations support it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING

from .memory import Identifier, Symbol
from .preferences import BETTER, BINARY_INDIFFERENT, NUMERIC_INDIFFERENT, WORSE, Preference

if TYPE_CHECKING:
    from .instantiation import Instantiation
    from .preferences import Slot

_BINARY = (BETTER, WORSE, BINARY_INDIFFERENT, NUMERIC_INDIFFERENT)


def _key(sym: Symbol | None) -> object:
    """1 and 1.0 are different symbols: the type is part of the key."""
    return (type(sym), sym) if not isinstance(sym, Identifier) else sym


class ResultSearch:
    """One search for the results of an instantiation fired at ``level``.

    ``level_of`` gives an identifier's goal level (results are searched before any of them
    is promoted); ``slots`` maps an identifier to its slots by attribute, oldest first.
    """

    def __init__(
        self,
        inst: Instantiation,
        level: int,
        level_of: Callable[[Identifier], int],
        slots: Mapping[Identifier, Mapping[object, Slot]],
    ) -> None:
        self.inst = inst
        self.level = level
        self.level_of = level_of
        self.slots = slots
        self.found: list[Preference] = []
        self.keys: set[tuple[object, ...]] = set()
        self.followed: set[Identifier] = set()

    def run(self) -> list[Preference]:
        """The results, in the order the kernel finds them: the instantiation's preferences
        on superstate identifiers (in the order it made them), each followed at once by the
        local structure its value links to."""
        for pref in reversed(self.inst.prefs):  # inst.prefs is newest first
            if self.level_of(pref.id) < self.level:
                self.add(pref)
        return self.found

    def add(self, pref: Preference) -> None:
        """Take ``pref`` unless an equal preference is already a result or another goal's
        instantiation made it; then follow what it links to."""
        binary = pref.type in _BINARY
        key = (pref.type, pref.id, _key(pref.attr), _key(pref.value),
               _key(pref.referent) if binary else None)
        if key in self.keys:
            return
        inst = pref.inst
        if inst is None or inst.goal.level != self.level:
            return
        self.keys.add(key)
        self.found.append(pref)
        self.follow(pref.value)
        if binary:
            self.follow(pref.referent)

    def follow(self, sym: Symbol | None) -> None:
        """An identifier still local to the substate (or deeper): every preference in its
        slots, newest slot first and newest preference first as the kernel keeps them, the
        identifiers its WMEs link to, and the firing instantiation's own preferences on it
        (not in any slot yet)."""
        if not isinstance(sym, Identifier) or sym in self.followed:
            return
        if self.level_of(sym) < self.level:
            return
        self.followed.add(sym)
        slots = self.slots.get(sym)
        if slots:
            for slot in reversed(list(slots.values())):
                for pref in slot.all_preferences():
                    self.add(pref)
                for wme in list(slot.wmes.values()):
                    self.follow(wme.value)
        for pref in reversed(self.inst.prefs):
            if pref.id is sym:
                self.add(pref)


def find_results(
    inst: Instantiation,
    level: int,
    level_of: Callable[[Identifier], int],
    slots: Mapping[Identifier, Mapping[object, Slot]],
) -> list[Preference]:
    """The results of ``inst`` (fired at goal ``level``), the last found first: the order
    of a justification's preference list (its preferences are asserted last first)."""
    return ResultSearch(inst, level, level_of, slots).run()[::-1]
