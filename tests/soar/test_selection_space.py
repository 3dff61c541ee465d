"""The selection space of ``rules/default/selection.soar`` and the look-ahead agents using it.

Every case runs in the real Soar kernel (``soar_sml``, the authority) and in our engine
through the differential harness, and must agree with it; each also checks what the
selection space is meant to do (which operator a verdict picks, what the state copy holds,
how many evaluations a depth limit allows), so that a selection space that agreed with the
kernel by doing nothing would still fail.
"""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("soar_sml")
from differential.kernel import Graph, RunResult, our_graph, run_kernel, run_ours  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SELECTION = ROOT / "rules" / "default" / "selection.soar"
AGENTS = {
    "water-jug-lookahead": "The 3-gallon jug holds 1 gallon.",
    "eight-puzzle-lookahead": "Solved.",
    "blocks-world-lookahead": "A is on B, B is on C.",
    "missionaries-cannibals": "Everyone has crossed.",
}
FIRST = "srand 1\nindifferent-selection --first\n"


def _write(tmp_path: Path, name: str, rules: str, preamble: str = FIRST) -> Path:
    path = tmp_path / f"{name}.soar"
    path.write_text(f"{preamble}source {SELECTION}\n{rules}")
    return path


def _both(path: Path, decisions: int) -> tuple[RunResult, RunResult]:
    return run_kernel(path, decisions=decisions), run_ours(path, decisions=decisions)


def _assert_agree(theirs: RunResult, ours: RunResult) -> None:
    assert "Error" not in theirs.trace
    assert ours.halted == theirs.halted
    assert ours.output == theirs.output
    assert ours.operators == theirs.operators
    assert (ours.decisions, ours.production_firings) == (theirs.decisions,
                                                          theirs.production_firings)
    assert ours.wm == theirs.wm


# --------------------------------------------------------------------------- a tie

# Three operators a, b, c tie in the task state; applying one records ^done, which halts
# the top state. Verdict rules are added per case.
TASK = """
sp {task*elaborate*state
   (state <s> ^superstate nil)
-->
   (<s> ^name task ^desired <d> ^problem-space <p>)
   (<p> ^name task ^max-look-ahead-depth 1)
   (<d> ^better BETTER)}

sp {task*propose*op
   (state <s> ^name task -^done)
-->
   (<s> ^operator <a> + <b> + <c> +)
   (<a> ^name a) (<b> ^name b) (<c> ^name c)}

sp {task*apply*op
   (state <s> ^operator.name <n>)
-->
   (<s> ^done <n>)}

sp {task*halt
   (state <s> ^superstate nil ^done <n>)
-->
   (write |done | <n>)
   (halt)}
"""


def _task(verdicts: dict[str, str | int], better: str = "higher") -> str:
    """The task with one verdict rule per operator: a symbolic verdict or a number."""
    rules = [TASK.replace("BETTER", better)]
    for op, verdict in verdicts.items():
        action = (f"(<s> ^numeric-value {verdict})" if isinstance(verdict, int)
                  else f"(<s> ^{verdict} <d>)")
        rules.append(f"sp {{task*evaluate*{op}\n   (state <s> ^name task ^desired <d>"
                     f" ^tried-tied-operator.name {op})\n-->\n   {action}}}\n")
    return "\n".join(rules)


def test_a_tie_opens_a_selection_state_proposing_evaluate_operator(tmp_path: Path) -> None:
    theirs, ours = _both(_write(tmp_path, "tie", _task({})), decisions=2)
    _assert_agree(theirs, ours)
    assert ours.operators == ["evaluate-operator"]
    selection = [t for t in ours.wm if t[1:] == ("|name|", "|selection|", "")]
    assert len(selection) == 1
    state = selection[0][0]
    proposed = {t[2] for t in ours.wm if t[0] == state and t[1] == "|operator|" and t[3] == "+"}
    names = {t[2] for t in ours.wm if t[0] in proposed and t[1] == "|name|"}
    assert len(proposed) == 3 and names == {"|evaluate-operator|"}


@pytest.mark.parametrize(
    ("verdicts", "chosen"),
    [({"a": "success", "b": "failure", "c": "indifferent"}, "a"),
     ({"a": "failure", "b": "failure", "c": "indifferent"}, "c"),
     ({"a": "partial-success", "b": "success", "c": "indifferent"}, "b"),
     ({"a": "partial-failure", "b": "failure", "c": "indifferent"}, "c"),
     ({"b": "indifferent"}, "b")],
    ids=["success-best", "failure-reject", "success-over-partial", "partial-failure-worst",
         "dead-end-failure"],
)  # fmt: skip
def test_symbolic_verdicts_become_preferences(
    tmp_path: Path, verdicts: dict[str, str | int], chosen: str
) -> None:
    theirs, ours = _both(_write(tmp_path, "symbolic", _task(verdicts)), decisions=200)
    _assert_agree(theirs, ours)
    assert ours.halted and ours.output.startswith(f"done {chosen}")


@pytest.mark.parametrize(
    ("verdicts", "better", "chosen"),
    [({"a": 1, "b": 3, "c": 2}, "higher", {"b"}),
     ({"a": 1, "b": 3, "c": 2}, "lower", {"a"}),
     ({"a": 2, "b": 2, "c": 1}, "higher", {"a", "b"})],
    ids=["higher", "lower", "equal-indifferent"],
)  # fmt: skip
def test_numeric_values_become_better_and_indifferent(
    tmp_path: Path, verdicts: dict[str, str | int], better: str, chosen: set[str]
) -> None:
    path = _write(tmp_path, "numeric", _task(verdicts, better))
    theirs, ours = _both(path, decisions=200)
    _assert_agree(theirs, ours)
    assert ours.halted and ours.output.removeprefix("done ")[0] in chosen


@pytest.mark.parametrize("limit", [1, 2, 3])
def test_depth_limit_stops_the_look_ahead(tmp_path: Path, limit: int) -> None:
    """No verdict ever: each level evaluates both tied operators, and the ties of the
    deepest evaluation states end as `exhausted`; the top state then picks either."""
    rules = TASK.replace("BETTER", "higher").replace(
        "^max-look-ahead-depth 1", f"^max-look-ahead-depth {limit}").replace(
        "^operator <a> + <b> + <c> +)\n   (<a> ^name a) (<b> ^name b) (<c> ^name c)",
        "^operator <a> + <b> +)\n   (<a> ^name a) (<b> ^name b)").replace(
        "(state <s> ^name task -^done)", "(state <s> ^name task)")
    theirs, ours = _both(_write(tmp_path, "depth", rules), decisions=2000)
    _assert_agree(theirs, ours)
    assert ours.halted
    assert ours.operators.count("evaluate-operator") == 2 ** (limit + 1) - 2


# --------------------------------------------------------------------------- the state copy

COPY = """
sp {task*elaborate*state
   (state <s> ^superstate nil)
-->
   (<s> ^name task ^problem-space <p> ^obj <x> ^count 3 ^skip 1)
   (<x> ^colour red ^size 2)
   (<p> ^name task SWITCHES)}

sp {task*propose*op
   (state <s> ^name task ^obj <x>)
-->
   (<s> ^operator <a> + <b> +)
   (<a> ^name a ^target <x>) (<b> ^name b ^target <x>)}
"""


def _eval_state(graph: Graph) -> str:
    (state,) = [ident for ident, edges in graph.items()
                if any(attr == ("str", "duplicates") for attr, _, _ in edges)]
    return state


def _values(graph: Graph, ident: str, attr: str) -> list:
    return [value for a, value, acc in graph[ident] if a == ("str", attr) and not acc]


def _copy_run(tmp_path: Path, switches: str) -> tuple[Graph, str, str]:
    """Four decisions: the tie, evaluate-operator, the evaluation state (copied in that
    cycle's application phase), the copied operator selected there."""
    from sann.soar.agent import Agent

    path = _write(tmp_path, "copy", COPY.replace("SWITCHES", switches))
    theirs, ours = _both(path, decisions=4)
    _assert_agree(theirs, ours)
    agent = Agent()
    agent.source(str(path))
    agent.run(decisions=4)
    graph, roots = our_graph(agent)
    return graph, roots[0], _eval_state(graph)


def _shared_obj(graph: Graph, top: str, copy: str) -> bool:
    (original,) = _values(graph, top, "obj")
    (copied,) = _values(graph, copy, "obj")
    return copied == original


def test_copy_by_default_shares_every_attribute(tmp_path: Path) -> None:
    graph, top, copy = _copy_run(tmp_path, "")
    assert _shared_obj(graph, top, copy)
    assert _values(graph, copy, "count") == [("int", 3)] and _values(graph, copy, "skip")


def test_copy_one_level_attributes_only(tmp_path: Path) -> None:
    graph, top, copy = _copy_run(tmp_path, "^one-level-attributes obj")
    assert _shared_obj(graph, top, copy)
    assert not _values(graph, copy, "count")


def test_copy_two_level_attributes_duplicates_and_maps_the_operator(tmp_path: Path) -> None:
    graph, top, copy = _copy_run(tmp_path, "^two-level-attributes obj")
    assert not _shared_obj(graph, top, copy)
    (new,) = _values(graph, copy, "obj")
    assert sorted(_values(graph, new[1], "colour") + _values(graph, new[1], "size")) == [
        ("int", 2), ("str", "red")]
    assert not _values(graph, copy, "count")
    (selected,) = _values(graph, copy, "operator")
    assert _values(graph, selected[1], "target") == [new]


def test_copy_all_attributes_at_level_two(tmp_path: Path) -> None:
    graph, top, copy = _copy_run(tmp_path, "^all-attributes-at-level two")
    assert not _shared_obj(graph, top, copy)
    assert _values(graph, copy, "count") == [("int", 3)]


def test_copy_dont_copy_leaves_an_attribute_out(tmp_path: Path) -> None:
    graph, top, copy = _copy_run(tmp_path, "^all-attributes-at-level one ^dont-copy skip")
    assert _shared_obj(graph, top, copy)
    assert _values(graph, copy, "count") and not _values(graph, copy, "skip")


def test_copy_can_be_switched_off(tmp_path: Path) -> None:
    graph, top, copy = _copy_run(tmp_path, "^default-state-copy no")
    assert not _values(graph, copy, "obj") and not _values(graph, copy, "count")
    assert _values(graph, copy, "name") == [("str", "task")]


# --------------------------------------------------------------------------- the agents


def _agent(tmp_path: Path, name: str, preamble: str) -> Path:
    path = tmp_path / f"{name}-run.soar"
    path.write_text(f"{preamble}source {ROOT / 'rules' / 'classic' / name}.soar\n")
    return path


@pytest.mark.parametrize("name", sorted(AGENTS))
def test_agent_agrees_with_the_kernel(tmp_path: Path, name: str) -> None:
    theirs, ours = _both(_agent(tmp_path, name, FIRST), decisions=5000)
    _assert_agree(theirs, ours)
    assert ours.halted and ours.output.startswith(AGENTS[name])


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("name", sorted(AGENTS))
def test_agent_halts_in_the_kernel_with_random_choices(
    tmp_path: Path, name: str, seed: int
) -> None:
    result = run_kernel(_agent(tmp_path, name, f"srand {seed}\n"), decisions=5000)
    assert result.halted and result.output.startswith(AGENTS[name])


@pytest.mark.parametrize("name", sorted(AGENTS))
def test_agent_header(name: str) -> None:
    lines = (ROOT / "rules" / "classic" / f"{name}.soar").read_text().splitlines()
    assert lines[0].startswith("# ") and lines[1].startswith("# Teaches: ")
    assert "source ../default/selection.soar" in lines


# --------------------------------------------------------------------------- found on the way


def test_rhs_identifier_of_an_s_variable_is_named_i(tmp_path: Path) -> None:
    """The kernel keeps the letter S for states: ``<small>`` makes I4 (after I1-I3 of the
    io link), ``<big>`` B1. Identifier letters count in the canonical working memory."""
    path = tmp_path / "letters.soar"
    path.write_text("sp {t (state <s> ^superstate nil) --> (<s> ^x <small> ^y <big>)}\n")
    theirs, ours = _both(path, decisions=1)
    assert ours.wm == theirs.wm
    (made,) = [value for ident, attr, value, _ in ours.wm if (ident, attr) == ("S1", "|x|")]
    assert made.startswith("I")


def test_conjunctive_negation_inside_a_conjunctive_negation_loads_and_matches(
    tmp_path: Path,
) -> None:
    """``-{ ... -{ ... } }`` ("no item lacks a value"): loading it crashed in the kernel
    order's node keys (ValueError from reorder.format_kcond)."""
    path = tmp_path / "nested-ncc.soar"
    path.write_text(
        "sp {init (state <s> ^superstate nil) --> (<s> ^item 1 2 ^value <v>) (<v> ^n 1)}\n"
        "sp {every-item-valued (state <s> ^superstate nil)\n"
        "   -{(<s> ^item <i>) -{(<s> ^value <v>) (<v> ^n <i>)}} --> (write |all|)}\n"
        "sp {add (state <s> ^value.n 1) --> (<s> ^value <v>) (<v> ^n 2)}\n")
    theirs, ours = _both(path, decisions=2)
    assert "Error" not in theirs.trace
    assert (ours.output, ours.production_firings) == (theirs.output,
                                                        theirs.production_firings)
    # Once before init's items exist (vacuously), once when the last item gets its value.
    assert ours.output == "allall"
