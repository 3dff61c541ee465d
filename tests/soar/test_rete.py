"""Unit tests of the matchers: every kind of test, negations, incremental changes, excise,
semantic checks.  Semantics tests run on both the Rete and the brute-force oracle; the
expected results of the relational corners were read off the real kernel (soar_sml 9.6.5).
"""

from __future__ import annotations

import pytest

from sann.soar.errors import SoarSemanticError
from sann.soar.matching.matches import Match
from sann.soar.matching.oracle import BruteForceMatcher
from sann.soar.matching.rete import Rete
from sann.soar.matching.symbols import symbol_order_less
from sann.soar.memory import WME, Identifier, IdentifierFactory
from sann.soar.parsing.parser import parse_production
from sann.soar.production import Condition, Const, Production, Var

MATCHERS = [Rete, BruteForceMatcher]


class World:
    """A matcher, a top state S1 and helpers to add and remove WMEs."""

    def __init__(self, matcher_class: type) -> None:
        self.m = matcher_class()
        self.ids = IdentifierFactory()
        self.s1 = Identifier("S", 1, level=1)
        self.timetag = 0

    def new(self, letter: str = "B") -> Identifier:
        return self.ids.new(letter)

    def add(self, ident: Identifier, attr: object, value: object,
            acceptable: bool = False) -> WME:
        self.timetag += 1
        wme = WME(ident, attr, value, self.timetag, acceptable)  # type: ignore[arg-type]
        self.m.add_wme(wme)
        return wme

    def rule(self, text: str, name: str = "r") -> Production:
        production = parse_production(f"sp {{{name} {text} --> (write |x|)}}")
        self.m.add_production(production)
        return production

    def bindings(self, name: str = "r") -> list[dict[str, object]]:
        """Current matches as binding dicts, sorted for comparison."""
        return sorted((m.bindings for m in self.m.matches(name)), key=repr)

    def values(self, name: str, var: str) -> list[object]:
        return sorted((m.bindings[var] for m in self.m.matches(name)), key=repr)


@pytest.fixture(params=MATCHERS, ids=["rete", "brute"])
def world(request: pytest.FixtureRequest) -> World:
    return World(request.param)


# ----- constants and symbol types -------------------------------------------------------------


def test_constant_equality_distinguishes_int_float_and_string(world: World) -> None:
    for value in (1, 1.0, "1", 2):
        world.add(world.s1, "n", value)
    world.rule("(state <s> ^n {<v> 1})", "int")
    world.rule("(state <s> ^n {<v> 1.0})", "float")
    world.rule("(state <s> ^n {<v> |1|})", "string")
    assert [type(v) for v in world.values("int", "v")] == [int]
    assert [type(v) for v in world.values("float", "v")] == [float]
    assert [type(v) for v in world.values("string", "v")] == [str]


def test_variable_equality_is_symbol_equality(world: World) -> None:
    world.add(world.s1, "a", 1)
    world.add(world.s1, "b", 1.0)
    world.add(world.s1, "c", 1)
    world.rule("(state <s> ^a <x> ^<attr> <x>)")
    assert sorted(b["attr"] for b in world.bindings()) == ["a", "c"]


def test_variable_attribute_binds(world: World) -> None:
    world.add(world.s1, "color", "red")
    world.add(world.s1, "shade", "red")
    world.add(world.s1, "size", 3)
    world.rule("(state <s> ^<a> red)")
    assert sorted(b["a"] for b in world.bindings()) == ["color", "shade"]


def test_a_disjunction_matches_only_its_listed_values(world: World) -> None:
    for value in ("red", "blue", "green", 1.0):
        world.add(world.s1, "color", value)
    world.rule("(state <s> ^color {<c> << red green 1 >>})")
    assert world.values("r", "c") == ["green", "red"]


def test_conjunction_binds_and_tests(world: World) -> None:
    for value in (1, 5, 9):
        world.add(world.s1, "n", value)
    world.rule("(state <s> ^n {<x> > 2 < 9 <> 7})")
    assert world.values("r", "x") == [5]


# ----- relational tests -----------------------------------------------------------------------


def test_relations_between_variables_as_the_kernel_runs_them(world: World) -> None:
    """A test runs on the tested WME's value against the bound value: numbers with numbers
    (int and float alike), and between kinds ``<`` and ``<=`` hold, ``>`` and ``>=`` do
    not, as against a constant. (The agent first moves a test on a variable the kernel's
    order binds later into that variable's condition, inverted: test_decision_counts_and_traces.)"""
    other = world.new("A")
    world.add(world.s1, "base", 5)
    for value in (3, 5, 7.5, "abc", other):
        world.add(world.s1, "v", value)
    for name, op in [("lt", "<"), ("le", "<="), ("gt", ">"), ("ge", ">=")]:
        world.rule(f"(state <s> ^base <b> ^v {{<x> {op} <b>}})", name)
    assert world.values("lt", "x") == ["abc", 3, other]
    assert world.values("le", "x") == ["abc", 3, 5, other]
    assert world.values("gt", "x") == [7.5]
    assert world.values("ge", "x") == [5, 7.5]


def test_relations_against_constants_follow_the_kernel(world: World) -> None:
    for value in (5, 2.5, "abc", "10"):
        world.add(world.s1, "v", value)
    world.rule("(state <s> ^v {<x> < 5})", "lt")
    world.rule("(state <s> ^v {<x> > 1})", "gt")
    world.rule("(state <s> ^v {<x> < zzz})", "lt-string")
    # against a constant of another kind, < holds and > fails (soar_sml 9.6.5)
    assert world.values("lt", "x") == ["10", "abc", 2.5]
    assert world.values("gt", "x") == [2.5, 5]
    assert world.values("lt-string", "x") == ["10", "abc", 2.5, 5]


def test_not_equal_and_same_type(world: World) -> None:
    for value in (1, 1.0, "1", 2):
        world.add(world.s1, "v", value)
    world.add(world.s1, "one", 1)
    world.rule("(state <s> ^one <o> ^v {<x> <> <o>})", "ne")
    world.rule("(state <s> ^one <o> ^v {<x> <=> <o>})", "same")
    world.rule("(state <s> ^v {<x> <=> 2.5})", "same-const")
    assert world.values("ne", "x") == ["1", 1.0, 2]
    assert world.values("same", "x") == [1, 2]
    assert world.values("same-const", "x") == [1.0]


def test_an_unlinked_identifier_fails_at_and_passes_not_at(world: World) -> None:
    world.add(world.s1, "v", world.new("L"))
    world.rule("(state <s> ^v {<x> @ <s>})", "at")
    world.rule("(state <s> ^v {<x> !@ <s>})", "not-at")
    assert world.m.matches("at") == []
    assert len(world.m.matches("not-at")) == 1


def test_relational_on_a_variable_bound_later(world: World) -> None:
    """The operand is bound by a condition written after (and joined after) the test."""
    block = world.new()
    world.add(world.s1, "block", block)
    world.add(block, "size", 4)
    world.add(world.s1, "limit", 3)
    world.add(world.s1, "limit", 6)
    world.rule("(state <s> ^block <b>) (<b> ^size {<z> > <lim>}) (<s> ^limit <lim>)")
    assert world.values("r", "lim") == [3]


# ----- acceptable, states ---------------------------------------------------------------------


def test_acceptable_preference_test(world: World) -> None:
    o1, o2 = world.new("O"), world.new("O")
    world.add(world.s1, "operator", o1, acceptable=True)
    world.add(world.s1, "operator", o2, acceptable=True)
    world.add(world.s1, "operator", o1)
    world.rule("(state <s> ^operator <o> +)", "proposed")
    world.rule("(state <s> ^operator <o>)", "selected")
    assert world.values("proposed", "o") == sorted([o1, o2], key=repr)
    assert world.values("selected", "o") == [o1]


def test_state_test_requires_a_state(world: World) -> None:
    thing = world.new("T")
    s2 = Identifier("S", 2, level=2)
    world.add(thing, "name", "x")
    world.add(s2, "name", "x")
    world.add(world.s1, "name", "x")
    world.rule("(state <s> ^name x)", "state")
    world.rule("(impasse <s> ^name x)", "impasse")
    assert world.values("state", "s") == sorted([world.s1, s2], key=repr)
    assert world.values("impasse", "s") == sorted([world.s1, s2], key=repr)


def test_second_state_condition_joins_on_superstate(world: World) -> None:
    s2 = Identifier("S", 2, level=2)
    world.add(s2, "superstate", world.s1)
    world.add(world.s1, "name", "top")
    world.rule("(state <ss> ^superstate <s>) (state <s> ^name top)")
    assert world.bindings() == [{"s": world.s1, "ss": s2}]


# ----- negations ------------------------------------------------------------------------------


def test_negated_condition_blocks_and_unblocks(world: World) -> None:
    block = world.new()
    world.add(world.s1, "block", block)
    world.rule("(state <s> ^block <b>) -(<b> ^on <any>)")
    assert len(world.m.matches("r")) == 1
    on = world.add(block, "on", "table")
    assert world.m.matches("r") == []
    world.m.remove_wme(on)
    assert world.bindings() == [{"b": block, "s": world.s1}]


def test_negation_local_variable_is_existential(world: World) -> None:
    a, b = world.new(), world.new()
    world.add(world.s1, "block", a)
    world.add(world.s1, "block", b)
    world.add(a, "on", b)
    world.rule("(state <s> ^block <x>) -(<x> ^on <y>) -(<s> ^missing <y>)")
    # <y> is local to each negation: a rests on something, b does not
    assert world.values("r", "x") == [b]


def test_negation_with_relational_to_bound_variable(world: World) -> None:
    a, b = world.new(), world.new()
    for block, size in ((a, 3), (b, 5)):
        world.add(world.s1, "block", block)
        world.add(block, "size", size)
    world.rule("(state <s> ^block <x>) (<x> ^size <z>) -(<s> ^block.size > <z>)")
    assert world.values("r", "x") == [b]  # the largest block


def test_conjunctive_negation(world: World) -> None:
    a, b, c = world.new(), world.new(), world.new()
    for block in (a, b, c):
        world.add(world.s1, "block", block)
    world.add(a, "on", b)
    world.add(b, "on", c)
    color = world.add(a, "color", "red")
    # blocks with no red block on them
    world.rule("(state <s> ^block <x>) -{(<s> ^block <y>) (<y> ^on <x>) (<y> ^color red)}")
    assert world.values("r", "x") == sorted([a, c], key=repr)
    world.m.remove_wme(color)
    assert world.values("r", "x") == sorted([a, b, c], key=repr)


def test_nested_conjunctive_negation(world: World) -> None:
    """Blocks whose every supporter is red: no supporter exists that is not red."""
    a, b, c = world.new(), world.new(), world.new()
    for block in (a, b, c):
        world.add(world.s1, "block", block)
    world.add(a, "on", b)
    world.add(a, "on", c)
    world.add(b, "color", "red")
    c_red = world.add(c, "color", "blue")
    world.rule("(state <s> ^block <x>) -{(<x> ^on <y>) -(<y> ^color red)}")
    assert world.values("r", "x") == sorted([b, c], key=repr)
    world.m.remove_wme(c_red)
    world.add(c, "color", "red")
    assert world.values("r", "x") == sorted([a, b, c], key=repr)


def test_ncc_shares_variables_with_positive_conditions(world: World) -> None:
    a, b = world.new(), world.new()
    world.add(world.s1, "block", a)
    world.add(world.s1, "block", b)
    world.add(world.s1, "target", a)
    world.add(world.s1, "held", b)
    world.rule("(state <s> ^block <x> ^target <t>) -{(<s> ^held <x>) (<s> ^target <> <x>)}")
    # b is held and is not the target; a is the target
    assert world.values("r", "x") == [a]


def test_ncc_top_of_pile_follows_moves(world: World) -> None:
    """The Towers-of-Hanoi pattern: a disk is free while no smaller disk is on its peg.  Moves
    change the witnesses of blocked disks (the query NCC re-runs its search) and block free
    ones (a WME arriving in an inner memory)."""
    disks = {size: world.new("D") for size in (1, 2, 3)}
    on = {size: world.add(disks[size], "on", "a") for size in disks}
    for size, disk in disks.items():
        world.add(world.s1, "disk", disk)
        world.add(disk, "size", size)
    world.rule("(state <s> ^disk <d>) (<d> ^size <k> ^on <p>)"
               " -{(<s> ^disk <o>) (<o> ^on <p> ^size < <k>)}")
    assert world.values("r", "d") == [disks[1]]

    def move(size: int, peg: str) -> None:
        world.m.remove_wme(on[size])
        on[size] = world.add(disks[size], "on", peg)

    move(1, "c")
    assert world.values("r", "d") == sorted([disks[1], disks[2]], key=repr)
    move(2, "b")
    assert world.values("r", "d") == sorted(disks.values(), key=repr)
    move(1, "b")  # now 1 blocks 2 on peg b
    assert world.values("r", "d") == sorted([disks[1], disks[3]], key=repr)
    move(3, "c")
    move(1, "a")
    assert world.values("r", "d") == sorted(disks.values(), key=repr)


def test_ncc_inner_negation_invalidates_and_restores_witnesses(world: World) -> None:
    """A blocker counts only while it is not removed: adding ``^removed`` kills the witness,
    removing it brings the blocker back; a second blocker keeps the target blocked."""
    target, top, other = world.new(), world.new(), world.new()
    for block, name, below in ((target, "t", "table"), (top, "u", "t"), (other, "v", "t")):
        world.add(world.s1, "block", block)
        world.add(block, "name", name)
        world.add(block, "on", below)
    world.rule("(state <s> ^block <b>) (<b> ^name <n>)"
               " -{(<s> ^block <a>) (<a> ^on <n> ^name <m>) -(<s> ^removed <m>)}")
    assert world.values("r", "n") == ["u", "v"]
    gone_u = world.add(world.s1, "removed", "u")
    assert world.values("r", "n") == ["u", "v"]  # v still blocks t
    gone_v = world.add(world.s1, "removed", "v")
    assert world.values("r", "n") == ["t", "u", "v"]
    world.m.remove_wme(gone_u)
    assert world.values("r", "n") == ["u", "v"]
    world.m.remove_wme(gone_v)
    world.add(world.s1, "removed", "u")
    assert world.values("r", "n") == ["u", "v"]


@pytest.mark.parametrize("order", [("name", "on", "block"), ("on", "block", "name"),
                                   ("block", "name", "on")])
def test_ncc_blocks_whatever_order_its_inner_wmes_arrive_in(world: World, order) -> None:
    """A conjunctive negation's inner match completes with whichever WME comes last: one
    arriving before the WMEs it joins with is rejected by the Rete's semi-join filter
    (no inner WME shares its value), the last one is tried against the owners."""
    target, above = world.new(), world.new()
    world.add(world.s1, "block", target)
    world.add(target, "name", "t")
    world.add(target, "on", "table")
    world.rule("(state <s> ^block <b>) (<b> ^name <n>)"
               " -{(<s> ^block <a>) (<a> ^on <n> ^name <m>)}")
    wmes = {"name": (above, "name", "u"), "on": (above, "on", "t"),
            "block": (world.s1, "block", above)}
    for attr in order:
        assert "t" in world.values("r", "n"), f"blocked before {attr} arrived"
        world.add(*wmes[attr])
    assert world.values("r", "n") == ["u"]


def test_runs_match_in_any_arrival_order(world: World) -> None:
    """Consecutive independent tests (one node in the Rete) give one match per combination
    of WMEs, whichever arrives first, and lose it when any of them goes."""
    a, b = world.new(), world.new()
    world.rule("(state <s> ^pair <p>) (<p> ^left <a> ^right <b>)"
               " (<a> ^x <xa>) (<b> ^x > <xa>) (<b> ^y < <xa>) (<a> ^tag <t>) (<b> ^tag <t>)")
    pair = world.new("P")
    world.add(world.s1, "pair", pair)
    world.add(pair, "left", a)
    world.add(pair, "right", b)
    world.add(a, "x", 5)
    b_y = world.add(b, "y", 1)
    world.add(a, "tag", "red")
    assert world.bindings() == []
    world.add(b, "tag", "red")
    b_x = world.add(b, "x", 7)
    assert len(world.m.matches("r")) == 1
    world.add(b, "y", 2)  # a second WME passing one filter: a second combination
    assert len(world.m.matches("r")) == 2
    world.m.remove_wme(b_y)
    assert len(world.m.matches("r")) == 1
    world.m.remove_wme(b_x)
    assert world.bindings() == []
    world.add(b, "x", 4)  # fails ^x > 5
    assert world.bindings() == []


def test_run_nodes_are_shared_and_removed() -> None:
    rete = Rete()
    text = "(state <s> ^block <b>) (<b> ^size 2) (<b> ^color red) (<s> ^mode go)"
    rete.add_production(parse_production(f"sp {{one {text} --> (write x)}}"))
    rete.take_changes()  # builds the network
    alone = _node_count(rete)
    rete.add_production(parse_production(f"sp {{two {text} --> (write y)}}"))
    rete.take_changes()
    assert _node_count(rete) == alone + 1  # only a production node
    s1, b = Identifier("S", 1, level=1), Identifier("B", 1)
    for t, wme in enumerate([(s1, "block", b), (b, "size", 2), (b, "color", "red"),
                             (s1, "mode", "go")]):
        rete.add_wme(WME(*wme, t))  # type: ignore[arg-type]
    runs = [n for n in _nodes(rete) if type(n).__name__ == "RunNode"]
    assert runs and len(rete.matches("one")) == len(rete.matches("two")) == 1
    (match,) = rete.matches("one")
    assert [w.attr for w in match.wmes] == ["block", "size", "color", "mode"]
    rete.excise("one")
    rete.excise("two")
    assert _node_count(rete) == 1 and rete._amems == {}
    assert all(info[0] == [] and not info[1] for info in rete._wme_info.values())


def test_query_ncc_cleans_up_on_excise() -> None:
    rete = Rete()
    s1 = Identifier("S", 1, level=1)
    b = Identifier("B", 1)
    rete.add_wme(WME(s1, "block", b, 1))
    rete.add_wme(WME(b, "size", 3, 2))
    rete.add_production(parse_production(
        "sp {q (state <s> ^block <b>) -{(<s> ^block <o>) (<o> ^size > 2)} --> (write x)}"))
    assert rete.matches("q") == []
    rete.excise("q")
    assert _node_count(rete) == 1 and rete._amems == {}
    assert all(info[0] == [] and not info[3] for info in rete._wme_info.values())


# ----- incremental behaviour ------------------------------------------------------------------


def test_take_changes_reports_appear_and_retract_pairs(world: World) -> None:
    block = world.new()
    world.rule("(state <s> ^block <b>) (<b> ^color red)")
    w1 = world.add(world.s1, "block", block)
    w2 = world.add(block, "color", "red")
    added, removed = world.m.take_changes()
    assert removed == [] and len(added) == 1
    match = added[0]
    assert isinstance(match, Match) and match.wmes == (w1, w2)
    assert match.bindings == {"s": world.s1, "b": block}
    world.m.remove_wme(w2)
    added, removed = world.m.take_changes()
    assert added == [] and removed == [match]  # the very same object
    assert world.m.take_changes() == ([], [])


def test_transient_match_is_reported_neither_way(world: World) -> None:
    world.rule("(state <s> ^flag on)")
    world.m.take_changes()
    flag = world.add(world.s1, "flag", "on")
    world.m.remove_wme(flag)
    assert world.m.take_changes() == ([], [])


def _fill_blocks(world: World) -> list[WME]:
    a, b, c = world.new(), world.new(), world.new()
    made = [world.add(world.s1, "block", block) for block in (a, b, c)]
    made += [world.add(a, "on", b), world.add(b, "on", c), world.add(a, "color", "red")]
    return made


def test_clear_wmes_retracts_everything_and_the_network_still_matches(world: World) -> None:
    rules = {
        "on": "(state <s> ^block <x>) (<x> ^on <y>)",
        "bare": "(state <s> ^block <x>) -(<x> ^on <y>)",
        "free": "(state <s> ^block <x>) -{(<s> ^block <y>) (<y> ^on <x>) (<y> ^color red)}",
    }
    for name, text in rules.items():
        world.rule(text, name)
    _fill_blocks(world)
    world.m.take_changes()
    live = {id(m) for name in rules for m in world.m.matches(name)}
    world.m.clear_wmes()
    added, removed = world.m.take_changes()
    assert added == [] and {id(m) for m in removed} == live
    assert all(world.m.matches(name) == [] for name in rules)
    made = _fill_blocks(world)  # new identifiers: the memories must hold no stale token
    fresh = BruteForceMatcher()
    for name, text in rules.items():
        fresh.add_production(parse_production(f"sp {{{name} {text} --> (write |x|)}}"))
    for wme in made:
        fresh.add_wme(wme)
    for name in rules:
        assert world.bindings(name) == sorted((m.bindings for m in fresh.matches(name)), key=repr)
    assert len(world.m.matches("on")) == 2 and len(world.m.matches("free")) == 2


def test_wmes_follow_written_order_with_none_for_negations(world: World) -> None:
    block = world.new()
    world.rule("(state <s> ^name go) -(<s> ^stop yes) (<s> ^block <b>) -{(<b> ^x 1)}")
    w_block = world.add(world.s1, "block", block)
    w_name = world.add(world.s1, "name", "go")
    (match,) = world.m.matches("r")
    assert match.wmes == (w_name, None, w_block, None)


def test_production_added_late_matches_existing_memory(world: World) -> None:
    block = world.new()
    world.add(world.s1, "block", block)
    world.add(block, "on", "table")
    world.rule("(state <s> ^block <b>) (<b> ^on table) -(<b> ^clear no)")
    added, _ = world.m.take_changes()
    assert [m.bindings["b"] for m in added] == [block]


def test_excise_retracts_matches(world: World) -> None:
    world.add(world.s1, "name", "go")
    world.rule("(state <s> ^name go)", "one")
    world.rule("(state <s> ^name go)", "two")
    (match,) = world.m.take_changes()[0][:1]
    world.m.excise(match.production.name)
    assert world.m.take_changes() == ([], [match])
    assert [p.name for p in world.m.productions()] == ["two" if match.production.name ==
                                                       "one" else "one"]
    with pytest.raises(KeyError):
        world.m.excise("one" if match.production.name == "one" else "two")


def test_duplicate_wme_and_unknown_wme_are_errors(world: World) -> None:
    wme = world.add(world.s1, "a", 1)
    with pytest.raises(ValueError):
        world.m.add_wme(wme)
    world.m.remove_wme(wme)
    with pytest.raises(ValueError):
        world.m.remove_wme(wme)


def test_duplicate_production_name_is_an_error(world: World) -> None:
    world.rule("(state <s> ^a 1)")
    with pytest.raises(SoarSemanticError, match="r"):
        world.rule("(state <s> ^b 1)")


# ----- semantic checks ------------------------------------------------------------------------


# What the kernel refuses (measured in soar_sml 9.6; tests/soar/test_load_checks.py
# compares many more shapes with the kernel itself).
@pytest.mark.parametrize("text, message", [
    ("-(state <s> ^a b)", "no positive condition"),
    ("-{(state <s> ^a b) (<s> ^c d)}", "no positive condition"),
    ("(state <s> ^a <x>) -(<s> ^b {<z> > <w>})", "negated relational test > <w>"),
    ("(state <s> ^a <x>) -(<s> ^b {<z> > <z>})", "negated relational test > <z>"),
    ("(state <s> ^a <x>) -{(<s> ^b <y>) -(<y> ^c {> <q>})}", "negated relational test > <q>"),
])
def test_semantic_errors_name_the_production(world: World, text: str, message: str) -> None:
    with pytest.raises(SoarSemanticError, match=message) as info:
        world.rule(text, "bad*rule")
    assert "bad*rule" in str(info.value)
    assert world.m.productions() == []


@pytest.mark.filterwarnings("ignore::sann.soar.errors.SoarWarning")
@pytest.mark.parametrize("text", [
    "(state <s> ^a <x>) -(<s> ^b <z>)",  # a variable only in a negation is local
    "(state <s> ^a <x>) -(<s> ^b {<z> > <x>})",
    "(state <s> ^a {<x> > <y>}) (<x> ^b <y>)",  # bound later, by a linked condition
    "(state <s> ^a <x>) (state <t> ^superstate <s>)",
    "(state <s> ^a <x>) (state <t> ^b <x>)",
    # the kernel loads these (with a warning when a condition is not linked to a state)
    "(<s> ^a b)",
    "(state <s> -^a.b <x> ^c yes)",
    "(state <s> ^a <x>) (<y> ^b <x>)",
    "(state <s> ^a <x>) -(<y> ^b c)",
    "(state <s> ^a <x>) -{(<y> ^b <x>) (<y> ^c d)}",
    "(state <s> ^<a> x) (<a> ^b c)",
    # and drops a relational test of a positive condition on a variable nothing binds
    "(state <s> ^a {> <y>})",
    "(state <s> ^a <x>) -{(<s> ^b <y>) (<y> ^c {> <q>})}",
])
def test_accepted_productions(world: World, text: str) -> None:
    world.rule(text)
    assert [p.name for p in world.m.productions()] == ["r"]


@pytest.mark.parametrize("matcher", MATCHERS, ids=["rete", "brute"])
@pytest.mark.parametrize("text", [
    "(<s> ^a b)",
    "(state <s> ^a <x>) (<y> ^b <x>)",
    "(state <s> ^a <x>) -(<y> ^b c)",
    "(state <s> ^a <x>) -{(<y> ^b <x>) (<y> ^c d)}",
    "(state <s> ^<a> x) (<a> ^b c)",
])
@pytest.mark.filterwarnings("ignore::sann.soar.errors.SoarWarning")
def test_links_can_be_required(matcher: type, text: str) -> None:
    world = World(lambda: matcher(check_links=True))  # type: ignore[arg-type]
    with pytest.raises(SoarSemanticError, match="not linked to a state"):
        world.rule(text, "bad*rule")


def test_a_relational_test_on_an_unbound_variable_is_dropped(world: World) -> None:
    # As in the kernel: the test is gone, the condition matches any value.
    world.add(world.s1, "a", 1)
    world.add(world.s1, "a", "x")
    production = world.rule("(state <s> ^a {< <nothing> <v>})")
    assert production.conditions == parse_production(
        "sp {r (state <s> ^a <v>) --> (write |x|)}").conditions
    assert sorted(map(str, world.values("r", "v"))) == ["1", "x"]


def test_a_hand_built_relational_test_on_an_unbound_variable_is_refused(world: World) -> None:
    production = parse_production("sp {r (state <s> ^a {< <y> <v>}) (<s> ^b <y>) --> (write |x|)}")
    first, _ = production.conditions
    lone = Production("lone", (first,), production.actions)
    with pytest.raises(SoarSemanticError, match="<y> in a relational test"):
        world.m.add_production(lone)


@pytest.mark.parametrize("matcher", MATCHERS, ids=["rete", "brute"])
@pytest.mark.filterwarnings("ignore::sann.soar.errors.SoarWarning")
def test_unlinked_conditions_are_joined(matcher: type) -> None:
    world = World(matcher)
    parent, child = world.new("P"), world.new("C")
    world.add(world.s1, "child", child)
    world.add(parent, "kid", child)
    world.add(child, "kid", "x")
    world.rule("(state <s> ^child <c>) (<p> ^kid <c>)")
    world.rule("(<p> ^kid <k>) -(<q> ^kid <p>)", "roots")
    assert world.values("r", "p") == [parent]
    assert world.values("roots", "p") == [parent]


# ----- Rete structure -------------------------------------------------------------------------


def _nodes(rete: Rete) -> list:
    found, stack = [], [rete._root]
    while stack:
        node = stack.pop()
        found.append(node)
        stack.extend(node.children)
    return found


def _node_count(rete: Rete) -> int:
    return len(_nodes(rete))


def test_shared_prefix_and_alpha_memories() -> None:
    rete = Rete()
    rete.add_production(parse_production(
        "sp {one (state <s> ^name go ^block <b>) (<b> ^on table) --> (write x)}"))
    rete.take_changes()  # builds the network of the productions added so far
    alone = _node_count(rete)
    amems = len(rete._amems)
    rete.add_production(parse_production(
        "sp {two (state <s> ^name go ^block <b>) (<b> ^on table) (<b> ^color red) --> "
        "(write x)}"))
    rete.take_changes()
    assert _node_count(rete) == alone + 2  # one join and one production node
    assert len(rete._amems) == amems + 1
    rete.excise("two")
    assert _node_count(rete) == alone and len(rete._amems) == amems
    rete.excise("one")
    assert _node_count(rete) == 1 and rete._amems == {}


def test_excise_cleans_up_ncc_subnetworks() -> None:
    rete = Rete()
    s1 = Identifier("S", 1, level=1)
    rete.add_wme(WME(s1, "block", Identifier("B", 1), 1))
    rete.add_production(parse_production(
        "sp {ncc (state <s> ^block <b>) -{(<s> ^held <b>) (<b> ^size > 2)} --> (write x)}"))
    rete.excise("ncc")
    assert _node_count(rete) == 1 and rete._amems == {}
    assert all(info[0] == [] for info in rete._wme_info.values())


def test_removing_a_wme_touches_only_its_tokens() -> None:
    """Adding and removing a WME leaves every other token in place (tree-based removal)."""
    rete = Rete()
    rete.add_production(parse_production(
        "sp {r (state <s> ^block <b>) (<b> ^on <o>) --> (write x)}"))
    s1 = Identifier("S", 1, level=1)
    ids = IdentifierFactory()
    for n in range(50):
        block = ids.new("B")
        rete.add_wme(WME(s1, "block", block, 2 * n))
        rete.add_wme(WME(block, "on", "table", 2 * n + 1))
    before = {id(m) for m in rete.matches("r")}
    extra = ids.new("B")
    wme = WME(s1, "block", extra, 1000)
    on = WME(extra, "on", "table", 1001)
    rete.add_wme(wme)
    rete.add_wme(on)
    assert len(rete.matches("r")) == 51
    rete.remove_wme(wme)
    assert {id(m) for m in rete.matches("r")} == before


def test_symbols_order_identifiers_then_numbers_then_strings() -> None:
    b1, n1, n2 = Identifier("B", 1), Identifier("N", 1), Identifier("N", 2)
    ordered = [b1, n1, n2, -3, 1, 2.5, 10, "10", "abc"]
    for i, a in enumerate(ordered):
        for b in ordered[i + 1:]:
            assert symbol_order_less(a, b) and not symbol_order_less(b, a)


def test_productions_built_from_dataclasses() -> None:
    """The matcher needs no parser: productions are plain dataclasses."""
    rete = Rete()
    s1 = Identifier("S", 1, level=1)
    production = Production("p", (Condition(Var("s"), Const("a"), Var("x"), goal="state"),), ())
    rete.add_production(production)
    rete.add_wme(WME(s1, "a", 1, 1))
    assert [m.bindings for m in rete.matches("p")] == [{"s": s1, "x": 1}]


def test_volatile_checks_join_last() -> None:
    """A check of an attribute that some rule removes is joined after the stable ones, so
    that its changes rebuild few tokens; the order does not change the matches."""
    rete = Rete()
    rete.add_production(parse_production(
        "sp {use (state <s> ^flag on ^name go ^block <b>) (<b> ^size 1) --> (write x)}"))
    rete.add_production(parse_production(
        "sp {flip (state <s> ^flag on) --> (<s> ^flag on - off)}"))
    s1, block = Identifier("S", 1, level=1), Identifier("B", 1)
    flag = WME(s1, "flag", "on", 1)
    for wme in (flag, WME(s1, "name", "go", 2), WME(s1, "block", block, 3),
                WME(block, "size", 1, 4)):
        rete.add_wme(wme)
    (match,) = rete.matches("use")
    assert match.wmes[0] is flag
    pnode = rete._pnodes["use"]
    assert pnode.layout.levels[0][-1] == 0  # the ^flag check is joined last
    rete.remove_wme(flag)
    assert rete.matches("use") == []


def test_rebuild_after_an_attribute_turns_volatile_keeps_matches() -> None:
    rete = Rete()
    s1, block = Identifier("S", 1, level=1), Identifier("B", 1)
    for wme in (WME(s1, "flag", "on", 1), WME(s1, "block", block, 2), WME(block, "size", 1, 3)):
        rete.add_wme(wme)
    rete.add_production(parse_production(
        "sp {use (state <s> ^flag on ^block <b>) (<b> ^size 1) --> (write x)}"))
    (match,) = rete.take_changes()[0]
    assert rete._pnodes["use"].layout.levels[-1][0] == 0  # ^flag is not known to change yet
    rete.add_production(parse_production(
        "sp {flip (state <s> ^flag on) --> (<s> ^flag on - off)}"))
    added, removed = rete.take_changes()
    assert removed == [] and [m.production.name for m in added] == ["flip"]
    assert rete._pnodes["use"].layout.levels[0][-1] == 0  # rebuilt: ^flag joins last
    assert rete.matches("use") == [match]
    assert match.bindings == {"s": s1, "b": block}
    (flip,) = rete.matches("flip")
    rete.remove_wme(next(iter(rete._wme_info)))  # the ^flag WME goes: both matches retract
    assert sorted(rete.take_changes()[1], key=id) == sorted([match, flip], key=id)
    assert rete.matches("use") == []
