"""Substates: made for an impasse, removed with everything below them.

A substate gets the standard augmentations of a state and its impasse's (``^attribute``,
``^impasse``, ``^choices``, ``^item``...); removing it removes the substates below it, its
instantiations' preferences, its architecture WMEs and its goal dependency set.
"""

from __future__ import annotations

from collections.abc import Iterable

from ..goals import Goal
from ..memory import WME, Identifier, Symbol
from ..preferences import Slot
from ..trace import trace_preference
from . import preference_semantics as semantics
from .agent_state import AgentState, vkey
from .firing import remove_preference
from .matches import collect_changes
from .wm_phase import working_memory_phase
from .working_memory import add_arch, remove_arch, remove_wme, trace_wm_changes

#: A state's links to its memories: the kernel removes them (and their children) last
_LINK_ATTRS = ("reward-link", "epmem", "smem")


def ids_new_after_top(agent: AgentState, top: Identifier) -> Identifier:
    io = agent._ids.new("I", level=None)
    agent._level[io] = 1
    add_arch(agent, top, "io", io)
    agent._input_link_id = agent._new_id("I", 1)
    agent._output_link_id = agent._new_id("I", 1)
    add_arch(agent, io, "input-link", agent._input_link_id)
    add_arch(agent, io, "output-link", agent._output_link_id)
    return io


def new_goal(agent: AgentState, ident: Identifier, superstate: Goal | None) -> Goal:
    """Create a state's standard augmentations (type, superstate, reward-link, epmem, smem)."""
    goal = Goal(ident, superstate, Slot(ident, "operator", True))
    agent._goals[ident] = goal
    agent._slots.setdefault(ident, {})[vkey("operator")] = goal.op_slot
    level = goal.level
    goal.arch_wmes.append(add_arch(agent, ident, "type", "state"))
    goal.arch_wmes.append(
        add_arch(agent, ident, "superstate", superstate.id if superstate else "nil")
    )
    reward = agent._new_id("R", level)
    goal.arch_wmes.append(add_arch(agent, ident, "reward-link", reward))
    epmem = agent._new_id("E", level)
    command, result = agent._new_id("C", level), agent._new_id("R", level)
    goal.arch_wmes.append(add_arch(agent, ident, "epmem", epmem))
    goal.arch_wmes.append(add_arch(agent, epmem, "command", command))
    goal.arch_wmes.append(add_arch(agent, epmem, "result", result))
    goal.arch_wmes.append(add_arch(agent, epmem, "present-id", 1))
    smem = agent._new_id("L", level)
    command, result = agent._new_id("C", level), agent._new_id("R", level)
    goal.arch_wmes.append(add_arch(agent, ident, "smem", smem))
    goal.arch_wmes.append(add_arch(agent, smem, "command", command))
    goal.arch_wmes.append(add_arch(agent, smem, "result", result))
    return goal


def create_substate(agent: AgentState, goal: Goal, impasse: str, attribute: str,
                    candidates: list[Symbol], slot: Slot) -> None:
    if goal.level >= agent.max_goal_depth:
        # The kernel's guard against runaway subgoaling: say so, make the state, stop.
        # It prints "System halted." (when the run stops) but only interrupts: a later
        # run goes on (measured).
        agent._emit(
            f"\nGoal stack depth exceeded {agent.max_goal_depth} on a {impasse} impasse."
            "\nSoar appears to be in an infinite loop.  \nContinuing to subgoal may cause"
            " Soar to \nexceed the program stack of your system.\n"
        )
        agent._halt_note = agent._halt_note or "Interrupt received."
        agent.request_interrupt()
    ident = agent._ids.new("S", level=goal.level + 1)
    sub = new_goal(agent, ident, goal)
    sub.impasse, sub.attribute = impasse, attribute
    goal.sub = sub
    # a constraint failure has ^choices none too (measured)
    no_choice = impasse in (semantics.NO_CHANGE, semantics.CONSTRAINT_FAILURE)
    choices = "none" if no_choice else "multiple"
    sub.arch_wmes.append(add_arch(agent, ident, "attribute", attribute))
    sub.arch_wmes.append(add_arch(agent, ident, "impasse", impasse))
    sub.arch_wmes.append(add_arch(agent, ident, "choices", choices))
    sub.arch_wmes.append(add_arch(agent, ident, "quiescence", "t"))
    update_items(agent, sub, candidates, slot)
    collect_changes(agent)  # before the WME trace: it may warn (measured)
    if agent.trace_level >= 4:
        trace_wm_changes(agent)  # the kernel traces the decision after its WM changes
    if agent.trace_level >= 1:
        indent = " " + "   " * goal.level
        kind = (
            f"{attribute} {impasse}" if impasse != semantics.NO_CHANGE else f"{attribute} no-change"
        )
        agent._emit(f"\n{agent._decisions + 1:>6}:{indent}==>S: {ident} ({kind})")


def update_items(agent: AgentState, sub: Goal, candidates: list[Symbol], slot: Slot) -> None:
    """Make the substate's ``^item``/``^non-numeric`` WMEs and counts match the candidates."""
    if sub.impasse == semantics.NO_CHANGE:
        return
    numeric = {semantics._key(p.value) for p in slot.of_type("n=")}
    _sync_items(agent, sub, "item", candidates)
    _sync_items(agent, sub, "non-numeric",
                [c for c in candidates if semantics._key(c) not in numeric])


def _sync_items(agent: AgentState, sub: Goal, attr: str, values: list[Symbol]) -> None:
    wanted = {(attr, semantics._key(v)): v for v in values}
    for key, wme in list(sub.items.items()):
        if key[0] == attr and key not in wanted:
            del sub.items[key]
            remove_arch(agent, wme)
    for key, value in wanted.items():
        if key not in sub.items:
            sub.items[key] = add_arch(agent, sub.id, attr, value)
    count_attr = f"{attr}-count"
    old = sub.counts.pop(count_attr, None)
    if old is not None:
        remove_arch(agent, old)  # the kernel renews the count at every update
    if values:  # no ^non-numeric-count when every candidate has a numeric value
        sub.counts[count_attr] = add_arch(agent, sub.id, count_attr, len(values))


def remove_goal(agent: AgentState, goal: Goal) -> None:
    """Remove a substate and everything below it (``remove_existing_context...``)."""
    if not goal.alive:
        return
    if goal.sub is not None:
        remove_goal(agent, goal.sub)
    goal.alive = False
    selected = goal.selected()
    if selected is not None:
        goal.op_slot.wmes.clear()
        remove_wme(agent, selected)
    for inst in list(goal.insts):
        for pref in reversed(inst.prefs):  # as made (measured: the watch-5 trace)
            if pref.live:
                if agent.trace_level >= 5:
                    agent._emit_line(trace_preference("-", pref))
                remove_preference(agent, pref)
    goal.insts.clear()
    _drop_local_results(agent, goal)
    traced = len(agent._traced_removes)
    for wme in list(goal.items.values()) + list(goal.counts.values()) + goal.arch_wmes:
        remove_arch(agent, wme)
    if agent.trace_level >= 4:
        _trace_goal_removal(agent, goal, traced)
    goal.items.clear()
    goal.counts.clear()
    for match in list(goal.pending_i) + list(goal.pending_o):
        agent._pending_goal.pop(match, None)
    goal.pending_i.clear()
    goal.pending_o.clear()
    agent._nil_retractions.extend(goal.retractions)
    goal.retractions = []
    for wme in goal.gds:
        bucket = agent._gds_index.get(wme)
        if bucket is not None:
            bucket.pop(goal, None)
            if not bucket:
                del agent._gds_index[wme]
    goal.gds.clear()
    if goal.superstate is not None and goal.superstate.sub is goal:
        goal.superstate.sub = None
    del agent._goals[goal.id]
    agent._dead_ids.append(goal.id)
    if not agent._in_wm_phase:
        working_memory_phase(agent, diffs_last=True)


def _drop_local_results(agent: AgentState, goal: Goal) -> None:
    """A result may link the substate's own identifiers (the state, its operators):
    the justification's preferences on them go with the substate, the rest stay
    (measured in soar_sml: ``(A1 ^local-copy S2)`` made a result of ``(S2 ^operator
    O2 +)`` and ``(O2 ^name answer)``; removing S2 traces '- (S2 ^operator O2 +  :O )
    (justify1)' and '- (O2 ^name answer +  :O ) (justify1)' after its own
    instantiations' preferences)."""
    level = goal.level
    for just in goal.justified:
        for pref in reversed(just.prefs):
            if pref.live and agent._level_of(pref.id) >= level:
                if agent.trace_level >= 5:
                    agent._emit_line(trace_preference("-", pref))
                remove_preference(agent, pref)
    goal.justified.clear()


def _trace_goal_removal(agent: AgentState, goal: Goal, start: int) -> None:
    """Put the removed goal's architecture WMEs (traced from ``start`` on) in the
    kernel's order of removal (measured in soar_sml; the trace shows it reversed): its
    ^item WMEs with their count, its ^non-numeric ones with theirs, its impasse WMEs
    (type, superstate, attribute, impasse, choices, quiescence), each group newest
    first; then, after the
    batch's other removals, its ^reward-link, ^epmem and ^smem WMEs newest first, and
    the epmem and smem links' children, each link's newest first."""
    group = _newest_first
    items = group([*goal.items.values(), *goal.counts.values()])
    items = ([w for w in items if w.attr in ("item", "item-count")]
             + [w for w in items if w.attr not in ("item", "item-count")])
    own = [w for w in goal.arch_wmes if w.id is goal.id]
    links = group(w for w in own if w.attr in _LINK_ATTRS)
    early = items + group(w for w in own if w.attr not in _LINK_ATTRS)
    late = links + [child for link in reversed(links) for child in
                    group(w for w in goal.arch_wmes if w.id is link.value)]
    placed = {id(wme) for wme in early + late}
    kept = [wme for wme in agent._traced_removes[start:] if id(wme) not in placed]
    agent._traced_removes[start:] = early + kept
    agent._traced_late += late


def _newest_first(wmes: Iterable[WME]) -> list[WME]:
    return sorted(wmes, key=lambda wme: -wme.timetag)


def remove_current_decision(agent: AgentState, goal: Goal) -> None:
    if goal.sub is None and goal.selected() is None:
        return
    traced = len(agent._traced_removes)
    if goal.sub is not None:
        remove_goal(agent, goal.sub)
    selected = goal.selected()
    if selected is not None:
        goal.op_slot.wmes.clear()
        remove_wme(agent, selected)
        if agent.trace_level >= 4:  # the kernel removes it before the substates
            agent._traced_removes.remove(selected)
            agent._traced_removes.insert(traced, selected)
    agent._context_changed_at(goal.id)
    collect_changes(agent)
    if agent.trace_level >= 4:
        trace_wm_changes(agent)
