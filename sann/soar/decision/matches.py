"""The matcher's new and lost matches, queued at their goals.

``collect_changes`` takes the matcher's changes after each batch of WME changes: new
matches go to their goal's queue of i- or o-assertions in the order the kernel's Rete made
them (``firing_order``), fired matches that stopped matching are scheduled for retraction.
"""

from __future__ import annotations

from ..instantiation import (
    MIXED,
    Instantiation,
    is_o_supported,
    match_goal,
)
from .agent_state import AgentState
from .firing_order import batch_sorted, check_links, file_removals, found_order, kernel_sorted


def collect_changes(agent: AgentState, in_match_order: bool = False) -> None:
    """Move the matcher's new and retracted matches into the goals' queues.

    New matches are queued in the order the kernel's Rete would have made them: by
    the newest WME they match, and for one WME the later-loaded production first (its
    node is activated first); firing then takes them newest first, like the kernel's
    match-set lists."""
    new, gone = agent.matcher.take_changes()
    agent._collects += 1
    start, agent._batch_start = agent._batch_start, agent._timetag
    if start != agent._timetag:
        agent._batch_starts.append(start)
    if agent._removed_now:
        file_removals(agent)
    elif agent._last_removed:
        agent._last_removed = []
    if agent._join_links and (new or gone):
        check_links(agent)
    elif agent._links_before:
        agent._links_before = {}
    if gone:
        _retract_matches(agent, gone, agent.matcher.blocked_retractions)
    if new:
        if len(new) > 1 and not in_match_order:
            new = batch_sorted(agent, new, start)
        _queue_matches(agent, new)


def _retract_matches(agent: AgentState, gone: list, blocked: int = -1) -> None:
    """Schedule the retraction of fired matches that stopped matching, in creation
    order (it decides the order of retraction); unfired ones just leave their queue."""
    inst_of = agent._inst_of
    pending_goal = agent._pending_goal
    fired: list[Instantiation] = []
    first_removed = 0  # fired[:first_removed]: blocked by new WMEs (when known)
    for k, match in enumerate(gone):
        inst = inst_of.get(match)
        if inst is not None:
            del inst_of[match]
            fired.append(inst)
            if k < blocked:
                first_removed += 1
            continue
        goal = pending_goal.get(match)
        if goal is not None:
            del pending_goal[match]
            goal.pending_i.pop(match, None)
            goal.pending_o.pop(match, None)
    if len(fired) > 1:
        # The kernel's order of queueing them, which it undoes when retracting: first
        # those a new WME blocked (WMEs are added to the Rete before any is removed),
        # then those of removed WMEs, the newest match first.
        if blocked >= 0:
            made, removed = fired[:first_removed], fired[first_removed:]
        else:  # those that lost no WME
            wm = agent._wm
            made, removed = [], []
            for inst in fired:
                for wme in inst.wmes:
                    if wme is not None and wm.get(wme.timetag) is not wme:
                        removed.append(inst)
                        break
                else:
                    made.append(inst)
        if len(made) > 1:
            made = kernel_sorted(agent, made, [inst.match for inst in made], True)
        if len(removed) > 1:
            removed = found_order(agent, removed)
        fired = made + removed
    for inst in fired:
        agent._schedule_retraction(inst)


def _queue_matches(agent: AgentState, new: list) -> None:
    """Queue new matches at their goals as i- or o-assertions."""
    top = agent._top
    only_top = top.sub is None
    productions = agent._productions
    pending_goal = agent._pending_goal
    for match in new:
        info = productions.get(match.production.name)
        if info is None:
            continue
        if only_top:
            goal = top  # every state-linked match belongs to the only state
            if not info.operator_conditions and info.declared is None:
                top.pending_i[match] = info
                pending_goal[match] = top
                continue
            wmes = match.wmes
        else:
            wmes = match.wmes
            ident = match_goal(wmes)
            maybe = agent._goals.get(ident) if ident is not None else None
            if maybe is None or not maybe.alive:
                continue
            goal = maybe  # (mypyc checks the declared Goal: no None here)
        support = is_o_supported(info, wmes, goal.id, match)
        if support is MIXED:
            agent._warn_mixed_support(info.production.name)
            support = False
        if support:
            goal.pending_o[match] = info
        else:
            goal.pending_i[match] = info
        pending_goal[match] = goal
