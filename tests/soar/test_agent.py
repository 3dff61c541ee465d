"""The agent's decision cycle, support, retraction, stats, trace and print."""

from __future__ import annotations

import io

import pytest

from sann.soar import Agent, SoarRuntimeError, SoarSyntaxError
from sann.soar.matching.oracle import BruteForceMatcher

COUNTER = """
sp {propose*init
   (state <s> ^superstate nil -^name)
-->
   (<s> ^operator <o> +)
   (<o> ^name init)}
sp {apply*init
   (state <s> ^operator <o>)
   (<o> ^name init)
-->
   (<s> ^name count ^count 0)}
sp {propose*count
   (state <s> ^name count ^count <c> < 3)
-->
   (<s> ^operator <o> + =)
   (<o> ^name inc)}
sp {apply*count
   (state <s> ^operator <o> ^count <c>)
   (<o> ^name inc)
-->
   (<s> ^count <c> - (+ <c> 1))
   (write |count | <c> (crlf))}
sp {elab
   (state <s> ^count <c>)
-->
   (<s> ^double (* <c> 2))}
sp {propose*halt
   (state <s> ^count 3)
-->
   (<s> ^operator <o> +)
   (<o> ^name stop)}
sp {apply*halt
   (state <s> ^operator.name stop)
-->
   (halt)}
"""


def make(rules: str = "", **kwargs) -> tuple[Agent, io.StringIO]:
    out = io.StringIO()
    agent = Agent(out=out, **kwargs)
    if rules:
        agent.load(rules)
    return agent, out


def values(agent: Agent, ident: str, attr: str) -> list:
    return sorted(
        (w.value for w in agent.wmes() if w.id.name == ident and w.attr == attr),
        key=str,
    )


def test_top_state_prints_like_the_kernel() -> None:
    """Texts of soar_sml 9.6: a new agent's printer starts as if 17 characters were on the
    line, so its first print wraps before ^type; the next starts on a fresh line."""
    agent, _ = make()
    linked = (
        "  (E1 ^command C1 ^present-id 1 ^result R2)\n"
        "  (I1 ^input-link I2 ^output-link I3)\n"
        "  (L1 ^command C2 ^result R3)\n"
    )
    assert agent.print("S1", 3) == (
        "(S1 ^epmem E1 ^io I1 ^reward-link R1 ^smem L1 ^superstate nil\n"
        "       ^type state)\n" + linked
    )
    assert agent.print("S1", 3) == (
        "(S1 ^epmem E1 ^io I1 ^reward-link R1 ^smem L1 ^superstate nil ^type state)\n" + linked
    )
    assert agent.stats["wm_size"] == 13
    assert [w.timetag for w in agent.wmes()] == list(range(1, 14))


@pytest.mark.parametrize("matcher", [None, BruteForceMatcher])
def test_counter_matches_kernel_figures(matcher) -> None:
    # Figures measured with soar_sml 9.6 on the same rules.
    agent, out = make(COUNTER, matcher=matcher)
    agent.run()
    stats = agent.stats
    assert agent.halted
    assert (stats["decisions"], stats["elaboration_cycles"], stats["production_firings"]) == (
        5,
        11,
        14,
    )
    assert (stats["wme_changes"], stats["wm_size"]) == (55, 19)
    assert out.getvalue() == (
        "count 0\ncount 1\ncount 2\n" "\nSystem halted.\nInterrupt received.This Agent halted."
    )
    assert agent.operator_sequence == ["init", "inc", "inc", "inc", "stop"]
    assert agent.print("S1", 1).startswith(
        "(S1 ^count 3 ^double 6 ^epmem E1 ^io I1 ^name count ^operator O5\n"
        "       ^operator O5 + ^reward-link R1"
    )


def test_trace_level_1_and_3_text() -> None:
    agent, out = make(COUNTER)
    agent.trace(1)
    agent.run(2)
    assert out.getvalue() == "\n     1:    O: O1 (init)\n     2:    O: O2 (inc)"
    agent, out = make(COUNTER)
    agent.trace(3)
    agent.run(1)
    text = out.getvalue()
    assert "\nFiring propose*init" in text
    assert "--- Propose Phase ---" in text


def test_run_stops_before_apply_like_the_kernel() -> None:
    agent, out = make(COUNTER)
    agent.run(1)
    assert agent.stats["decisions"] == 1
    assert values(agent, "S1", "name") == []  # init not applied yet
    agent.step()
    assert values(agent, "S1", "name") == ["count"]
    agent.run(0)
    assert agent.stats["decisions"] == 2


def test_halt_stops_and_further_runs_do_nothing() -> None:
    agent, _ = make(COUNTER)
    agent.run()
    before = dict(agent.stats)
    agent.run(5)
    assert agent.stats == before


def test_init_keeps_rules_and_rebuilds_top_state() -> None:
    agent, out = make(COUNTER)
    agent.run()
    agent.init()
    assert not agent.halted
    assert agent.stats["decisions"] == 0 and agent.stats["wm_size"] == 13
    assert agent.stats["wme_changes"] == 13
    assert agent.productions == [
        "propose*init",
        "apply*init",
        "propose*count",
        "apply*count",
        "elab",
        "propose*halt",
        "apply*halt",
    ]
    agent.run()
    assert agent.halted and agent.stats["decisions"] == 5


def test_i_support_retracts_and_o_support_persists() -> None:
    rules = """
    sp {elab (state <s> ^superstate nil ^flag on) --> (<s> ^shadow yes)}
    sp {propose (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name go)}
    sp {apply (state <s> ^operator.name go) --> (<s> ^done yes ^flag on)}
    sp {propose2 (state <s> ^done yes ^flag on) --> (<s> ^operator <o> +) (<o> ^name off)}
    sp {apply2 (state <s> ^operator.name off ^flag on) --> (<s> ^flag on -)}
    """
    agent, _ = make(rules)
    agent.run(2)
    assert agent.operator_sequence == ["go", "off"]
    assert values(agent, "S1", "shadow") == ["yes"]
    agent.run(1)
    assert values(agent, "S1", "flag") == []
    assert values(agent, "S1", "shadow") == []  # i-supported: gone with its reason
    assert values(agent, "S1", "done") == ["yes"]  # o-supported: persists


def test_operator_elaboration_is_i_supported() -> None:
    rules = """
    sp {p (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name a)}
    sp {e (state <s> ^operator <o>) --> (<o> ^selected yes)}
    sp {a (state <s> ^operator.name a) --> (<s> ^done t)}
    """
    agent, _ = make(rules)
    agent.run(2)
    assert values(agent, "S1", "done") == ["t"]
    assert not any(w.attr == "selected" for w in agent.wmes())


def test_max_elaborations_warns_and_moves_on() -> None:
    rules = """
    sp {flip (state <s> ^superstate nil -^x) --> (<s> ^x 1)}
    sp {p (state <s> ^superstate nil) --> (<s> ^operator <o> +) (<o> ^name a)}
    """
    agent, out = make(rules)
    agent.load("max-elaborations 5")
    agent.run(1)
    assert "Warning: reached max-elaborations; proceeding to decide phase." in out.getvalue()
    assert agent.stats["elaboration_cycles"] == 5
    assert agent.operator_sequence == ["a"]


def test_tie_impasse_substate_and_resolution() -> None:
    rules = """
    sp {pa (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name a)}
    sp {pb (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name b)}
    sp {tie (state <s> ^impasse tie ^superstate <ss> ^item <i>) (<i> ^name a)
       --> (<ss> ^operator <i> >)}
    sp {apply (state <s> ^operator.name a) --> (<s> ^done t)}
    """
    agent, out = make(rules)
    agent.trace(1)
    agent.run(1)
    assert "==>S: S2 (operator tie)" in out.getvalue()
    sub = agent.print("S2", 1)
    for aug in (
        "^attribute operator",
        "^choices multiple",
        "^impasse tie",
        "^item-count 2",
        "^quiescence t",
        "^superstate S1",
        "^type state",
        "^non-numeric-count 2",
    ):
        assert aug in sub
    agent.run(1)
    assert agent.operator_sequence == ["a"]
    with pytest.raises(SoarRuntimeError):
        agent.print("S2")
    agent.run(1)
    assert values(agent, "S1", "done") == ["t"]
    assert agent.stats["elaboration_cycles"] == 6  # kernel figure


@pytest.mark.parametrize(
    ("rules", "kind"),
    [
        (
            "sp {x (state <s> ^superstate nil) --> (<s> ^operator <a> + ^operator <b> +)"
            " (<a> ^name a) (<b> ^name b) (<s> ^operator <a> > <b>) (<s> ^operator <b> > <a>)}",
            "operator conflict",
        ),
        (
            "sp {x (state <s> ^superstate nil) --> (<s> ^operator <a> ! ^operator <b> !)"
            " (<a> ^name a) (<b> ^name b)}",
            "operator constraint-failure",
        ),
        (
            "sp {x (state <s> ^superstate nil) --> (<s> ^operator <a> +) (<a> ^name a)}",
            "operator no-change",
        ),
        ("", "state no-change"),
    ],
)
def test_each_impasse_kind_makes_its_substate_and_choices(rules: str, kind: str) -> None:
    agent, out = make(rules)
    agent.trace(1)
    agent.run(2)
    assert f"==>S: S2 ({kind})" in out.getvalue()
    # measured on the kernel: a constraint failure has no choices either
    choices = {"operator conflict": "multiple"}.get(kind, "none")
    assert f"^choices {choices}" in agent.print("S2")


def test_state_no_changes_stack_up() -> None:
    agent, out = make()
    agent.trace(1)
    agent.run(3)
    assert out.getvalue() == (
        "\n     1:    ==>S: S2 (state no-change)"
        "\n     2:       ==>S: S3 (state no-change)"
        "\n     3:          ==>S: S4 (state no-change)"
    )


def test_result_from_operator_no_change_is_o_supported() -> None:
    rules = """
    sp {p (state <s> ^superstate nil -^done) --> (<s> ^operator <x> + >) (<x> ^name a)}
    sp {sub (state <s> ^impasse no-change ^attribute operator ^superstate <ss>)
            (<ss> ^operator <o>)
       --> (<s> ^operator <p> +) (<p> ^name subop)}
    sp {subapply (state <s> ^operator.name subop ^superstate <ss>)
       --> (<ss> ^done t ^res (/ 7 2))}
    """
    agent, _ = make(rules)
    agent.run(6)
    # Kernel: the result survives the substate it came from (o-supported justification).
    assert values(agent, "S1", "done") == ["t"]
    assert values(agent, "S1", "res") == [3.5]
    assert agent.stats["elaboration_cycles"] == 5


def test_gds_removes_substate_when_superstate_wme_changes() -> None:
    rules = """
    sp {init (state <s> ^superstate nil -^count) --> (<s> ^operator <o> +) (<o> ^name init)}
    sp {init*a (state <s> ^operator.name init) --> (<s> ^count 0 ^started yes)}
    sp {w (state <s> ^superstate nil ^count <c> < 2) --> (<s> ^weather (+ <c> 10))}
    sp {work (state <s> ^superstate nil ^started yes -^count 2)
       --> (<s> ^operator <o> +) (<o> ^name work)}
    sp {dress (state <s> ^superstate.operator.name work -^dressed)
       --> (<s> ^operator <o> +) (<o> ^name dress)}
    sp {dress*a (state <s> ^operator.name dress ^superstate.weather <w>)
       --> (<s> ^dressed <w>)}
    sp {tick (state <s> ^dressed <w>) --> (<s> ^operator <o> +) (<o> ^name tick)}
    sp {tick*a (state <s> ^operator.name tick ^superstate <ss>) (<ss> ^count <c>)
       --> (<ss> ^count <c> - (+ <c> 1))}
    """
    agent, out = make(rules)
    agent.trace(1)
    agent.run(12)
    text = out.getvalue()
    assert "==>S: S3 (operator no-change)" in text  # S2 was removed by the GDS
    assert values(agent, "S1", "count") == [2]


def test_input_link_handles_and_output_link() -> None:
    rules = """
    sp {copy (state <s> ^io <io>) (<io> ^input-link.block <b> ^output-link <out>)
             (<b> ^id <id>)
       --> (<out> ^seen <x>) (<x> ^id <id>)}
    """
    agent, _ = make(rules)
    block = agent.input_link.add("block")
    assert block.id == "B1"
    wme = block.add("id", 3)
    agent.run(1)
    seen = agent.output_link.get("seen")
    assert seen is not None and seen.get("id") == 3
    assert agent.output_link.children() == [("seen", seen)]
    block.update("id", 4)
    agent.run(1)
    assert agent.output_link.get("seen").get("id") == 4
    wme.remove()  # already replaced: removing twice is harmless
    block.remove()
    agent.run(1)
    assert agent.output_link.children() == []
    assert not any(w.id.name == "B1" for w in agent.wmes())


def test_input_values_are_checked() -> None:
    agent, _ = make()
    with pytest.raises(SoarRuntimeError):
        agent.input_link.add("x", object())
    with pytest.raises(SoarRuntimeError):
        agent.input_link.remove()


def test_excise_retracts_and_replacing_a_production() -> None:
    agent, _ = make("sp {e (state <s> ^superstate nil) --> (<s> ^x 1)}")
    agent.run(1)
    assert values(agent, "S1", "x") == [1]
    agent.load("sp {e (state <s> ^superstate nil) --> (<s> ^x 2)}")
    assert agent.productions == ["e"]
    agent.run(1)
    assert values(agent, "S1", "x") == [2]
    agent.excise("e")
    agent.run(1)
    assert values(agent, "S1", "x") == []
    with pytest.raises(SoarRuntimeError):
        agent.excise("e")


def test_first_error_stops_the_rest_of_the_text() -> None:
    agent, _ = make()
    text = (
        "sp {a (state <s> ^superstate nil) --> (<s> ^x 1)}\n"
        "sp {b (state <s> ^superstate nil) -->\n  (<s> ^y 1}\n"
        "sp {c (state <s> ^superstate nil) --> (<s> ^z 1)}\n"
    )
    with pytest.raises(SoarSyntaxError):
        agent.load(text)
    assert agent.productions == ["a"]


def test_source_resolves_relative_paths(tmp_path) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "main.soar").write_text("source sub/one.soar\n")
    (tmp_path / "sub" / "one.soar").write_text(
        "source two.soar\nsp {one (state <s> ^superstate nil) --> (<s> ^one 1)}\n"
    )
    (tmp_path / "sub" / "two.soar").write_text(
        "sp {two (state <s> ^superstate nil) --> (<s> ^two 2)}\n"
    )
    agent, _ = make()
    agent.source(tmp_path / "main.soar")
    assert agent.productions == ["two", "one"]
    with pytest.raises(SoarRuntimeError, match="cannot open"):
        agent.source(tmp_path / "missing.soar")


def test_non_operator_multi_values_and_reject() -> None:
    rules = """
    sp {p (state <s> ^superstate nil) --> (<s> ^color red green blue)}
    sp {r (state <s> ^superstate nil ^color green) --> (<s> ^color green -)}
    """
    agent, _ = make(rules)
    agent.run(1)
    assert values(agent, "S1", "color") == ["blue", "red"]


def test_unlinked_structure_is_garbage_collected() -> None:
    rules = """
    sp {p (state <s> ^superstate nil -^stage) --> (<s> ^operator <o> +) (<o> ^name make)}
    sp {a (state <s> ^operator.name make) --> (<s> ^stage 1 ^thing <t>) (<t> ^part <p>)
       (<p> ^size 3)}
    sp {pdrop (state <s> ^stage 1) --> (<s> ^operator <o> +) (<o> ^name drop)}
    sp {adrop (state <s> ^operator.name drop ^thing <t>) --> (<s> ^thing <t> - ^stage 1 - 2)}
    """
    agent, _ = make(rules)
    agent.run(3)
    assert not any(w.attr in ("part", "size") for w in agent.wmes())


def test_rhs_error_prints_the_kernels_line_and_the_run_goes_on() -> None:
    # Kernel: "Error: attempt to divide ('/') by zero.", the action is dropped, the rest
    # of the rule and the run go on.
    agent, out = make("sp {bad (state <s> ^superstate nil) --> (<s> ^x (/ 1 0) ^y 2)}")
    agent.run(1)
    assert out.getvalue() == "Error: attempt to divide ('/') by zero.\n"
    assert agent.errors == ["Error: production bad: attempt to divide ('/') by zero."]
    assert values(agent, "S1", "y") == [2] and values(agent, "S1", "x") == []


def test_trace_level_is_checked() -> None:
    agent, _ = make()
    with pytest.raises(SoarRuntimeError):
        agent.trace(6)


def test_input_link_handle_is_shared_and_stale_after_init() -> None:
    agent, _ = make()
    agent.input_link.add("x", 1)
    agent.input_link.update("x", 2)
    agent.run(1)
    assert values(agent, "I2", "x") == [2]
    block = agent.input_link.add("block")
    agent.init()
    block.remove()  # harmless: working memory was cleared
    with pytest.raises(SoarRuntimeError, match="before init"):
        block.add("id", 1)
    agent.input_link.add("y", 3)
    agent.run(1)
    assert values(agent, "I2", "y") == [3] and values(agent, "I2", "x") == []


def test_results_retract_when_negated_superstate_test_fails() -> None:
    rules = """
    sp {top*elab (state <s> ^superstate nil) --> (<s> ^counter 0)}
    sp {sub (state <s> ^impasse no-change ^attribute state ^superstate <ss>)
            (<ss> ^counter <c> -^done)
       --> (<ss> ^operator <o> + =) (<o> ^name from-sub)}
    sp {apply (state <s> ^operator <o>) (<o> ^name from-sub) --> (<s> ^done yes)}
    """
    agent, _ = make(rules)
    agent.run(2)
    assert agent.operator_sequence == ["from-sub"]
    agent.run(1)
    # ^done appeared: the justification of the proposal (made in the substate) retracts.
    assert not any(w.attr == "operator" for w in agent.wmes() if w.id.name == "S1")


def test_remove_and_readd_same_value_in_one_firing_keeps_it() -> None:
    rules = """
    sp {p (state <s> ^superstate nil -^mark) --> (<s> ^operator <o> +) (<o> ^name init)}
    sp {a (state <s> ^operator.name init) --> (<s> ^mark a)}
    sp {t (state <s> ^mark a -^done) --> (<s> ^operator <o> +) (<o> ^name touch)}
    sp {at (state <s> ^operator.name touch ^mark <m>) --> (<s> ^mark <m> - <m> ^done yes)}
    """
    agent, _ = make(rules)
    agent.run(3)
    assert values(agent, "S1", "mark") == ["a"]


def test_goal_stack_depth_guard_interrupts_like_the_kernel() -> None:
    agent, out = make()
    agent.run(120)
    # Kernel: 100 decisions, S101 made, then "System halted." -- but only an interrupt:
    # each later run makes one more decision and stops again (measured: 101, then 102).
    assert not agent.halted and agent.stats["decisions"] == 100
    assert "Goal stack depth exceeded 100 on a no-change impasse." in out.getvalue()
    assert agent.print("S101").startswith("(S101 ")
    agent.run(3)
    assert agent.stats["decisions"] == 101 and not agent.halted
    agent.run(3)
    assert agent.stats["decisions"] == 102


def test_dropped_working_memory_is_freed_without_the_cycle_collector() -> None:
    """Retracted instantiations, removed preferences, deleted tokens and what ``init``
    drops hold no reference cycle: reference counting frees them at once (the cyclic
    collector, when it had them to find, took a quarter of the run time)."""
    import gc
    from pathlib import Path

    hanoi = (Path(__file__).resolve().parents[2] / "rules" / "hanoi.soar").read_text()
    agent, _ = make(COUNTER)
    other, _ = make(hanoi)
    gc.collect()
    gc.disable()
    try:
        for _ in range(3):
            agent.run()
            agent.init()
        other.input_link.add("disks", 4)
        other.run(decisions=12)
        other.init()
        other.run(decisions=5)
        found = gc.collect()
    finally:
        gc.enable()
    assert agent.halted is False and other.stats["decisions"] == 5
    assert found == 0


def test_wait_snc_makes_a_state_with_nothing_to_do_wait() -> None:
    """``waitsnc --on`` (measured on the kernel): no state no-change substate; each waiting
    decision shows the state again, a substate with its own impasse."""
    agent, out = make(
        "sp {p (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name a)}\n"
        "sp {a (state <s> ^operator.name a) --> (<s> ^done yes)}"
    )
    agent.wait_snc = True
    agent.trace(1)
    agent.run(4)
    assert out.getvalue() == (
        "\n     1:    O: O1 (a)\n     2: ==>S: S1 \n     3: ==>S: S1 \n     4: ==>S: S1 "
    )
    assert agent.stats["decisions"] == 4 and agent.stats["elaboration_cycles"] == 4
    with pytest.raises(SoarRuntimeError):
        agent.find_identifier("S2")


def test_wait_snc_in_a_substate() -> None:
    agent, out = make(
        "sp {p (state <s> ^superstate nil) --> (<s> ^operator <o> +) (<o> ^name a)}\n"
        "sp {e (state <s> ^superstate.operator.name a) --> (<s> ^mark yes)}"
    )
    agent.wait_snc = True
    agent.trace(1)
    agent.run(4)
    assert out.getvalue() == "\n     1:    O: O1 (a)" + "".join(
        f"\n     {n}:    ==>S: S2 (operator no-change)" for n in (2, 3, 4))
    assert agent.stats["elaboration_cycles"] == 2 and values(agent, "S2", "mark") == ["yes"]


def test_an_agent_raises_the_young_gc_threshold_and_never_lowers_it() -> None:
    import gc

    from sann.soar.agent import GC_YOUNG_THRESHOLD

    before = gc.get_threshold()
    try:
        gc.set_threshold(700, 10, 10)
        Agent()
        assert gc.get_threshold() == (GC_YOUNG_THRESHOLD, 10, 10)
        gc.set_threshold(GC_YOUNG_THRESHOLD * 2, 5, 5)
        Agent()
        assert gc.get_threshold() == (GC_YOUNG_THRESHOLD * 2, 5, 5)
    finally:
        gc.set_threshold(*before)
