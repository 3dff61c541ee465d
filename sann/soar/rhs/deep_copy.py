"""``deep-copy``: a new identifier holding a copy of everything reachable from one, walked in
the kernel's order, its WMEs made as preferences of the firing rule.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from sann.soar.memory import WME, Identifier, Symbol
from sann.soar.preferences import Preference
from sann.soar.rhs.context import RhsContext, RhsFunction, one
from sann.soar.rhs.wm import GOAL_ATTRIBUTES

#: What ``deep-copy`` returns for an argument that is not an identifier (measured).
DEEP_COPY_NOT_ID = "*symbol not id*"


#: A state's architecture WMEs that the memory modules keep in slots; the others
#: (``^type``, ``^superstate``, impasse augmentations) are not copied.
_MODULE_LINKS = ("reward-link", "epmem", "smem")


class DeepCopies:
    """The firing instantiation, while ``deep-copy`` has preferences waiting for it.

    The kernel adds a copy's preferences to the instantiation right after the preference of
    the action that called ``deep-copy`` (measured: ``(S1 ^copy D1)`` takes the timetag
    before the copy's WMEs, the action's next preference the one after them). A function
    runs before its action's preference exists, so the copies wait here, with the number
    of preferences the instantiation had then, and `settle` puts them in place once the
    rule's actions are done (the agent calls it when ``firing`` is no longer the
    instantiation it set)."""

    __slots__ = ("inst", "groups")

    def __init__(self, inst: object) -> None:
        self.inst = inst
        self.groups: list[tuple[int, list[Preference]]] = []

    def settle(self) -> None:
        prefs: list[Preference] = self.inst.prefs  # type: ignore[attr-defined]
        for index, copies in reversed(self.groups):  # later groups first: indices stay valid
            if index < len(prefs):
                ptype = prefs[index].type
                for pref in copies:  # the copies take the action's preference type
                    pref.type = ptype
            prefs[index + 1 : index + 1] = copies
        self.groups = []


def _deep_copy(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(deep-copy <id>)``: a new identifier (letter D) holding a copy of everything
    reachable from ``<id>``, each identifier copied once (shared structure and cycles stay
    so) under a new one of its own letter, at ``<id>``'s level. The copies are preferences
    of the firing rule, with its support. Walked as the kernel walks them (all measured):
    depth first, a WME after the identifiers below it, an identifier's slots newest first
    and their WMEs newest first, then its input WMEs newest first; a state's ``^type``,
    ``^superstate`` and impasse augmentations and its acceptable operator preferences are
    left out, its ``^io``, ``^reward-link``, ``^epmem``, ``^smem`` and selected operator
    copied."""
    base = one("deep-copy", args)
    if type(base) is not Identifier:
        return DEEP_COPY_NOT_ID
    agent: Any = ctx
    firing = agent.firing
    if type(firing) is not DeepCopies:
        firing = agent.firing = DeepCopies(firing)
    inst: Any = firing.inst
    level = agent._level_of(base)
    new_id = agent._new_id
    root = new_id("D", level)
    made: list[tuple[Identifier, Symbol, Symbol]] = []
    copied: dict[Identifier, Identifier] = {}
    views = _KernelSlots(agent)

    def copy_of(ident: Identifier) -> Identifier:
        twin = copied.get(ident)
        if twin is None:
            twin = new_id(ident.letter, level)
        walk(ident, twin)
        return twin

    def walk(ident: Identifier, twin: Identifier) -> None:
        if ident in copied:
            return
        copied[ident] = twin
        for wme in views.of(ident):
            attr, value = wme.attr, wme.value
            if type(attr) is Identifier:
                attr = copy_of(attr)
            if type(value) is Identifier:
                value = copy_of(value)
            made.append((twin, attr, value))

    walk(base, root)
    o_supported = bool(inst.o_support)
    prefs = []
    for ident, attr, value in made:
        pref = Preference("+", ident, attr, value, None, inst)
        pref.o_supported = o_supported
        prefs.append(pref)
    firing.groups.append((len(inst.prefs), prefs))
    return root


class _KernelSlots:
    """An identifier's WMEs in the order the kernel's ``deep-copy`` visits them: its slots
    newest first (a state's module links are in slots made before its operator slot), the
    WMEs of a slot newest first, then its input WMEs (``^io``, the io link's, the
    environment's) newest first."""

    def __init__(self, agent: Any) -> None:
        self.agent = agent
        self.modules: set[Symbol] = set()
        for ident in agent._goals:
            for wme in agent._arch.get(ident, ()):
                if wme.attr in _MODULE_LINKS:
                    self.modules.add(wme.value)

    def of(self, ident: Identifier) -> list[WME]:
        agent = self.agent
        slots: dict[object, list[WME]] = {}  # by `_slot_key`
        inputs: list[WME] = []
        is_goal = ident in agent._goals
        for wme in agent._arch.get(ident, ()):
            if is_goal and wme.attr in GOAL_ATTRIBUTES:
                continue
            if (is_goal and wme.attr != "io") or ident in self.modules:
                slots.setdefault(_slot_key(wme.attr), []).append(wme)
            else:
                inputs.append(wme)
        for key, slot in agent._slots.get(ident, {}).items():
            if slot.wmes:
                slots.setdefault(key, []).extend(slot.wmes.values())
        out: list[WME] = []
        for wmes in reversed(slots.values()):
            out.extend(sorted(wmes, key=_timetag, reverse=True))
        out.extend(sorted(inputs, key=_timetag, reverse=True))
        return out


def _slot_key(attr: Symbol) -> object:
    return attr if type(attr) is not float else (float, attr)


def _timetag(wme: WME) -> int:
    return wme.timetag


#: This family's functions, by the name a rule calls them with.
FUNCTIONS: dict[str, RhsFunction] = {
    "deep-copy": _deep_copy,
}
