"""The exercises' checks (sann/exercises.py), the ones the live page runs after each Run:
the reference solutions kept here pass, the chapter's starting cells and wrong answers do not."""

from __future__ import annotations

from pathlib import Path

import pytest

from sann.exercises import EXERCISES, check

SOLUTIONS = Path(__file__).resolve().parent / "solutions"
BOOK = Path(__file__).resolve().parents[2] / "book"


def test_every_exercise_has_a_solution_and_a_live_cell() -> None:
    chapter = (BOOK / "exercises.md").read_text(encoding="utf-8")
    for name in EXERCISES:
        assert (SOLUTIONS / f"{name}.soar").is_file(), name
        assert f"```{{live-exercise}} {name}\n" in chapter, name


@pytest.mark.parametrize("name", sorted(EXERCISES))
def test_the_reference_solution_passes(name: str) -> None:
    result = check(name, (SOLUTIONS / f"{name}.soar").read_text(encoding="utf-8"))
    assert result["passed"], result["results"]


@pytest.mark.parametrize("name", sorted(EXERCISES))
def test_the_starting_cell_does_not_pass(name: str) -> None:
    result = check(name, EXERCISES[name].start)
    assert not result["passed"]


def test_a_rule_that_does_not_parse_fails_with_the_engine_message() -> None:
    result = check("greedy-empty", "sp {broken (state <s> -->")
    assert not result["passed"]
    assert "<exercise greedy-empty>:1:" in result["results"][0]["detail"]


def test_greedy_without_the_tie_does_not_pass() -> None:
    # Best only for emptying the 5-gallon jug: the file's strategy still solves the puzzle.
    narrow = """sp {water-jug*select*empty*five*best
   (state <s> ^name water-jug ^operator <o> +)
   (<o> ^name empty ^empty-jug.volume 5)
-->
   (<s> ^operator <o> >)}
"""
    results = {r["name"]: r["passed"] for r in check("greedy-empty", narrow)["results"]}
    assert results["the cell adds a rule"]
    assert not results["every proposed empty operator is best"]


def test_all_have_water_with_a_plain_negation_does_not_pass() -> None:
    plain = """sp {water-jug*elaborate*all-have-water
   (state <s> ^name water-jug ^jug <j>)
   (<j> -^contents 0)
-->
   (<s> ^all-have-water yes)}
"""
    result = check("all-have-water", plain)
    assert not result["passed"]
    names = {r["name"]: r["passed"] for r in result["results"]}
    assert not names["it uses a negated conjunction -{ ... }"]
    assert not names["^all-have-water yes is on the state exactly when no jug is empty"]


def test_a_monitor_without_the_decision_count_does_not_pass() -> None:
    names_only = """sp {hanoi*monitor
   (state <s> ^operator <o>)
   (<o> ^name <name>)
-->
   (write <name> (crlf))}
"""
    result = check("hanoi-monitor", names_only)
    assert not result["passed"]


def test_the_small_pile_is_what_the_cups_driver_writes() -> None:
    """The cups exercise's input is the chapter's hand-made pile as sann.tasks.cups puts it
    on the input-link (the page has no numpy, so it replays the tree)."""
    import numpy as np

    from sann.exercises import small_pile
    from sann.live import input_tree
    from sann.tasks.cups import CupPlanner, CupScene

    n = 4
    positions = np.array([[0, 0, 100], [60, 0, 100], [30, 0, 0], [0, 0, 200]], dtype=float)
    over = np.zeros((n, n), dtype=bool)
    on = np.zeros((n, n), dtype=bool)
    for a, b in [(0, 2), (1, 2), (3, 0)]:
        over[a, b] = on[a, b] = True
    over[3, 2] = True
    pile = CupScene(positions, np.tile([0.0, 0.0, 1.0], (n, 1)), np.ones(n), over, on)
    with CupPlanner() as planner:
        planner.plan(pile)
        assert input_tree(planner._backend.agent) == small_pile()
