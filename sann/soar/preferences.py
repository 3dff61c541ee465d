"""Preferences and slots: the temporary memory that working memory is derived from.

Every action of a fired rule is a *preference* for a value of an ``(identifier ^attribute)``
slot. Working memory is computed from the preferences of each slot, as in the Soar 9.6
kernel: a non-operator slot holds every acceptable value that is not rejected; an operator
slot of a state holds at most one *selected* value chosen by the decision procedure
(`decision/preference_semantics.py`), plus ``(S1 ^operator O1 +)`` acceptable-preference
WMEs for its proposals.

Preference lists keep the kernel's order (new preferences go to the head of their list)
because candidate order decides tie ``^item`` order and the ``first``/``last`` selection
policies.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .memory import WME, Identifier, Symbol

if TYPE_CHECKING:
    from .instantiation import Instantiation

#: Whether this module runs compiled by mypyc: its classes are then native, their objects made
#: by calling the class (``object.__new__`` refuses them).
NATIVE = not __file__.endswith(".py")

ACCEPTABLE = "+"
REJECT = "-"
REQUIRE = "!"
PROHIBIT = "~"
RECONSIDER = "@"
BEST = ">"
WORST = "<"
UNARY_INDIFFERENT = "="
BETTER = "b>"
WORSE = "b<"
BINARY_INDIFFERENT = "b="
NUMERIC_INDIFFERENT = "n="

#: Every preference type, in the order the kernel prints a slot's preferences.
PREFERENCE_TYPES = (
    ACCEPTABLE,
    REQUIRE,
    REJECT,
    PROHIBIT,
    RECONSIDER,
    UNARY_INDIFFERENT,
    BINARY_INDIFFERENT,
    NUMERIC_INDIFFERENT,
    BEST,
    BETTER,
    WORST,
    WORSE,
)


def preference_type(symbol: str, referent: object | None) -> str:
    """Map a written preference (``>`` with or without a referent, ``= 0.5`` ...) to its type."""
    if referent is None:
        return symbol
    if symbol == "=":
        is_number = isinstance(referent, int | float) and not isinstance(referent, bool)
        return NUMERIC_INDIFFERENT if is_number else BINARY_INDIFFERENT
    return "b" + symbol


class Preference:
    """One preference: ``(id ^attr value type [referent])`` made by one instantiation."""

    __slots__ = ("type", "id", "attr", "value", "referent", "inst", "o_supported", "slot", "live")

    def __init__(
        self,
        ptype: str,
        id: Identifier,
        attr: Symbol,
        value: Symbol,
        referent: Symbol | None,
        inst: Instantiation,
    ) -> None:
        self.type = ptype
        self.id = id
        self.attr = attr
        self.value = value
        self.referent = referent
        self.inst: Instantiation | None = inst
        self.o_supported = False
        self.slot: Slot | None = None
        self.live = False

    def written_type(self) -> str:
        """The preference symbol as written in a rule (``>`` for both best and better)."""
        return self.type[-1]

    def __repr__(self) -> str:
        ref = f" {self.referent}" if self.referent is not None else ""
        return f"({self.id} ^{self.attr} {self.value} {self.written_type()}{ref})"


class Slot:
    """All preferences for one ``(id ^attr)`` and the WMEs derived from them."""

    __slots__ = (
        "id",
        "attr",
        "is_context",
        "prefs",
        "wmes",
        "acceptable_wmes",
        "changed",
        "touched",
    )

    def __init__(self, id: Identifier, attr: Symbol, is_context: bool) -> None:
        self.id = id
        self.attr = attr
        self.is_context = is_context
        self.prefs: dict[str, list[Preference]] = {}
        #: value -> WME (non-operator slots; for the operator slot: the selected operator).
        self.wmes: dict[object, WME] = {}  # keyed by `agent._vkey` (floats in a tuple)
        #: value -> ``(id ^operator value +)`` WME (operator slots only).
        self.acceptable_wmes: dict[object, WME] = {}
        self.changed = False
        #: A context slot: a preference came or went since the slot was last decided
        #: (the kernel's per-slot changed flag; a state no-change stands while it is unset).
        self.touched = False

    def of_type(self, ptype: str) -> list[Preference]:
        return self.prefs.get(ptype, _EMPTY)

    def add(self, pref: Preference) -> None:
        """Insert at the head of the type's list, like the kernel."""
        self.prefs.setdefault(pref.type, []).insert(0, pref)
        pref.slot = self
        pref.live = True

    def remove(self, pref: Preference) -> None:
        bucket = self.prefs.get(pref.type)
        if bucket is not None:
            try:
                bucket.remove(pref)  # a C-level search: Preference compares by identity
            except ValueError:
                pass
            if not bucket:
                del self.prefs[pref.type]
        pref.live = False

    def all_preferences(self) -> list[Preference]:
        prefs = self.prefs
        if len(prefs) == 1:  # the usual slot: one type, no need to walk all twelve
            for bucket in prefs.values():
                return list(bucket)
        return [p for t in PREFERENCE_TYPES for p in prefs.get(t, ())]

    def is_empty(self) -> bool:
        return not self.prefs and not self.wmes and not self.acceptable_wmes


_EMPTY: list[Preference] = []
