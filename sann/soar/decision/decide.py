"""The decision phase: operator slots decided, impasses, and the stack's consistency.

From the highest goal whose operator slot changed, the preference semantics choose an
operator or name an impasse, which makes (or keeps) a substate. Between decisions, a
decision that the current preferences no longer support is removed with everything below
it (``consistent_through``).
"""

from __future__ import annotations

from ..goals import Goal
from ..memory import Identifier, Symbol
from ..preferences import ACCEPTABLE, REQUIRE
from ..text import format_value
from ..trace import symbol_text
from . import preference_semantics as semantics
from .agent_state import AgentState, vkey
from .matches import collect_changes
from .results import remember_source
from .substates import create_substate, remove_current_decision, remove_goal, update_items
from .working_memory import add_wme, trace_wm_changes


def decide_context_slots(agent: AgentState) -> None:
    """Decide from the highest goal whose context changed, else only the bottom goal."""
    goal: Goal | None = agent._context_changed
    agent._context_changed = None
    if goal is None or not goal.alive:
        goal = agent._top
        while goal.sub is not None:
            goal = goal.sub
    while goal is not None:
        slot = goal.op_slot
        decidable = not slot.wmes and bool(slot.prefs)
        if decidable or goal.sub is None:
            if _decide_slot(agent, goal, decidable):
                return
        goal = goal.sub


def _decide_slot(agent: AgentState, goal: Goal, decidable: bool) -> bool:
    slot = goal.op_slot
    slot.touched = False
    if not decidable:
        impasse, candidates = semantics.NO_CHANGE, []
    else:
        impasse, candidates = semantics.run_preference_semantics(slot, agent.exploration)
        if impasse == semantics.NONE:
            if candidates:
                _select(agent, goal, candidates[0])
                return True
            impasse = semantics.NO_CHANGE
    attribute = "operator" if slot.wmes or impasse != semantics.NO_CHANGE else "state"
    if attribute == "state" and agent.wait_snc and goal.sub is None:
        if agent.trace_level >= 1:  # the kernel shows the waiting state again (measured)
            indent = " " + "   " * (goal.level - 1)
            kind = ""
            if goal.impasse:
                no_change = goal.impasse == semantics.NO_CHANGE
                kind = f"({goal.attribute} {'no-change' if no_change else goal.impasse})"
            agent._emit(f"\n{agent._decisions + 1:>6}:{indent}==>S: {goal.id} {kind}")
        return True
    sub = goal.sub
    if sub is not None and sub.impasse == impasse and sub.attribute == attribute:
        update_items(agent, sub, candidates, slot)
        return False
    if sub is not None:
        remove_goal(agent, sub)
    create_substate(agent, goal, impasse, attribute, candidates, slot)
    return True


def _select(agent: AgentState, goal: Goal, value: Symbol) -> None:
    if goal.sub is not None:
        remove_goal(agent, goal.sub)
    slot = goal.op_slot
    wme = slot.wmes[vkey(value)] = add_wme(agent, goal.id, "operator", value)
    if goal.level > 1:
        remember_source(agent, wme, slot, (REQUIRE, ACCEPTABLE))
        if agent.learning != "never":
            agent.chunker.selected(agent, wme, slot)
    name = _operator_name(agent, value)
    agent._operator_names.append(name if name is not None else "?")
    collect_changes(agent)  # before the WME trace: it may warn (measured)
    if agent.trace_level >= 4:
        trace_wm_changes(agent)  # the kernel traces the decision after its WM changes
    if agent.trace_level >= 1:
        indent = " " + "   " * goal.level
        label = f" ({symbol_text(name)})" if name is not None else ""
        agent._emit(f"\n{agent._decisions + 1:>6}:{indent}O: {format_value(value)}{label}")


def _operator_name(agent: AgentState, value: Symbol) -> Symbol | None:
    if not isinstance(value, Identifier):
        return None
    slot = agent._slot(value, "name", create=False)
    if slot is not None:
        for wme in slot.wmes.values():
            return wme.value
    for wme in agent._arch.get(value, ()):
        if wme.attr == "name":
            return wme.value
    return None


def consistent_through(agent: AgentState, limit: Goal | None) -> bool:
    """Check decisions from the top down to ``limit`` (the bottom if None); remove the
    first inconsistent one with everything below it."""
    goal: Goal | None = agent._top
    while goal is not None:
        if not _decision_consistent(agent, goal):
            if agent.trace_level >= 2 and (goal.sub is not None or goal.selected()):
                _trace_inconsistent(agent, goal)
            remove_current_decision(agent, goal)
            return False
        if goal is limit:
            break
        goal = goal.sub
    return True


def _trace_inconsistent(agent: AgentState, goal: Goal) -> None:
    """What the kernel prints at watch 2 and more when it removes an inconsistent
    decision (measured in soar_sml): the 'REMOVING CONTEXT SLOT' line only when no
    operator was selected (an impasse stood there)."""
    text = (f"Removing substates of {goal.id} because the operator last selected"
            f" in {goal.id} is not\nconsistent with the current preferences.\n")
    if goal.selected() is None:
        text += (f"\n       REMOVING CONTEXT SLOT: Slot Identifier [{goal.id}] and"
                 " attribute [operator]\n")
    text += (f"\n          Decision for goal [{goal.id}] is inconsistent.  Replacing it"
             " with....\n")
    agent._emit_line(text)


def _decision_consistent(agent: AgentState, goal: Goal) -> bool:
    slot = goal.op_slot
    prefs = slot.prefs
    selected_wme = goal.selected()
    if selected_wme is not None:
        if len(prefs) == 1:
            # Fast path: only acceptable preferences, all for the selected operator.
            only = prefs.get(ACCEPTABLE)
            value = selected_wme.value
            if only and all(p.value is value for p in only):
                return True
    elif goal.sub is None:
        # No operator and no impasse: nothing to be inconsistent with. The next decision
        # settles what was proposed meanwhile (measured: pending o-assertions still fire).
        return True
    impasse, candidates = semantics.run_preference_semantics(slot, None, consistency=True)
    selected = goal.selected()
    if selected is not None:
        key = semantics._key(selected.value)
        return impasse == semantics.NONE and any(semantics._key(c) == key for c in candidates)
    sub = goal.sub
    if sub is not None and sub.impasse != semantics.NO_CHANGE:
        return impasse == sub.impasse
    if sub is not None:
        # A state no-change stands while no preference came or went since the slot was
        # decided (measured in soar_sml: one made while the slot held a rejected
        # proposal stays; any later preference, even a lone reject, prohibit or better,
        # or a second reject of the same operator, takes it away).
        return not slot.touched
    return impasse == semantics.NONE and not candidates
