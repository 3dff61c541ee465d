"""sann.live, the engine side of the live book's cells, in CPython (the page runs the same)."""

from __future__ import annotations

from pathlib import Path

from sann import live

ROOT = Path(__file__).resolve().parents[1]
WATER_JUG = (ROOT / "rules" / "water-jug.soar").read_text(encoding="utf-8")
BLOCKS = (ROOT / "rules" / "blocks.soar").read_text(encoding="utf-8")


def test_a_whole_file_runs_to_its_halt() -> None:
    answer = live.run_cell({"text": WATER_JUG, "file": "water-jug.soar", "shipped": WATER_JUG,
                            "queries": ["print S1", "preferences", "stats"]})
    assert answer["error"] is None and answer["halted"]
    assert "The problem has been solved." in answer["output"]
    assert "System halted" not in answer["output"]  # the cell says how the run ended
    assert answer["stats"]["decisions"] == 9
    assert [q["command"] for q in answer["queries"]] == ["print S1", "preferences", "stats"]
    assert "(S1 ^" in answer["queries"][0]["text"]
    assert "9 decisions" in answer["queries"][2]["text"]


def test_a_runaway_run_stops_at_the_limit() -> None:
    looping = WATER_JUG.replace("(halt)", "")
    answer = live.run_cell({"text": looping, "file": "water-jug.soar", "shipped": WATER_JUG,
                            "decisions": 20, "trace": 0})
    assert answer["limit"] and not answer["halted"]
    assert "stopped at the 20-decision limit" in answer["output"]


def test_a_fragment_runs_inside_its_file_and_errors_count_from_the_cell() -> None:
    start = BLOCKS.index("sp {", BLOCKS.index("the scene, once"))
    fragment = BLOCKS[start:BLOCKS.index("\n\n", start) + 1]
    cell = live.Cell(text=fragment, file="blocks.soar", shipped=fragment)
    text, first = live.compose(cell)
    assert text == BLOCKS
    assert first == BLOCKS.count("\n", 0, start) + 1
    broken = fragment.replace("-->", "--> )", 1)
    answer = live.run_cell({"text": broken, "file": "blocks.soar", "shipped": fragment})
    error = answer["error"]
    assert error["kind"] == "SoarSyntaxError"
    assert error["file"] == "rules/blocks.soar"
    assert error["cell_line"] == error["line"] - first + 1
    assert broken.splitlines()[error["cell_line"] - 1].strip().startswith("-->")


def test_a_magic_cell_runs_on_its_preloaded_agent() -> None:
    cell = ("%%soar jug --init --trace 0 --decisions 12\n"
            "sp {water-jug*select*fill*empty-small*best\n"
            "   (state <s> ^name water-jug ^operator <o> +)\n"
            "   (<o> ^name fill ^fill-jug <j>)\n   (<j> ^volume 5 ^contents 0)\n"
            "-->\n   (<s> ^operator <o> >)}\n")
    answer = live.run_cell({"text": cell, "preload": ["water-jug.soar"]})
    assert answer["error"] is None
    assert answer["operators"][:2] == ["initialize-water-jug", "fill"]
    assert answer["limit"] and not answer["halted"]  # this strategy alone never solves it
    assert answer["stats"]["decisions"] == 12


def test_stepping_by_phase_and_by_decision() -> None:
    stepper = live.Stepper({"text": WATER_JUG, "file": "water-jug.soar", "shipped": WATER_JUG,
                            "trace": 0})
    first = stepper.step("decision")
    assert first["decisions"] == 1 and first["phase"] == "apply"
    assert first["goals"][0]["operator_name"] == "initialize-water-jug"
    phase = stepper.step("phase")
    assert phase["phase"] != "apply" and phase["decisions"] == 1
    graph = phase["graph"]
    ids = {n["id"] for n in graph["nodes"]}
    assert {"S1", "J1", "J2"} <= ids
    assert all(e["from"] in ids and e["to"] in ids for e in graph["edges"])


def test_a_tie_shows_its_substate() -> None:
    rules = "".join(
        f"sp {{propose*{side} (state <s> ^superstate nil) --> (<s> ^operator <o> +)"
        f" (<o> ^name {side})}}\n" for side in ("left", "right"))
    stepper = live.Stepper({"text": "%%soar tie --trace 0\n" + rules})
    goals = stepper.step("decision")["goals"]
    assert [g["id"] for g in goals] == ["S1", "S2"]
    assert goals[1]["impasse"] == "tie" and goals[1]["attribute"] == "operator"
    assert "acceptables" in goals[0]["preferences"]


def test_syntax_errors_are_placed_in_the_cell() -> None:
    magic = ("%%soar jug --trace 0\nsp {ok (state <s> ^superstate nil) --> (<s> ^a b)}\n"
             "sp {bad (state <s> -->\n")
    error = live.run_cell({"text": magic})["error"]
    assert error["file"] == "<%%soar jug>"
    assert error["cell_line"] == 3
    exercise = "# comment\nsp {broken\n  (state <s> ^x)\n-- > (<s> ^y 1)}\n"
    error = live.run_cell({"text": exercise, "exercise": "greedy-empty"})["error"]
    assert error["file"] == "<exercise greedy-empty>" and error["cell_line"] == error["line"]
    assert 2 <= error["cell_line"] <= 4
