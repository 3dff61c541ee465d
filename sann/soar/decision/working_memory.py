"""Working memory's primitives: adding and removing WMEs.

Every WME of a run is made by ``add_wme`` and leaves by ``remove_wme``, which keep the
matcher, the indexes of working memory and the trace buffers up to date. A WME leaving may
retract the justifications that tested it and remove the substates whose goal dependency
set holds it; one coming may retract a justification whose negated condition it matches.
"""

from __future__ import annotations

from ..goals import Goal
from ..memory import WME, Identifier, Symbol
from ..production import ConjunctiveNegation, Const, Var
from ..trace import trace_wme
from .agent_state import AgentState, vkey

_new = object.__new__


def add_wme(agent: AgentState, ident: Identifier, attr: Symbol, value: Symbol,
            acceptable: bool = False) -> WME:
    timetag = agent._timetag = agent._timetag + 1
    # WME.__init__, inline: CPython 3.11 runs a class's Python __init__ through a C
    # call into a new interpreter frame, and every WME of a run is made here
    wme = _new(WME)
    wme.id = ident
    wme.attr = attr
    wme.value = value
    wme.timetag = timetag
    wme.acceptable = acceptable
    wm = agent._wm
    wm[timetag] = wme
    if type(value) is Identifier and value.level is None:
        refs = agent._refs
        refs[value] = refs.get(value, 0) + 1
    if agent._neg_watch:
        _check_negations(agent, wme)
    agent.matcher.add_wme(wme)
    by_id = agent._by_id
    if by_id is not None:  # _file_wme, inline: every WME of a run is made here
        slots = by_id.get(ident)
        if slots is None:
            by_id[ident] = {vkey(attr): {wme: None}}
        else:
            key = vkey(attr)
            bucket = slots.get(key)
            if bucket is None:
                slots[key] = {wme: None}
            else:
                bucket[wme] = None
    by_attr = agent._by_attr
    if by_attr is not None:
        key = vkey(attr)
        bucket = by_attr.get(key)
        if bucket is None:
            by_attr[key] = {wme: None}
        else:
            bucket[wme] = None
    if agent.trace_level >= 4:
        agent._traced_adds.append(wme)
    return wme


def remove_wme(agent: AgentState, wme: WME) -> None:
    wm = agent._wm
    if len(wm) > agent._wm_max:
        # Working memory only shrinks here, so its high-water mark is reached just
        # before a removal (or now: see stats).
        agent._wm_max = len(wm)
    timetag: int = wme.timetag
    if timetag not in wm:  # (not ``wm.pop(timetag, None)``: mypyc calls that generically)
        return
    del wm[timetag]
    agent.matcher.remove_wme(wme)
    agent._removed_now.append(wme)
    by_id = agent._by_id
    if by_id is not None:
        slots = by_id[wme.id]
        key = vkey(wme.attr)
        bucket = slots[key]
        del bucket[wme]
        if not bucket:
            del slots[key]
            if not slots:
                del by_id[wme.id]
    by_attr = agent._by_attr
    if by_attr is not None:
        key = vkey(wme.attr)
        bucket = by_attr[key]
        del bucket[wme]
        if not bucket:
            del by_attr[key]
    value = wme.value
    if type(value) is Identifier and value.level is None:
        count = agent._refs[value] - 1
        if count:
            agent._refs[value] = count
        else:
            del agent._refs[value]
            agent._unlinked.append(value)
    if agent.trace_level >= 4:
        agent._traced_removes.append(wme)
    if agent._dependents or agent._gds_index:  # justifications and substates only
        _substate_wme_gone(agent, wme)


def trace_wm_changes(agent: AgentState) -> None:
    """Print the WME changes buffered since the last call, as the kernel's
    ``do_buffered_wm_changes`` does at the end of each working-memory phase (measured:
    additions newest first, then removals, the last requested first; each line ends
    with a newline)."""
    adds, removes = agent._traced_adds, agent._traced_removes
    if not adds and not removes and not agent._traced_late:
        return
    removes += agent._traced_late
    agent._traced_adds, agent._traced_removes, agent._traced_late = [], [], []
    lines = [f"=>WM: {trace_wme(wme)}\n" for wme in reversed(adds)]
    lines += [f"<=WM: {trace_wme(wme)}\n" for wme in reversed(removes)]
    agent._emit("".join(lines))


def _substate_wme_gone(agent: AgentState, wme: WME) -> None:
    """A WME left: retract the justifications that rest on it and remove the substates
    whose goal dependency set holds it."""
    dependents = agent._dependents.pop(wme, None)
    if dependents:
        for inst in dependents:
            source = inst.source
            if source is not None and not source.alive and all(
                p.o_supported for p in inst.prefs
            ):
                # Its retraction, which changes nothing, went with its substate
                # (measured: no elaboration cycle for it when the decision that
                # removed its ground removed the substate too).
                continue
            agent._schedule_retraction(inst)
    goals = agent._gds_index.pop(wme, None)
    if goals:
        for goal in goals:
            if goal.alive:
                if agent.trace_level >= 2:
                    trace_gds_removal(agent, goal, wme)
                agent._remove_goal(goal)


def trace_gds_removal(agent: AgentState, goal: Goal, wme: WME) -> None:
    """The kernel's watch-2 text for a goal-dependency-set violation (measured in
    soar_sml; one text wherever the WME goes): on a fresh line, two messages naming
    the WME, each line ended."""
    where = trace_wme(wme)
    agent._emit_line(
        f"Removing state {goal.id} because element in GDS changed. WME: {where}\n"
        f"\n    REMOVING GOAL [{goal.id}] due to change in GDS WME {where}\n"
    )


def add_arch(agent: AgentState, ident: Identifier, attr: Symbol, value: Symbol) -> WME:
    wme = add_wme(agent, ident, attr, value)
    agent._arch.setdefault(ident, []).append(wme)
    return wme


def remove_arch(agent: AgentState, wme: WME) -> None:
    bucket = agent._arch.get(wme.id)
    if bucket is not None:
        try:
            bucket.remove(wme)
        except ValueError:
            pass
        if not bucket:
            del agent._arch[wme.id]
    remove_wme(agent, wme)


def _check_negations(agent: AgentState, wme: WME) -> None:
    watchers = agent._neg_watch.get((wme.id, vkey(wme.attr)))
    if not watchers:
        return
    for just, test, bindings in list(watchers):
        if just.retracted:
            continue
        if isinstance(test, ConjunctiveNegation):
            agent._ncc_checks.append((just, test, bindings))
            continue
        if isinstance(test, Const) and vkey(test.value) != vkey(wme.value):
            continue
        if isinstance(test, Var):
            bound = bindings.get(test.name)
            if bound is not None and vkey(bound) != vkey(wme.value):
                continue
        agent._schedule_retraction(just)


def apply_input_ops(agent: AgentState) -> None:
    """Apply the queued input changes in order. A handle is queued when made and again
    when removed: unremoved without a WME it is added; removed with a WME it goes
    (removed before it was ever added, both entries are no-ops)."""
    ops, agent._input_ops = agent._input_ops, []
    arch = agent._arch
    for handle in ops:
        if handle.removed:
            if handle.wme is not None:
                remove_arch(agent, handle.wme)
                handle.wme = None
            continue
        if handle.wme is not None:
            continue  # defensive: a live handle is added once
        ident = handle.id
        wme = handle.wme = add_wme(agent, ident, handle.attr, handle.value)
        bucket = arch.get(ident)
        if bucket is None:
            arch[ident] = [wme]
        else:
            bucket.append(wme)
