"""The explanation of a result: the rule firings behind it, walked back as Soar 9.6 does.

Starting from the instantiations that made the results, every positive condition either
tested a superstate WME (a *ground*: it becomes a condition of the chunk) or a local one,
which is explained in turn by the instantiation whose preference made it; the condition's
identities are unified with that action's on the way (see `identity`). Relational tests
met on local WMEs are *constraints* kept on their identity, added to the chunk where the
identity is tested in a ground (measured in soar_sml: ``^val { <v> < 100 }`` on a local
copy of ``(<ss> ^y { <y> > 2 })`` gives the chunk ``^y { <y1> < 100 > 2 }``). Negated
conditions on superstate identifiers are kept; those on local ones are dropped (the
kernel's default ``allow-local-negations on``).
"""

from __future__ import annotations

from collections.abc import Hashable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..decision.results import _current_supports, _item_proposal, _supporting_instantiations
from ..memory import WME, Identifier, Symbol
from ..preferences import (
    ACCEPTABLE,
    BEST,
    BETTER,
    PROHIBIT,
    REJECT,
    REQUIRE,
    WORSE,
    WORST,
    Preference,
    preference_type,
)
from ..production import (
    Condition,
    Conjunction,
    ConjunctiveNegation,
    Const,
    FuncCall,
    MakeAction,
    Production,
    Relational,
    RhsValue,
    Test,
    Var,
)
from .identity import Identities

if TYPE_CHECKING:
    from ..agent import Agent
    from ..goals import Goal
    from ..instantiation import Instantiation

ITEM_ATTRS = ("item", "non-numeric")
FIELDS = ("id_test", "attr_test", "value_test")


class NotExplained(Exception):  # noqa: N818 -- a reason to fall back, not an error
    """The explanation cannot make a chunk (the reason is the message); a justification
    stands in, as in the kernel."""


@dataclass
class Step:
    """One instantiation behind the results: its production, the symbols its variables
    had (those of new identifiers too), and which action made each of its preferences."""

    n: int
    inst: Instantiation
    production: Production
    bindings: dict[str, Symbol]
    actions: dict[int, MakeAction]
    #: the WME each condition matched (None for negations)
    wmes: tuple[WME | None, ...] = ()


@dataclass
class Ground:
    """A superstate WME and every condition (of which step) that tested it."""

    wme: WME
    tests: list[tuple[Condition, Step]] = field(default_factory=list)


@dataclass
class Explanation:
    """What backtracing found, for `build` to turn into a production."""

    #: the instantiation whose firing returned the results (the chunk is named after it)
    fired: Instantiation
    goal: Goal
    level: int
    ids: Identities = field(default_factory=Identities)
    steps: dict[int, Step] = field(default_factory=dict)
    grounds: dict[int, Ground] = field(default_factory=dict)
    negations: list[tuple[Condition | ConjunctiveNegation, Step]] = field(default_factory=list)
    constraints: list[tuple[Hashable, Relational, Step, Symbol]] = field(default_factory=list)
    results: list[tuple[Preference, MakeAction, Step]] = field(default_factory=list)
    local_negations: int = 0
    quiescence: bool = False

    def key(self, step: Step, name: str) -> Hashable:
        """The identity key of a variable of a step."""
        return (step.n, name)


def explain(agent: Agent, fired: Instantiation, results: list[Preference]) -> Explanation:
    """Backtrace ``results`` (returned by the firing of ``fired``) through the rule firings
    behind them."""
    ex = Explanation(fired, fired.goal, fired.goal.level)
    queue: list[Step] = []
    for pref in results:
        if pref.inst is None:  # an o-reject, done with when it was asserted
            continue
        step = _step(agent, ex, pref.inst, queue)
        action = step.actions.get(id(pref))
        if action is None:
            raise NotExplained(f"no action of {pref.inst.name} made {pref}")
        ex.results.append((pref, action, step))
    head = 0
    while head < len(queue):
        _backtrace_step(agent, ex, queue[head], queue)
        head += 1
    return ex


def _step(agent: Agent, ex: Explanation, inst: Instantiation, queue: list[Step]) -> Step:
    step = ex.steps.get(id(inst))
    if step is not None:
        return step
    match = _match_of(agent, inst)
    if match is None:
        raise NotExplained(f"{inst.name} is not a rule firing")
    production: Production = match.production  # type: ignore[attr-defined]
    info = agent._productions.get(production.name)
    if info is not None and len(info.production.conditions) == len(production.conditions):
        # the rule as written: the matcher's copy has relational tests moved where the
        # kernel's Rete runs them (`reorder.with_kernel_relations`), which chunks do not show
        production = info.production
    bindings = dict(match.bindings)  # type: ignore[attr-defined]
    actions = _align(production, inst, bindings)
    step = Step(len(ex.steps), inst, production, bindings, actions,
                match.wmes)  # type: ignore[attr-defined]
    ex.steps[id(inst)] = step
    queue.append(step)
    return step


def _match_of(agent: Agent, inst: Instantiation) -> object | None:
    """The match of a rule firing, or of a chunk's own instantiation (see `Chunker`)."""
    if inst.is_justification:
        return agent.chunker.matches.get(inst)
    return inst.match


def _align(production: Production, inst: Instantiation,
           bindings: dict[str, Symbol]) -> dict[int, MakeAction]:
    """Which make-action made each preference (in the order they were made), binding the
    new identifiers' variables on the way."""
    makes = [a for a in production.actions if isinstance(a, MakeAction)]
    found: dict[int, MakeAction] = {}
    start = 0
    for pref in inst.prefs:
        for j in range(start, len(makes)):
            trial = dict(bindings)
            if _fits_action(makes[j], pref, trial):
                bindings.update(trial)
                found[id(pref)] = makes[j]
                start = j + 1
                break
    return found


def _fits_action(action: MakeAction, pref: Preference, bindings: dict[str, Symbol]) -> bool:
    referent = pref.referent if action.referent is not None else None
    if preference_type(action.preference, referent) != pref.type:
        return False
    pairs = [(action.id, pref.id), (action.attr, pref.attr), (action.value, pref.value)]
    if action.referent is not None:
        pairs.append((action.referent, pref.referent))
    return all(_fits(node, sym, bindings) for node, sym in pairs)


def _fits(node: RhsValue, sym: Symbol | None, bindings: dict[str, Symbol]) -> bool:
    if isinstance(node, Var):
        bound = bindings.get(node.name)
        if bound is None:
            if sym is None:
                return False
            bindings[node.name] = sym
            return True
        return same_symbol(bound, sym)
    if isinstance(node, Const):
        return same_symbol(node.value, sym)
    return True  # a function's value


def same_symbol(a: object, b: object) -> bool:
    if isinstance(a, Identifier) or isinstance(b, Identifier):
        return a is b
    return type(a) is type(b) and a == b


def _backtrace_step(agent: Agent, ex: Explanation, step: Step, queue: list[Step]) -> None:
    wmes = step.wmes
    for k, element in enumerate(step.production.conditions):
        if isinstance(element, ConjunctiveNegation):
            _negation(agent, ex, step, element, _ncc_ids(element, step))
            continue
        if element.negated:
            _negation(agent, ex, step, element, [_bound_id(element, step)])
            continue
        wme = wmes[k]
        if wme is None:
            continue
        if wme.attr == "quiescence" and wme.value == "t":
            ex.quiescence = True
        if wme.attr in ITEM_ATTRS:
            proposal = _item_proposal(agent, wme)
            if proposal is not wme:
                stand_in = _stand_in(step, element, proposal, k)
                ex.ids.union(("state", proposal.id), ex.key(step, f"item*{k}"))
                if agent._level_of(proposal.id) < ex.level:
                    _add_ground(ex, proposal, stand_in, step)
                else:
                    _local(agent, ex, step, stand_in, proposal, queue, k)
                continue
        if agent._level_of(wme.id) < ex.level:
            _add_ground(ex, wme, element, step)
            continue
        _local(agent, ex, step, element, wme, queue, k)


def _stand_in(step: Step, cond: Condition, proposal: WME, k: int) -> Condition:
    """``(S2 ^item O2)`` stands for the superstate's ``(S1 ^operator O2 +)``."""
    name = f"item*{k}"
    step.bindings[name] = proposal.id
    return Condition(Var(name), Const("operator"), cond.value_test, acceptable=True)


def _add_ground(ex: Explanation, wme: WME, cond: Condition, step: Step) -> None:
    cond = _with_equalities(cond, step, wme)
    ground = ex.grounds.get(wme.timetag)
    if ground is None:
        ground = ex.grounds[wme.timetag] = Ground(wme)
    ground.tests.append((cond, step))


def _with_equalities(cond: Condition, step: Step, wme: WME) -> Condition:
    """The condition with a variable in each field that has no equality test, as the
    kernel's parser gives it one (``^cook-time > <k>`` is ``^cook-time { <c*1> > <k> }``):
    so its identity joins those of other conditions on the WME."""
    tests = {}
    for slot, value in zip(FIELDS, (wme.id, wme.attr, wme.value), strict=True):
        test = getattr(cond, slot)
        if equality_var(test) is None and not isinstance(test, Const):
            name = f"eq*{id(cond)}*{slot}"
            step.bindings[name] = value
            parts = test.tests if isinstance(test, Conjunction) else (test,)
            test = Conjunction((Var(name), *parts))
        tests[slot] = test
    return Condition(tests["id_test"], tests["attr_test"], tests["value_test"], cond.negated,
                     cond.acceptable, cond.goal)


def _bound_id(cond: Condition, step: Step) -> Symbol | None:
    test = cond.id_test
    name = equality_var(test)
    return step.bindings.get(name) if name is not None else None


def _ncc_ids(ncc: ConjunctiveNegation, step: Step) -> list[Symbol | None]:
    """The identifiers bound outside that a conjunctive negation tests, nested ones too."""
    ids: list[Symbol | None] = []
    for cond in ncc.conditions:
        if isinstance(cond, ConjunctiveNegation):
            ids.extend(i for i in _ncc_ids(cond, step) if i is not None)
            continue
        ident = _bound_id(cond, step)
        if ident is not None:
            ids.append(ident)
    return ids or [None]


def _negation(agent: Agent, ex: Explanation, step: Step,
              element: Condition | ConjunctiveNegation, ids: list[Symbol | None]) -> None:
    """Kept when every identifier it tests (bound outside it) is a superstate's."""
    if all(isinstance(i, Identifier) and agent._level_of(i) < ex.level for i in ids):
        ex.negations.append((element, step))
    else:
        ex.local_negations += 1


def _local(agent: Agent, ex: Explanation, step: Step, cond: Condition, wme: WME,
           queue: list[Step], k: int) -> None:
    """A local WME: unify the condition with the action that made it, and explain that
    action's instantiation in turn."""
    keys = [_field_key(ex, step, getattr(cond, name), f"{k}{name}") for name in FIELDS]
    values = (wme.id, wme.attr, wme.value)
    for key, name, value in zip(keys, FIELDS, values, strict=True):
        for rel in _relationals(getattr(cond, name)):
            ex.constraints.append((key, rel, step, value))
    sources = _supporting_instantiations(agent, wme)
    if not sources:  # made by the architecture: nothing behind it
        if wme.attr == "superstate" and isinstance(wme.value, Identifier):
            # but every rule that reaches the superstate this way reaches one identity
            # (measured in soar_sml: ``^superstate <ss>`` and ``^superstate <ss2>`` of two
            # rules make one ``<s1>``, while a ``^top-state`` value stays its own)
            ex.ids.union(("state", wme.value), keys[2])
        return
    source = sources[0]
    pref = _pref_of(source, wme)
    if (pref is None or not pref.live) and agent._wm.get(wme.timetag) is wme:
        # its preference went while another kept the WME: the kernel moves the WME's
        # preference to that one, for the firings matched after the move (measured in
        # soar_sml: a count rewritten to the same value by a function is backtraced through
        # the function, and its arguments literalized, by the rules that tested it later)
        moved = _moved_support(agent, wme, step)
        if moved is not None:
            source, pref = moved
    if pref is None or _match_of(agent, source) is None:
        return
    maker = _step(agent, ex, source, queue)
    action = maker.actions.get(id(pref))
    if action is None:
        return
    for key, test, node in zip(keys, (cond.id_test, cond.attr_test, cond.value_test),
                               (action.id, action.attr, action.value), strict=True):
        _unify(ex, key, test, maker, node)
    if wme.attr == "operator" and not wme.acceptable:
        _selection_knowledge(agent, ex, wme, queue)


#: the preferences that choose among operators (the kernel's ``add-osk``, on by default)
SELECTION = (REJECT, PROHIBIT, REQUIRE, BEST, WORST, BETTER, WORSE)


def _selection_knowledge(agent: Agent, ex: Explanation, wme: WME, queue: list[Step]) -> None:
    """A selected operator of a substate is explained by the preferences that chose it too,
    as they were when it was chosen (measured in soar_sml: a look-ahead's chunk tests the
    ``^visited`` records that the reject chunks firing in the copied state tested,
    rejecting the other operators)."""
    for inst in agent.chunker.selection.get(wme, ()):
        if _match_of(agent, inst) is not None:
            _step(agent, ex, inst, queue)


def _moved_support(agent: Agent, wme: WME, step: Step) -> tuple[Instantiation, Preference] | None:
    """The live preference that holds ``wme`` now, when its instantiation fired before
    ``step`` matched (its newest WME is older than the step's newest)."""
    newest = max((w.timetag for w in step.wmes if w is not None), default=0)
    for other in _current_supports(agent, wme):
        if other is step.inst:
            continue
        match = _match_of(agent, other)
        found = _pref_of(other, wme)
        if match is None or found is None or not found.live:
            continue
        if max((w.timetag for w in match.wmes if w is not None),  # type: ignore[attr-defined]
               default=0) < newest:
            return other, found
    return None


def _field_key(ex: Explanation, step: Step, test: Test, tag: str) -> Hashable:
    name = equality_var(test)
    if name is None:
        return (step.n, f"*{tag}")
    return ex.key(step, name)


def _unify(ex: Explanation, key: Hashable, test: Test, maker: Step, node: RhsValue) -> None:
    ids = ex.ids
    if isinstance(node, Var):
        made = ex.key(maker, node.name)
        if isinstance(test, Const):
            ids.literalize(made)
        else:
            ids.union(key, made)
    elif isinstance(node, FuncCall):
        ids.literalize(key)
        for name in _call_vars(node):
            ids.literalize(ex.key(maker, name))
    else:
        ids.literalize(key)


def _call_vars(call: FuncCall) -> Iterator[str]:
    for arg in call.args:
        if isinstance(arg, Var):
            yield arg.name
        elif isinstance(arg, FuncCall):
            yield from _call_vars(arg)


def _pref_of(source: Instantiation, wme: WME) -> Preference | None:
    for pref in source.prefs:
        if (pref.id is wme.id and pref.type in (ACCEPTABLE, REQUIRE)
                and same_symbol(pref.attr, wme.attr) and same_symbol(pref.value, wme.value)):
            return pref
    return None


def equality_var(test: Test) -> str | None:
    """The variable a test binds (``<x>`` or ``{ <x> > 3 }``), if any."""
    if isinstance(test, Var):
        return test.name
    if isinstance(test, Conjunction):
        for part in test.tests:
            if isinstance(part, Var):
                return part.name
    return None


def _relationals(test: Test) -> list[Relational]:
    if isinstance(test, Relational):
        return [test]
    if isinstance(test, Conjunction):
        return [part for part in test.tests if isinstance(part, Relational)]
    return []
