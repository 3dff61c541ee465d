"""The working-memory phase: changed slots become WME changes.

A non-operator slot holds every acceptable value that is not rejected; an operator slot
shows its acceptable values as ``(S ^operator O +)`` WMEs (the selection is the decision
phase's). The slots are decided until none is changed, and the removals are traced in the
kernel's order.
"""

from __future__ import annotations

from ..matching.kernel_prefix import _exists
from ..memory import WME, Symbol
from ..preferences import ACCEPTABLE, PROHIBIT, REJECT, REQUIRE, Preference, Slot
from ..trace import trace_wme
from .agent_state import AgentState, vkey
from .firing import remove_preference
from .results import remember_source
from .working_memory import add_wme, remove_arch, remove_wme, trace_gds_removal


def working_memory_phase(agent: AgentState, diffs_last: bool = False) -> None:
    """Turn changed slots into WME changes, in the kernel's timetag order."""
    if agent._in_wm_phase:
        return
    agent._in_wm_phase = True
    try:
        _working_memory_changes(agent, diffs_last)
    finally:
        agent._in_wm_phase = False
    while agent._dead_ids:
        agent._slots.pop(agent._dead_ids.pop(), None)
    if agent._ncc_checks:
        _check_conjunctive_negations(agent)


def _check_conjunctive_negations(agent: AgentState) -> None:
    """Retract the justifications whose watched conjunctive negation now matches."""
    checks, agent._ncc_checks = agent._ncc_checks, []
    for just, element, bindings in checks:
        if not just.retracted and _exists(element.conditions, bindings, agent._candidates):
            agent._schedule_retraction(just)


def _working_memory_changes(agent: AgentState, diffs_last: bool = False) -> None:
    """Decide the changed slots until none is left. The trace shows the removals in
    the kernel's order (measured in soar_sml; see ``_order_traced_removals``)."""
    agent._phase_timetag = agent._timetag
    tracing = agent.trace_level >= 4
    buffer = agent._traced_removes
    phase_start = len(buffer)
    if tracing and agent._collected_slots:
        agent._collected_slots = set()
    context_removals: list[WME] = []
    collected: list[WME] = []
    while agent._changed or agent._changed_context:
        changed, agent._changed = agent._changed, []
        adds: list[tuple[Slot, object, Symbol]] = []
        removes: list[WME] = []
        gds_index = agent._gds_index
        for slot in reversed(changed):
            slot.changed = False
            if not gds_index:
                _diff_slot(agent, slot, adds, removes)
                continue
            before = len(removes)
            _diff_slot(agent, slot, adds, removes)
            if len(removes) > before:
                # Like the kernel, while deciding the slot: a substate whose GDS holds
                # a WME about to go is removed now; WMEs already decided still come
                # and go in this phase, later slots see the substate gone.
                _gds_violations(agent, removes[before:])
        if adds:
            _add_slot_wmes(agent, adds)
        context, agent._changed_context = agent._changed_context, []
        traced = len(buffer)
        for slot in reversed(context):
            slot.changed = False
            _update_acceptable_wmes(agent, slot)
        if tracing:
            context_removals += buffer[traced:]
            del buffer[traced:]
        if removes:
            agent.matcher.mark_removals()
        for wme in removes:
            remove_wme(agent, wme)
        if agent._unlinked:
            traced = len(buffer)
            _collect_unlinked(agent)
            if tracing:
                collected += buffer[traced:]
                del buffer[traced:]
        for slot in changed:
            if not slot.prefs and not slot.wmes:
                _drop_slot(agent, slot)
        for slot in context:
            if not slot.prefs and not slot.wmes and not slot.acceptable_wmes:
                _collect_garbage(agent, slot)
    if tracing:
        _order_traced_removals(agent, phase_start, context_removals, collected, diffs_last)


def _order_traced_removals(agent: AgentState, start: int, context: list[WME],
                           collected: list[WME], diffs_last: bool) -> None:
    """Lay the phase's traced removals (from ``start``) out in the kernel's order of
    requests: the slot diffs' (its ``decide_non_context_slots``), those of the operator
    slots' acceptable-preference WMEs (measured: '(15: S1 ^operator O1 +)', '(16: S1
    ^operator O1)', then '(14: O1 ^name init)' in the trace, which reverses them), then
    those of identifiers no longer linked. After a goal removed outside a
    working-memory phase (``diffs_last``), the kernel collects the goal's structures
    as unlinked: the diffs come after the acceptable-preference WMEs (measured)."""
    buffer = agent._traced_removes
    if agent._collected_slots:  # WMEs the diffs removed from collected slots
        keys = agent._collected_slots
        region = buffer[start:]
        collected = collected + [w for w in region if (w.id, vkey(w.attr)) in keys]
        buffer[start:] = [w for w in region if (w.id, vkey(w.attr)) not in keys]
    if diffs_last:
        buffer[start:] = context + buffer[start:] + collected
    else:
        buffer += context + collected


def _add_slot_wmes(agent: AgentState, adds: list[tuple[Slot, object, Symbol]]) -> None:
    """Make the WMEs the slot diffs decided on: ``(slot, value key, value)``; the diff
    already entered the key in ``slot.wmes``, without its WME."""
    if agent._top.sub is None:  # no substate: no WME to remember the source of
        for slot, key, value in adds:
            slot.wmes[key] = add_wme(agent, slot.id, slot.attr, value)
        return
    levels = agent._level
    for slot, key, value in adds:
        ident = slot.id
        wme = slot.wmes[key] = add_wme(agent, ident, slot.attr, value)
        level = ident.level
        if (level if level is not None else levels.get(ident, 1)) > 1:
            remember_source(agent, wme, slot, (ACCEPTABLE,))


def _gds_violations(agent: AgentState, removes: list[WME]) -> bool:
    """Remove the substates whose goal dependency set holds a WME about to go, before
    any WME is added (the kernel does it while deciding the slot)."""
    removed = False
    for wme in removes:
        goals = agent._gds_index.pop(wme, None)
        for goal in goals or ():
            if goal.alive:
                if agent.trace_level >= 2:
                    trace_gds_removal(agent, goal, wme)
                agent._remove_goal(goal)
                removed = True
    return removed


def _collect_unlinked(agent: AgentState) -> None:
    """Soar 9.6 drops the o-supported preferences (and input WMEs) of identifiers that
    no WME links to any more; their i-supported WMEs wait for their instantiations to
    retract, as in the kernel. The slots are decided again in this same phase."""
    unlinked, refs = agent._unlinked, agent._refs
    while unlinked:
        ident = unlinked.pop()
        if ident in refs:
            continue
        arch = agent._arch.get(ident)
        if arch:
            for wme in list(arch):
                remove_arch(agent, wme)
        slots = agent._slots.get(ident)
        if slots:
            for slot in list(slots.values()):
                _drop_unlinked_slot(agent, slot)


def _drop_unlinked_slot(agent: AgentState, slot: Slot) -> None:
    """Remove an unlinked slot's o-supported preferences and the WMEs it gained in this
    phase (measured on the kernel); older i-supported WMEs wait for their
    instantiations to retract."""
    doomed = [pref for bucket in slot.prefs.values() for pref in bucket if pref.o_supported]
    if doomed and agent.trace_level >= 4:
        agent._collected_slots.add((slot.id, vkey(slot.attr)))
    for pref in doomed:
        remove_preference(agent, pref)
    wmes = slot.wmes
    if wmes:
        since = agent._phase_timetag
        fresh = [key for key, wme in wmes.items() if wme is not None and wme.timetag > since]
        for key in fresh:
            remove_wme(agent, wmes.pop(key))


def _diff_slot(agent: AgentState, slot: Slot, adds: list, removes: list[WME]) -> None:
    """A non-operator slot holds every acceptable value that is not rejected. Its WMEs
    that go are removed newest first, as the kernel's slot lists them (measured in
    soar_sml, n-queens: two ^tried WMEs of S1 leave the Rete oldest first, as watch 4
    prints them)."""
    prefs = slot.prefs
    wmes = slot.wmes
    if not prefs:  # the slot's last preference went: so do all its WMEs
        _move_values(wmes, removes)
        return
    if len(prefs) == 1:
        acceptable = prefs.get(ACCEPTABLE)
        if acceptable is not None:
            if len(acceptable) > 1:
                _diff_acceptable(slot, acceptable, adds, removes)
                return
            # Fast path: one acceptable preference and nothing else.
            value = acceptable[0].value
            key: object = value if type(value) is not float else (float, value)
            if key in wmes:
                if len(wmes) > 1:
                    for other in [k for k in reversed(wmes)
                                  if k != key or type(k) is not type(key)]:
                        removes.append(wmes.pop(other))
                return
            if wmes:
                _move_values(wmes, removes)
            wmes[key] = None  # type: ignore[assignment]
            adds.append((slot, key, value))
            return
    acceptable = prefs.get(ACCEPTABLE)
    wanted: dict[object, Symbol] = {}
    if acceptable:
        for pref in acceptable:
            value = pref.value
            key = value if type(value) is not float else (float, value)
            if key not in wanted:
                wanted[key] = value
        if len(wanted) > 1:  # the kernel's candidate list is built front-first
            wanted = dict(reversed(wanted.items()))
        for ptype in (REJECT, PROHIBIT):
            for pref in prefs.get(ptype, ()):
                wanted.pop(vkey(pref.value), None)
    for key in [k for k in reversed(wmes) if k not in wanted]:
        removes.append(wmes.pop(key))
    for key, value in wanted.items():
        if key not in wmes:
            wmes[key] = None  # type: ignore[assignment]
            adds.append((slot, key, value))


def _diff_acceptable(slot: Slot, acceptable: list[Preference], adds: list,
                     removes: list[WME]) -> None:
    """A slot with only acceptable preferences (the usual multi-valued slot) holds
    their distinct values. Sets find what changed without rebuilding the kernel's
    candidate order, which only the new values need (see the general case)."""
    wmes = slot.wmes
    present = {
        p.value if type(p.value) is not float else (float, p.value) for p in acceptable
    }
    gone = [key for key in reversed(wmes) if key not in present]
    key: object
    for key in gone:
        removes.append(wmes.pop(key))
    missing = len(present) - len(wmes)
    if missing == 0:
        return
    if missing == 1:  # one new value (the usual case): no order to keep, usually the head
        for pref in acceptable:
            value = pref.value
            key = value if type(value) is not float else (float, value)
            if key not in wmes:
                wmes[key] = None  # type: ignore[assignment]
                adds.append((slot, key, value))
                return
    new: dict[object, Symbol] = {}
    for pref in acceptable:  # head first: a value's first occurrence is its newest
        value = pref.value
        key = value if type(value) is not float else (float, value)
        if key not in wmes and key not in new:
            new[key] = value
    for key, value in reversed(new.items()):  # the kernel's candidate list, front-first
        wmes[key] = None  # type: ignore[assignment]
        adds.append((slot, key, value))


def _update_acceptable_wmes(agent: AgentState, slot: Slot) -> None:
    """An operator slot shows each required or acceptable value as ``(S ^operator O +)``."""
    wanted: dict[object, Symbol] = {}
    prefs = slot.prefs
    for ptype in (REQUIRE, ACCEPTABLE):
        for pref in prefs.get(ptype, ()):
            value = pref.value
            key: object = value if type(value) is not float else (float, value)
            if key not in wanted:
                wanted[key] = value
    current = slot.acceptable_wmes
    # Newest first, as the kernel's list of them (measured: the trace shows the oldest
    # removed first, the selected operator's WME just after its acceptable one).
    gone = [key for key in reversed(current) if key not in wanted]
    for key in gone:
        wme = current.pop(key)
        _operator_proposal_gone(agent, slot, wme)
        remove_wme(agent, wme)
    for key, value in wanted.items():
        if key not in current:
            current[key] = add_wme(agent, slot.id, "operator", value, True)


def _operator_proposal_gone(agent: AgentState, slot: Slot, wme: WME) -> None:
    """Soar 9.6: a selected operator whose proposal no longer matches is removed."""
    selected = slot.wmes.get(vkey(wme.value))
    if selected is None:
        return
    if agent.trace_level >= 2:
        agent._emit(
            "\n        REMOVING: Operator from context slot (proposal no longer matches): "
            + trace_wme(wme) + "\n"
        )
    goal = agent._goals[slot.id]
    traced = len(agent._traced_removes)
    sub = goal.sub
    if sub is not None:
        if agent.trace_level >= 2:
            agent._emit_line(f"Removing state {sub.id} because of an operator removal.\n")
        agent._remove_goal(sub)
    del slot.wmes[vkey(wme.value)]
    agent._context_changed_at(slot.id)
    remove_wme(agent, selected)
    if sub is not None and agent.trace_level >= 4:
        # the kernel removes the operator before the substate (measured)
        agent._traced_removes.insert(traced, agent._traced_removes.pop())


def _collect_garbage(agent: AgentState, slot: Slot) -> None:
    if slot.is_empty() and not slot.is_context:
        _drop_slot(agent, slot)


def _drop_slot(agent: AgentState, slot: Slot) -> None:
    """Forget an empty non-context slot (the caller checked that it is empty)."""
    slots = agent._slots.get(slot.id)
    if slots is not None:
        attr = slot.attr
        key = attr if type(attr) is not float else (float, attr)
        if slots.get(key) is slot:
            del slots[key]
            if not slots:
                del agent._slots[slot.id]


def _move_values(wmes: dict[object, WME], removes: list[WME]) -> None:
    """Empty a slot's WMEs into ``removes``, newest first (a loop: mypyc's ``list.extend``
    of a dict's values goes through the generic iterator protocol, which costs more than
    the loop for the usual one WME)."""
    if len(wmes) == 1:
        for wme in wmes.values():
            removes.append(wme)
    else:
        for wme in reversed(wmes.values()):
            removes.append(wme)
    wmes.clear()
