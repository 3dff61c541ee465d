"""Firing instantiations, retracting them, and asserting their preferences.

``fire`` runs a match's actions (interpreted, or compiled once the rule has fired
``COMPILE_AFTER`` times), making an instantiation; a wave's preferences are then added to
their slots in the kernel's order (``assert_preferences``), o-supported rejects first.
"""

from __future__ import annotations

from typing import cast

from ..goals import Goal
from ..instantiation import (
    COMPILE_AFTER,
    Instantiation,
    ProductionInfo,
    compile_actions,
    interpret_actions,
    tested_operators,
)
from ..memory import Identifier
from ..preferences import REJECT, Preference, Slot
from ..trace import symbol_text, trace_preference
from .agent_state import AgentState
from .results import handle_substate_preferences


def fire(agent: AgentState, match: object, info: ProductionInfo, goal: Goal,
         o_support: bool) -> Instantiation:
    """Fire a match (``o_support``: it was queued as an o-assertion)."""
    name = info.production.name
    inst = Instantiation(name, match, goal, match.wmes, o_support)  # type: ignore[attr-defined]
    agent._firings += 1
    info.firings += 1
    if agent.trace_level >= 3:
        agent._emit(f"\nFiring {symbol_text(name)}\n")  # |s*p| (measured)
    agent._inst_of[match] = inst
    operators = (
        tested_operators(info, inst.wmes, goal.id)
        if o_support and info.declared != "o-support"
        else ()
    )
    bindings = match.bindings  # type: ignore[attr-defined]
    program = info.program
    # for deep-copy, which may replace it by its waiting copies (cast: not narrowed to
    # Instantiation, which mypyc would check when reading it back)
    agent.firing = cast(object, inst)
    if program is not None:
        program(agent, bindings, inst, o_support, operators)
    else:
        info.runs += 1
        if info.runs >= COMPILE_AFTER:
            info.program = compile_actions(name, info.actions, frozenset(bindings))
        interpret_actions(info.actions, agent, bindings, inst, o_support, operators)
    if agent.firing is not inst:
        agent.firing.settle()  # type: ignore[attr-defined]
    if goal.level > 1:
        goal.insts[inst] = None
        handle_substate_preferences(agent, inst)
    return inst


def retract(agent: AgentState, inst: Instantiation) -> None:
    """Remove an instantiation's i-supported preferences (o-supported ones stay)."""
    trace = agent.trace_level
    if trace >= 3:
        _trace_retraction(agent, inst)
    # In the order the kernel made them (inst.prefs is newest first): the slots they
    # leave are decided in that order's reverse, which the trace shows (measured:
    # <=WM: (37: O4 ^name buy), then (38: O4 ^item I5) for a rule that made both).
    for pref in reversed(inst.prefs):
        if pref.live and not pref.o_supported:
            remove_preference(agent, pref)
    if inst.goal.level > 1 and not any(p.live for p in inst.prefs):
        inst.goal.insts.pop(inst, None)
    if inst.is_justification:
        if inst.source is not None and not any(p.live for p in inst.prefs):
            inst.source.justified.pop(inst, None)
        if agent._justification_index.get(inst.match) is inst:  # type: ignore[arg-type]
            del agent._justification_index[inst.match]  # type: ignore[arg-type]
        for key in agent._neg_keys.pop(inst, ()):
            bucket = agent._neg_watch.get(key)
            if bucket is not None:
                bucket[:] = [entry for entry in bucket if entry[0] is not inst]
                if not bucket:
                    del agent._neg_watch[key]
        for wme in inst.grounds:
            bucket = agent._dependents.get(wme)
            if bucket is not None and inst in bucket:
                bucket.remove(inst)


def _trace_retraction(agent: AgentState, inst: Instantiation) -> None:
    """``Retracting name`` when the instantiation loses a preference; at watch 5 the
    preferences it loses, in the order they were asserted (measured)."""
    gone = [pref for pref in reversed(inst.prefs) if pref.live and not pref.o_supported]
    if gone:
        agent._emit(f"\nRetracting {symbol_text(inst.name)}\n")
        if agent.trace_level >= 5:
            agent._emit_line("".join(trace_preference("-", pref) for pref in gone))


def assert_preferences(agent: AgentState, fired: list[Instantiation], o_support: bool) -> None:
    """Let o-supported rejects remove the older preferences for their values, then add
    the new preferences to their slots, both in the kernel's order (a rule may remove
    and re-add the same value in one firing: the new preference survives).  The rejects
    go first, as in the kernel: their slots are then decided last in the working-memory
    phase, after the slots that gained preferences (it matters when the removal takes
    a substate away: what was decided before stays for the phase, measured).
    ``o_support``: the wave fired o-assertions (an i-assertion wave makes no o-supported
    preference; a justification may)."""
    justifications, agent._new_justifications = agent._new_justifications, []
    insts = _with_justifications(fired, justifications) if justifications else fired[::-1]
    tracing = agent.trace_level >= 5
    # The kernel takes the o-rejects in the reverse of the order it asserts the rest
    # (measured: '- (S1 ^last-moved other ...)' of the last rule to assert, before the
    # first rule's '- (D1 ^on a ...)' and '- (S1 ^moves 0 ...)').
    o_rejects = [pref for inst in reversed(insts) for pref in inst.prefs
                 if pref.o_supported and pref.type == REJECT
                 ] if o_support or justifications else ()
    for pref in o_rejects:  # not traced itself (measured): what it removes is
        _o_reject(agent, pref)
        pref.inst = None  # type: ignore[assignment]  # never in a slot: done with
    for inst in insts:
        for pref in reversed(inst.prefs):
            if pref.inst is None:  # an o-reject, done with above
                continue
            if pref.o_supported and inst.goal.level == 1 and _already_supported(agent, pref):
                if tracing:
                    agent._emit_line(trace_preference("+", pref)[:-1]
                                    + " ALREADY SUPPORTED ON TOP LEVEL.  IGNORING.\n")
                _drop_copied(agent, pref)
                continue
            if tracing:
                agent._emit_line(trace_preference("+", pref))
            _add_preference(agent, pref)
    agent._copied_from.clear()


def _drop_copied(agent: AgentState, pref: Preference) -> None:
    """An ignored justification preference takes the results it copies with it: the
    kernel's clones go together (measured in soar_sml: when '+ (S1 ^y 1 +  :O )
    (justify1) ALREADY SUPPORTED ON TOP LEVEL.  IGNORING.', the substate rule's own
    (S1 ^y 1) is neither asserted nor removed with the substate)."""
    original = agent._copied_from.get(pref)
    while original is not None:
        original.inst = None  # type: ignore[assignment]  # never asserted
        original = agent._copied_from.get(original)


def _already_supported(agent: AgentState, pref: Preference) -> bool:
    """Whether the slot already holds the same o-supported preference: the kernel then
    ignores a new one made on the top level (measured in soar_sml: '+ (S1 ^note x +
    :O ) (a) ALREADY SUPPORTED ON TOP LEVEL.  IGNORING.', and a later o-reject of x
    removes only the older preference). Only a top-level instantiation's preference
    counts: a substate's own stays beside its justification's copy, which outlives it
    (measured: ``(S1 ^x 1 :O) [level 2]`` does not make ``justify1``'s ignored, a
    top-level rule's or an older justification's does)."""
    slots = agent._slots.get(pref.id)
    attr = pref.attr
    slot = slots.get(attr if type(attr) is not float else (float, attr)) if slots else None
    bucket = slot.prefs.get(pref.type) if slot is not None else None
    if not bucket:
        return False
    value, referent = pref.value, pref.referent
    for old in bucket:  # 1 and 1.0 are different symbols: the types must agree too
        if (old.o_supported and old.value == value and type(old.value) is type(value)
                and old.referent == referent and type(old.referent) is type(referent)
                and old.inst is not None and old.inst.goal.level == 1):
            return True
    return False


def _add_preference(agent: AgentState, pref: Preference) -> None:
    ident = pref.id
    slots = agent._slots.get(ident)
    if slots is None:
        slots = agent._slots[ident] = {}
    attr = pref.attr
    key = attr if type(attr) is not float else (float, attr)
    slot = slots.get(key)
    if slot is None:
        slot = slots[key] = Slot(ident, attr, False)
    # Slot.add, inlined: the kernel puts a new preference at the head of its list.
    bucket = slot.prefs.get(pref.type)
    if bucket is None:
        slot.prefs[pref.type] = [pref]
    else:
        bucket.insert(0, pref)
    pref.slot = slot
    pref.live = True
    if slot.is_context:
        agent._context_changed_at(ident)
        slot.touched = True
        if not slot.changed:
            slot.changed = True
            agent._changed_context.append(slot)
    elif not slot.changed:
        slot.changed = True
        agent._changed.append(slot)


def remove_preference(agent: AgentState, pref: Preference) -> None:
    slot = pref.slot
    if slot is None or not pref.live:
        return
    # Slot.remove, inlined (Preference compares by identity: list.remove is a C search).
    prefs = slot.prefs
    bucket = prefs.get(pref.type)
    if bucket is not None:
        try:
            bucket.remove(pref)
        except ValueError:
            pass
        if not bucket:
            del prefs[pref.type]
    pref.live = False
    # A removed preference no longer needs its instantiation; dropping the link breaks
    # the inst.prefs <-> pref.inst cycle, so reference counting frees both at once and
    # the cyclic garbage collector has no garbage of firings to find.
    pref.inst = None  # type: ignore[assignment]
    if slot.is_context:
        agent._context_changed_at(slot.id)
        slot.touched = True
    if not slot.changed:
        slot.changed = True
        (agent._changed_context if slot.is_context else agent._changed).append(slot)


def _o_reject(agent: AgentState, reject: Preference) -> None:
    """An o-supported reject removes every preference for that value from the slot."""
    slots = agent._slots.get(reject.id)
    if slots is None:
        return
    attr = reject.attr
    slot = slots.get(attr if type(attr) is not float else (float, attr))
    if slot is None:
        return
    target = reject.value
    buckets = slot.prefs.values()
    if type(target) is Identifier:  # identifiers are equal only to themselves
        doomed = [
            pref
            for bucket in buckets
            for pref in bucket
            if pref.value is target
        ]
    elif type(target) is float:  # 1.0 is not the symbol 1
        doomed = [
            pref
            for bucket in buckets
            for pref in bucket
            if type(pref.value) is float
            and (pref.value is target or pref.value == target)
        ]
    else:
        doomed = [
            pref
            for bucket in buckets
            for pref in bucket
            if pref.value == target
            and type(pref.value) is not float
        ]
    for pref in doomed:
        if agent.trace_level >= 5:
            agent._emit_line(trace_preference("-", pref))
        remove_preference(agent, pref)


def _with_justifications(fired: list[Instantiation],
                         justifications: list[tuple[Instantiation, Instantiation]]
                         ) -> list[Instantiation]:
    """The order the kernel asserts a wave's preferences in: the instantiations the wave
    fired, the last first, each right after the justification of its results (measured
    in soar_sml: sx then sy fire in a substate, the kernel traces '+ ... (justify3)',
    '+ ... [level 2] (sy)', '+ ... (justify1)', '+ ... [level 2] (sx)'; with snc fired
    for counts 0 then 2, justify7 and snc of count 2 come first, so (S1 ^count 3) gets the
    older timetag)."""
    made: dict[int, list[Instantiation]] = {}
    for source, just in justifications:
        made.setdefault(id(source), []).append(just)
    insts: list[Instantiation] = []
    for inst in reversed(fired):
        justs = made.pop(id(inst), None)
        if justs:
            insts += reversed(justs)
        insts.append(inst)
    if made:  # not of this wave's firings (none known): first, as before
        others = [just for justs in made.values() for just in justs]
        insts[:0] = reversed(others)
    return insts
