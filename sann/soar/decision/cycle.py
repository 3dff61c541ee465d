"""The decision cycle's phases: input, propose, decide, apply, output.

``run_phase`` runs the phase the agent is in. The propose and apply phases run
elaboration cycles until quiescence, level by level as the kernel's "waterfall" does: each
cycle fires the pending assertions of the highest goal that has any (in the apply phase,
when a goal has no i-activity left, its o-assertions: a ``PE`` cycle), lower levels after
it while they have assertions waiting, then the retractions, then the working-memory
phase. The goal stack is checked for consistency when the active level moves down or a
goal turns from i- to o-firing.
"""

from __future__ import annotations

from ..goals import Goal
from ..instantiation import (
    Instantiation,
    ProductionInfo,
)
from ..memory import Identifier
from .agent_state import AgentState
from .decide import consistent_through, decide_context_slots
from .firing import assert_preferences, fire, retract
from .matches import collect_changes
from .results import JustificationMatch, grow_gds
from .wm_phase import working_memory_phase
from .working_memory import apply_input_ops, trace_wm_changes


def run_phase(agent: AgentState) -> None:
    phase = agent._phase
    if phase == "input":
        _input_phase(agent)
    elif phase == "propose":
        _elaboration_phase(agent, apply=False)
    elif phase == "decide":
        _decision_phase(agent)
    elif phase == "apply":
        _elaboration_phase(agent, apply=True)
    else:
        _output_phase(agent)


def _input_phase(agent: AgentState) -> None:
    if agent.trace_level >= 2:
        agent._emit("\n--- Input Phase --- \n")
    apply_input_ops(agent)
    if agent.trace_level >= 4:
        trace_wm_changes(agent)
    collect_changes(agent)
    if agent.trace_level >= 2:
        agent._emit("\n--- END Input Phase --- \n")
    agent._phase = "propose"
    agent._active = None
    agent._active_type = ""
    agent._phase_cycles = 0
    if agent.trace_level >= 2:
        agent._emit("\n--- Propose Phase ---\n")


def _output_phase(agent: AgentState) -> None:
    if agent.trace_level >= 2:
        agent._emit("\n--- Output Phase ---\n\n--- END Output Phase ---\n")
    agent._phase = "input"


def _elaboration_phase(agent: AgentState, apply: bool) -> None:
    """Run elaboration cycles until quiescence ends the phase, or a halt stops the run
    (after the cycle it happened in). An interrupt stops the run when the phase is over,
    as in the kernel (measured)."""
    end = "output" if apply else "decide"
    if agent._phase_cycles == 0:
        agent._inner_goal = None
    if agent._phase_cycles == 0 and apply and agent.trace_level >= 2 and agent._active is None:
        agent._emit("\n--- Application Phase ---\n")
    while True:
        goal, firing = _next_active(agent, apply)
        if firing == "":
            # The kernel checks the stack at the end of an application phase only
            # after an IE cycle (measured: a tie that a PE cycle's result resolved
            # stands until the propose phase).
            if not apply or agent._active_type != "PE":
                consistent_through(agent, None)
            _end_phase(agent, apply, end)
            return
        _elaboration_cycle(agent, goal, firing)
        agent._e_cycles += 1
        agent._phase_cycles += 1
        if firing == "PE":
            agent._pe_cycles += 1
        if agent._phase_cycles >= agent.max_elaborations and not agent._halted:
            agent._emit(f"\nWarning: reached max-elaborations; proceeding to {end} phase.")
            _end_phase(agent, apply, end)
            return
        if agent._halted:  # an interrupt (_stop) lets the phase finish, as in the kernel
            # The phase's END line only when the halt came in its last cycle (measured:
            # 'Change Working Memory (PE) ---\n\nSystem halted.' when IE firings follow).
            if _quiescent(agent, apply):
                _trace_phase_end(agent, apply)
            return


def _quiescent(agent: AgentState, apply: bool) -> bool:
    """Whether no goal has firings or retractions waiting (without the consistency
    checks of ``_next_active``)."""
    if agent._nil_retractions:
        return False
    goal: Goal | None = agent._top
    while goal is not None:
        if goal.pending_i or goal.retractions or (apply and goal.pending_o):
            return False
        goal = goal.sub
    return True


def _trace_phase_end(agent: AgentState, apply: bool) -> None:
    if agent.trace_level >= 2:
        agent._emit(
            "\n--- END Application Phase ---\n" if apply else "\n--- END Propose Phase ---\n"
        )


def _end_phase(agent: AgentState, apply: bool, end: str) -> None:
    _trace_phase_end(agent, apply)
    agent._phase = end
    agent._active = None
    agent._active_type = ""
    agent._phase_cycles = 0


def _next_active(agent: AgentState, apply: bool) -> tuple[Goal | None, str]:
    """The goal and firing type of the next elaboration cycle, '' at quiescence.

    Checks the goal stack's consistency like the kernel when the active level moves or
    a goal switches from i- to o-firing; an inconsistent decision ends the phase.
    """
    if not apply and agent._nil_retractions:
        # The propose phase does the retractions of removed goals first, on their own
        # (measured); the apply phase lets them ride along with the next cycle.
        return None, "NIL"
    goal: Goal | None = agent._top
    chosen: Goal | None = None
    firing = ""
    while goal is not None:
        if goal.pending_i or goal.retractions:
            chosen, firing = goal, "IE"
            break
        if apply and goal.pending_o:
            chosen, firing = goal, "PE"
            break
        goal = goal.sub
    if chosen is None:
        # Retractions of instantiations whose goal is gone are done in any cycle; on
        # their own they make a cycle at "level 0", like the kernel's.
        return (None, "NIL") if agent._nil_retractions else (None, "")
    previous, previous_type = agent._active, agent._active_type
    check: Goal | None = None
    if previous is not None and previous.alive:
        if chosen.level > previous.level:
            check = previous  # moving down the stack: re-check the goals above
        elif firing == "PE" and previous_type != "PE":
            check = chosen
    elif previous is not None and not previous.alive and firing == "PE":
        check = chosen
    if check is not None and not consistent_through(agent, check):
        return None, ""
    agent._active, agent._active_type = chosen, firing
    return chosen, firing


def _elaboration_cycle(agent: AgentState, goal: Goal | None, firing: str) -> None:
    """One elaboration cycle, as the kernel's "new waterfall" preference phase: the
    pending assertions of the firing type fire level by level from the active goal down
    (each level's preferences asserted before the next level fires), then the active
    goal's retractions and those of removed goals, then the working-memory phase."""
    # A cycle of removed goals' retractions alone is an IE cycle, traced at the goal the
    # last cycle went down to, or at level 0 when that goal is gone (measured)
    shown = "IE" if goal is None else firing
    last = agent._inner_goal
    traced = goal if goal is not None else last if last is not None and last.alive else None
    if agent.trace_level >= 2 and agent._phase == "apply":
        depth = 0 if traced is None else traced.level
        agent._emit_line(
            f"\t--- Firing Productions ({shown}) For State At Depth {depth} ---\n"
        )
    if goal is None and agent.trace_level >= 3:
        where = "0 goal #" if traced is None else f"{traced.level} goal {traced.id}"
        agent._emit(f"\n--- Inner Elaboration Phase, active level {where} ---\n")
    level_goal = goal
    change_level = goal.level if goal is not None else 0
    while level_goal is not None:
        if level_goal is not goal and not _pending_from(agent, level_goal, firing):
            break  # the kernel goes down the stack only while assertions wait below
        if agent.trace_level >= 3:
            agent._emit(
                f"\n--- Inner Elaboration Phase, active level {level_goal.level}"
                f" goal {level_goal.id} ---\n"
            )
        agent._inner_goal = level_goal
        limit = change_level if level_goal is not goal else 0
        if _fire_level(agent, level_goal, firing, limit) and level_goal.level > change_level:
            change_level = level_goal.level
        level_goal = level_goal.sub
    retractions, agent._nil_retractions = agent._nil_retractions, []
    if goal is not None:
        # Newest first, like the kernel's match-set lists.
        retractions = goal.retractions[::-1] + retractions
        goal.retractions = []
    for inst in retractions:
        retract(agent, inst)
    if agent.trace_level >= 2 and agent._phase == "apply":
        # Not on a fresh line: after a write that did not end its line, the kernel
        # goes on on the same line (measured: "applied\t--- Change Working Memory").
        agent._emit(f"\t--- Change Working Memory ({shown}) ---\n")
    working_memory_phase(agent)
    if agent.trace_level >= 4:
        trace_wm_changes(agent)
    collect_changes(agent)


def _pending_from(agent: AgentState, goal: Goal, firing: str) -> bool:
    """Whether ``goal`` or a goal below it has retractions or assertions of the
    ``firing`` type waiting (measured: the kernel prints a lower level's 'Inner
    Elaboration Phase' header only then)."""
    level_goal: Goal | None = goal
    while level_goal is not None:
        if level_goal.retractions:
            return True
        queue = level_goal.pending_i if firing == "IE" else level_goal.pending_o
        if any(type(match) is not JustificationMatch for match in queue):
            return True
        level_goal = level_goal.sub
    return False


def _fire_level(agent: AgentState, goal: Goal, firing: str, change_level: int) -> bool:
    """Fire one level's pending assertions; return whether any were pending.

    Below the active level, the kernel's waterfall postpones an instantiation that
    would change an identifier at or above ``change_level`` (a level already changed in
    this cycle): it stays pending for a later cycle."""
    queue = goal.pending_i if firing == "IE" else goal.pending_o
    if not queue:
        return False
    matches = list(queue.items())
    queue.clear()
    fired: list[Instantiation] = []
    o_support = firing == "PE"
    pending_goal = agent._pending_goal
    postponed: list[tuple[object, ProductionInfo]] = []
    for match, info in reversed(matches):
        if type(match) is JustificationMatch:
            if change_level and match.level <= change_level:
                postponed.append((match, info))
            continue
        if change_level and _touches_level(agent, match, info, change_level):
            postponed.append((match, info))
            continue
        if match in pending_goal:
            del pending_goal[match]
        fired.append(fire(agent, match, info, goal, o_support))
    if postponed:
        # They keep their places in the queue (measured in soar_sml: two snc matches
        # the waterfall put off, of (S1 ^count 2) and the newer-entered (S1 ^count 0),
        # fire count 0 first, as they would have).
        queue.update(reversed(postponed))
    assert_preferences(agent, fired, o_support)
    if agent._gds_requests:
        grow_gds(agent)
    return True


def _touches_level(agent: AgentState, match: object, info: ProductionInfo,
                   change_level: int) -> bool:
    bindings = match.bindings  # type: ignore[attr-defined]
    for name in info.make_ids:
        ident = bindings.get(name)
        if isinstance(ident, Identifier) and agent._level_of(ident) <= change_level:
            if agent.trace_level >= 5:
                agent._emit(
                    f"\n*** Waterfall: aborting firing because ({ident} * *) level"
                    f" {agent._level_of(ident)} is on or higher (lower int) than change"
                    f" level {change_level}"
                )
            return True
    return False


def _decision_phase(agent: AgentState) -> None:
    if agent.trace_level >= 2:
        agent._emit("\n--- Decision Phase ---\n")
    collect_changes(agent)
    decide_context_slots(agent)
    agent._decisions += 1
    collect_changes(agent)
    if agent.trace_level >= 4:
        trace_wm_changes(agent)
    if agent.trace_level >= 2:
        agent._emit("\n--- END Decision Phase ---\n")
    agent._phase = "apply"
    agent._active = None
    agent._active_type = ""
    agent._phase_cycles = 0
