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

Once found, the results get a justification (``justify``): an instantiation one level up
whose conditions are the superstate WMEs the results depend on, found by backtracing; and a
substate's first o-supported local preferences make its goal dependency set (``grow_gds``),
the superstate WMEs whose change removes the substate.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping

from ..goals import Goal
from ..instantiation import (
    Instantiation,
)
from ..matching.kernel_prefix import _exists, _positive
from ..memory import WME, Identifier, Symbol
from ..preferences import (
    ACCEPTABLE,
    BETTER,
    BINARY_INDIFFERENT,
    NUMERIC_INDIFFERENT,
    REJECT,
    REQUIRE,
    WORSE,
    Preference,
    Slot,
)
from ..production import Condition, ConjunctiveNegation, Const, Var
from . import preference_semantics as semantics
from .agent_state import AgentState, vkey

# IMPORTS

def handle_substate_preferences(agent: AgentState, inst: Instantiation) -> None:
    """Results (preferences on superstate structure) get a justification; o-supported
    local preferences extend the goal dependency set."""
    goal = inst.goal
    level = goal.level
    results = _find_results(agent, inst, level)
    if results:
        _justify(agent, inst, results)
    if any(p.o_supported and p not in results for p in inst.prefs):
        agent._gds_requests.append((goal, inst))

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


def find_results(inst: Instantiation, level: int, level_of: Callable[[Identifier], int],
                 slots: Mapping[Identifier, Mapping[object, Slot]]) -> list[Preference]:
    """The results of ``inst`` (fired at goal ``level``), the last found first: the order
    of a justification's preference list (its preferences are asserted last first)."""
    return ResultSearch(inst, level, level_of, slots).run()[::-1]


def grow_gds(agent: AgentState) -> None:
    """Make the goal dependency set of a substate whose first o-supported local
    preferences this wave made, from the instantiation that made them; once made, the
    kernel does not extend it (measured in soar_sml: with the set made by an earlier
    operator, or by another rule of the same wave, a superstate WME that only a later
    o-supported instantiation tested leaves without removing the substate; tested by
    the rule that made the set, it removes it, whoever made the WME). The set goes
    through the local i-supported WMEs' current acceptable preferences, so a WME that
    an o-reject of the wave took away leads nowhere (measured: a counter made by an
    elaboration on a superstate flag and modified by ``^steps <n> - (+ <n> 1)`` does
    not make the flag part of the GDS)."""
    requests, agent._gds_requests = agent._gds_requests, []
    for goal, inst in requests:
        if not goal.alive or goal.gds_made:
            continue
        goal.gds_made = True
        for wme in _backtrace(agent, inst, goal.level, through_o_support=False):
            goal.gds.add(wme)
            agent._gds_index.setdefault(wme, {})[goal] = None


def _find_results(agent: AgentState, inst: Instantiation, level: int) -> list[Preference]:
    return find_results(inst, level, agent._level_of, agent._slots)


def _promote(agent: AgentState, results: list[Preference]) -> None:
    """Identifiers a result links to move up to the result's level (parents first:
    ``results`` is the last found first), once the results have been backtraced: the
    kernel backtraces a result made from local structure through that structure."""
    for pref in reversed(results):
        level = agent._level_of(pref.id)
        for sym in (pref.value, pref.referent):
            if (isinstance(sym, Identifier) and sym.level is None
                    and agent._level_of(sym) > level):
                agent._level[sym] = level


def _justify(agent: AgentState, inst: Instantiation, results: list[Preference]) -> None:
    """Stand in for the substate's reasoning with justifications whose conditions are
    the superstate WMEs the results depend on. As in the kernel, the first lives one
    level up and holds every result; when results go higher, that justification is an
    instantiation with results of its own, justified one level further up, and so on
    (measured in soar_sml: a result two levels up is asserted by '[level 2] (justify1)'
    and by 'justify3', which stays when the middle state goes)."""
    visited: list[Instantiation] = []
    grounds = tuple(_backtrace(agent,
        inst, inst.goal.level, through_o_support=True, visited=visited,
        also=[pref.inst for pref in results if pref.inst is not inst],
    ))
    # explained before the results' identifiers are promoted (they are local to it)
    explained = (agent.chunker.explain(agent, inst, results) if agent.learning != "never"
                 else None)
    _promote(agent, results)
    if not grounds:
        _ignore_unconditional_justification(agent, inst)
        return
    home = inst.goal.superstate
    assert home is not None  # results come from substates
    just, learned = _justify_or_learn(agent, inst, results, grounds, home, inst, explained)
    if _watch_negations(agent, just, visited, inst.goal.level):
        _justification_matches(agent, inst.goal, min(agent._level_of(p.id) for p in results))
    while home.superstate is not None:
        higher = [p for p in just.prefs if agent._level_of(p.id) < home.level]
        if not higher:
            break
        more: list[Instantiation] = []
        grounds = tuple(
            _backtrace(agent, just, home.level, through_o_support=True, visited=more)
        )
        if not grounds:
            break
        # the negated conditions of every rule behind it (the first is the previous
        # justification itself)
        visited += more[1:]
        # a chunk's instantiation with results higher up is explained in turn (the
        # kernel's chunkx2*...)
        explained = agent.chunker.explain(agent, just, higher) if learned else None
        source, home = home, home.superstate
        just, learned = _justify_or_learn(agent, just, higher, grounds, home, inst, explained)
        _watch_negations(agent, just, visited, source.level)


def _justify_or_learn(agent: AgentState, made_by: Instantiation, results: list[Preference],
                      grounds: tuple[WME, ...], home: Goal, fired: Instantiation,
                      explained: object | None) -> tuple[Instantiation, bool]:
    """The justification at ``home`` for ``made_by``'s results, or, when chunking
    ``explained`` them, the one the learner makes (a chunk's instantiation when it learns
    one); whether a chunk was learned."""
    if explained is None:
        return _make_justification(agent, made_by, results, grounds, home, fired), False
    return agent.chunker.justify(agent, made_by, results, grounds, home, fired, explained)


def _make_justification(agent: AgentState, inst: Instantiation, results: list[Preference],
                        grounds: tuple[WME, ...], home: Goal, fired: Instantiation,
                        chunk: str | None = None) -> Instantiation:
    """A justification at ``home`` for ``inst``'s results; its support is computed like
    a rule's: o-support when its conditions include the selected operator of its goal.
    ``fired``: the rule instantiation whose firing made it (its preferences are
    asserted next to that one's, see ``_with_justifications``); ``chunk``: the name
    of the chunk learned from it, which its instantiation is (see `Chunker`)."""
    agent._justifications += 1
    match_goal_id = _goal_of_grounds(agent, grounds).id
    operators = [
        w.value
        for w in grounds
        if w.id is match_goal_id and w.attr == "operator" and not w.acceptable
    ]
    just = Instantiation(
        # the kernel spends two numbers on each justification (measured: justify1,
        # justify3, justify5, ...)
        chunk or f"justify{2 * agent._justifications - 1}", None, home, grounds,
        bool(operators), True
    )
    just.grounds = grounds
    just.source = inst.goal
    inst.goal.justified[just] = None
    if operators and _proposes_on_a_state(results, match_goal_id):
        operators = []  # a proposal is i-supported, as a rule's (see is_o_supported)
    on_operator = [any(pref.id is op for op in operators) for pref in results]
    mixed = bool(operators) and any(on_operator) and not all(on_operator)
    if mixed and chunk is None:  # a chunk's own instantiation is not warned of (measured)
        agent._warn_mixed_support(just.name, justification=True)
    for pref, elaborates in zip(results, on_operator, strict=True):
        copy = Preference(pref.type, pref.id, pref.attr, pref.value, pref.referent, just)
        copy.o_supported = bool(operators) and not elaborates and not mixed
        just.prefs.append(copy)
        if not pref.live:
            agent._copied_from[copy] = pref
        if copy.o_supported and pref.type == REJECT and not pref.live:
            # The copy is an o-reject, which takes the rule's own reject with it
            # (measured in soar_sml: '+ (S1 ^x 5 -) [level 2]' is not asserted then).
            pref.inst = None  # type: ignore[assignment]
    agent._new_justifications.append((fired, just))
    _replace_duplicate_justification(agent, just)
    if home.level > 1:
        home.insts[just] = None
        level = home.level
        if any(p.o_supported and agent._level_of(p.id) == level for p in just.prefs):
            agent._gds_requests.append((home, just))
    return just


def _ignore_unconditional_justification(agent: AgentState, inst: Instantiation) -> None:
    """Results that test nothing in the superstate get no justification: the kernel
    warns at watch 2 and up and the results keep only the substate rule's support, so
    they go with the substate (measured in soar_sml: a result made from a negated
    superstate test leaves when its substate does)."""
    if agent.trace_level >= 2:
        agent._emit(
            "\nWarning: Soar has created a chunk or justification with no conditions."
            "  Ignoring.\n\n         Any results created will lose support when the"
            " sub-state disappears.\n         To avoid this issue, the problem-solving"
            " in the sub-state must\n         positively test at least one item in the"
            f" super-state.\n\nRule firing that led to invalid chunk: {inst.name}\n"
        )


def _replace_duplicate_justification(agent: AgentState, just: Instantiation) -> None:
    """A justification identical to a live one (same conditions, same results)
    replaces it: the kernel retracts the old one in the next cycle (measured). One
    made in the same wave is not retracted: no cycle goes to its level for it
    (measured in soar_sml: justify5 and justify7 of two elaborations firing together
    for the same (S1 ^seen O4) leave level 1 quiet)."""
    signature = (
        frozenset(w.timetag for w in just.grounds),
        frozenset(
            (p.type, id(p.id), vkey(p.attr), vkey(p.value), vkey(p.referent))
            for p in just.prefs
        ),
    )
    old = agent._justification_index.get(signature)
    if old is not None and not old.retracted and all(
            made is not old for _, made in agent._new_justifications):
        agent._schedule_retraction(old)
    agent._justification_index[signature] = just
    just.match = signature


def _justification_matches(agent: AgentState, source: Goal, result_level: int) -> None:
    """The kernel adds a justification to its Rete for each level a result passes
    (from the substate up to the result's level). When a result goes up two levels or
    more, each new one matches at once, which is activity at its level (a cycle there
    fires nothing; measured with soar_sml). Count it the same way."""
    if source.level - result_level < 2:
        return  # one level up: the kernel refracts the match, no new activity
    goal: Goal | None = source.superstate
    while goal is not None and goal.level >= result_level:
        goal.pending_i[JustificationMatch(result_level)] = None  # type: ignore[assignment]
        goal = goal.superstate


def _watch_negations(agent: AgentState, just: Instantiation, visited: list[Instantiation],
                     level: int) -> bool:
    """Watch what the new justification matches: a WME it tested leaving, or one that
    a negated condition of its instantiations tested in superstates appearing,
    retracts it even when its results are all o-supported: no preference changes,
    but it is activity at its level, like the kernel's (an elaboration cycle that
    fires nothing; measured).

    A justification whose conditions do not hold when it is made (backtracing
    through local o-supported WMEs reaches tests of the past: a negation of a WME
    that has since come, a WME since gone) never matches, so nothing retracts it:
    watch nothing then and return False (measured in soar_sml: justify3 with
    ``(state S1 -^problem <p*1>)`` when (S1 ^problem P1) stands and
    ``(C5 -^digit1 <d*1>)`` for its own result (C5 ^digit1 5) makes no cycle at S1's
    level, while justify1 with only the first makes one when (S1 ^problem P1) comes).
    """
    entries = list(_negations_of(agent, visited, level))
    wm = agent._wm
    if any(wm.get(wme.timetag) is not wme for wme in just.grounds) or any(
        _negation_holds_not(agent, element, bindings) for _, element, _, bindings in entries
    ):
        return False
    for wme in just.grounds:
        agent._dependents.setdefault(wme, []).append(just)
    keys = []
    for key, _, test, bindings in entries:
        agent._neg_watch.setdefault(key, []).append((just, test, bindings))
        keys.append(key)
    agent._neg_keys[just] = keys
    return True


def _negation_holds_not(agent: AgentState, element: object, bindings: dict[str, Symbol]) -> bool:
    """Whether a WME now matches a negated condition or conjunctive negation: a search
    that takes each condition's candidates from the index by identifier once an outer
    or earlier condition binds it (not a scan of working memory per condition)."""
    if isinstance(element, ConjunctiveNegation):
        return _exists(element.conditions, bindings, agent._candidates)
    assert isinstance(element, Condition)
    return _exists((_positive(element),), bindings, agent._candidates)


def _negations_of(agent: AgentState, visited: list[Instantiation], level: int
                  ) -> Iterator[tuple[tuple, object, object, dict[str, Symbol]]]:
    """``(watch key, element, watched test, bindings)`` of every negated condition
    on a superstate identifier in the instantiations behind a justification."""
    for source in visited:
        match = source.match
        if match is None:
            continue
        bindings = match.bindings  # type: ignore[attr-defined]
        for element in match.production.conditions:  # type: ignore[attr-defined]
            if isinstance(element, ConjunctiveNegation):
                # Watched on each inner condition of a superstate identifier bound
                # outside; whether the whole negation now matches is checked at the end
                # of the phase (its other WMEs may come later in it).
                for cond in element.conditions:
                    key = _watch_key(agent, cond, bindings, level)
                    if key is not None:
                        yield key, element, element, bindings
                continue
            if not isinstance(element, Condition) or not element.negated:
                continue
            key = _watch_key(agent, element, bindings, level)
            if key is not None:
                yield key, element, element.value_test, bindings


def _watch_key(agent: AgentState, cond: object, bindings: dict[str, Symbol],
               level: int) -> tuple | None:
    """``(identifier, attribute)`` of a negated condition on a superstate identifier
    that the match bound, or None."""
    if not isinstance(cond, Condition) or not isinstance(cond.id_test, Var):
        return None
    if not isinstance(cond.attr_test, Const):
        return None
    ident = bindings.get(cond.id_test.name)
    if not isinstance(ident, Identifier) or agent._level_of(ident) >= level:
        return None
    return (ident, vkey(cond.attr_test.value))


def _goal_of_grounds(agent: AgentState, grounds: tuple[WME, ...]) -> Goal:
    """The justification's match goal: the deepest state among its conditions."""
    best = agent._top
    for wme in grounds:
        goal = agent._goals.get(wme.id)
        if goal is not None and goal.level > best.level:
            best = goal
    return best


def _backtrace(agent: AgentState, inst: Instantiation, level: int, through_o_support: bool,
               visited: list[Instantiation] | None = None,
               also: Iterable[Instantiation | None] = ()) -> list[WME]:
    """Superstate WMEs (identifier above ``level``) that ``inst`` depends on, found by
    walking back through the instantiations that made its local WMEs. ``also``: the
    instantiations of its other results (made earlier, linked to the superstate by
    ``inst``), which the justification depends on too."""
    grounds: dict[int, WME] = {}
    starts = [inst]
    for other in also:
        if other is not None and all(other is not start for start in starts):
            starts.append(other)
    if visited is not None:
        visited.extend(starts)
    seen: set[int] = {id(start) for start in starts}
    stack = starts[::-1]
    while stack:
        current = stack.pop()
        for wme in current.wmes:
            if wme is None:
                continue
            if wme.attr in _ITEM_ATTRS:
                wme = _item_proposal(agent, wme)
            if agent._level_of(wme.id) < level:
                grounds.setdefault(wme.timetag, wme)
                continue
            supports = (_supporting_instantiations(agent, wme) if through_o_support
                        else _current_supports(agent, wme))
            for source in supports:
                if id(source) in seen:
                    continue
                if not through_o_support and any(
                    p.o_supported and p.live for p in source.prefs
                ):
                    continue
                seen.add(id(source))
                stack.append(source)
                if visited is not None:
                    visited.append(source)
    return list(grounds.values())


def _item_proposal(agent: AgentState, wme: WME) -> WME:
    """An impasse's ``^item`` or ``^non-numeric`` WME stands for the superstate's
    acceptable-preference WME of that operator (measured in soar_sml: a result made
    from ``(S2 ^item O2)`` alone is justified by ``(state S1 ^operator O2 +)``); any
    other WME stands for itself."""
    goal = agent._goals.get(wme.id)
    if goal is None or goal.superstate is None:
        return wme
    if goal.items.get((wme.attr, semantics._key(wme.value))) is not wme:
        return wme
    proposal = goal.superstate.op_slot.acceptable_wmes.get(vkey(wme.value))
    return wme if proposal is None else proposal


def remember_source(agent: AgentState, wme: WME, slot: Slot, types: tuple[str, ...]) -> None:
    """Note which instantiation made a substate WME, for backtracing after that
    instantiation has retracted (the kernel keeps it through ``wme->preference``)."""
    key = vkey(wme.value)
    for ptype in types:
        for pref in slot.of_type(ptype):
            if vkey(pref.value) == key:
                agent._sources[wme] = pref.inst
                return


def _current_supports(agent: AgentState, wme: WME) -> list[Instantiation]:
    """The rule instantiations whose acceptable (or require) preferences hold ``wme``'s
    value in its slot now: what the kernel's GDS elaboration follows."""
    slot = agent._slot(wme.id, wme.attr, create=False)
    if slot is None:
        return []
    key = vkey(wme.value)
    return [pref.inst for ptype in (ACCEPTABLE, REQUIRE) for pref in slot.of_type(ptype)
            if vkey(pref.value) == key and not pref.inst.is_justification]


def _supporting_instantiations(agent: AgentState, wme: WME) -> list[Instantiation]:
    """The instantiation a justification backtraces ``wme`` through: the one that
    made it (kept after it retracted), else the first that supports it now."""
    source = agent._sources.get(wme)
    if source is not None:
        return [] if source.is_justification else [source]
    return _current_supports(agent, wme)[:1]


_ITEM_ATTRS = frozenset(("item", "non-numeric"))


def _proposes_on_a_state(prefs: list[Preference], goal: Identifier) -> bool:
    """Whether the preferences propose an operator on the justification's match goal:
    the kernel gives a justification that does i-support, as it does a rule's match
    (measured in soar_sml: a substate rule testing its selected operator that proposes an
    operator on the superstate makes '+ (S1 ^operator O3 +) (justify1)', without ':O';
    a result that links the substate itself, with its proposal, keeps
    '+ (S2 ^operator O2 +  :O ) (justify1)')."""
    return any(
        pref.type == ACCEPTABLE and pref.attr == "operator" and pref.id is goal
        for pref in prefs
    )


class JustificationMatch:
    """A stand-in for the match of a new justification (see _justification_matches)."""

    __slots__ = ("level",)

    def __init__(self, level: int) -> None:
        self.level = level
