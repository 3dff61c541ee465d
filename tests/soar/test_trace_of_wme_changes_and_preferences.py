"""Watch 4 (WME changes) and watch 5 (preferences) traces, compared live and whole with the
real Soar 9.6 kernel (soar_sml).

What was measured in the kernel and is checked here:

- The WME changes of a working-memory phase (and of a decision or input phase) are traced
  together at its end, as ``=>WM: (tt: id ^attr value)\\n`` lines: the additions newest
  first, then the removals, the last requested first. The decision line comes after them.
- The kernel adds such a batch to its Rete newest first, so a rule matching three WMEs of
  one batch fires for the oldest first.
- Removals are requested in the kernel's order: the slot diffs', the acceptable-preference
  WMEs' (the selected operator's just before its acceptable one), unlinked structure; a
  removed goal's own WMEs in groups, its memory links and their children last.
- A preference line is ``+ (S1 ^x 1 +) (rule)\\n`` (``[level N]`` after it in a substate),
  ``-`` when removed, in the order it was asserted; it starts on a fresh line, a ``=>WM:``
  line does not; an o-supported reject is not traced itself; an o-supported preference on
  the top level that the slot already holds is ignored, and said so.
- A halt prints the phase's END line only when the phase ends in the cycle that halted.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from generated_agents import generated_agent, generated_substate_agent
from side_by_side import kernel_trace, our_trace

pytest.importorskip("soar_sml")
from differential import kernel as oracle  # noqa: E402  (needs soar_sml)

HERE = Path(__file__).parent
AGENTS = HERE / "differential" / "agents"

#: Differential agents whose whole watch-4 and watch-5 traces agree with the kernel's.
FILES = [
    "agent-commands", "conflict-impasse", "gds-retraction", "halt-in-substate",
    "halt-mid-retraction", "identifier-naming", "justification-retraction", "max-elaborations",
    "operator-gone-pe-wave", "operator-rejected-pe-wave", "remove-and-readd",
    "result-retracts-justification", "result-retracts-justification-ncc", "rhs-math",
    "state-no-change", "tie-cheapest", "tie-items-change", "tie-numeric-partial", "write-output",
]  # fmt: skip

#: Rules whose traces show one rule of the module docstring each.
CORNERS = {
    "batch-order": [
        "sp {a (state <s> ^superstate nil) --> (<s> ^x 1 ^x 2 ^x 3)}",
        "sp {b (state <s> ^x <v>) --> (<s> ^y <v>) (write |b| <v> | |)}",
    ],
    "halt-mid-phase": [
        "sp {p (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name go)}",
        "sp {a (state <s> ^operator.name go) --> (<s> ^done yes) (halt)}",
    ],
    "halt-at-quiescence": [
        "sp {p (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name go)}",
        "sp {a (state <s> ^operator.name go) --> (<s> ^done yes)}",
        "sp {h (state <s> ^done yes) --> (halt)}",
    ],
    "writes-before-traces": [
        "sp {a (state <s> ^superstate nil) --> (<s> ^x 1) (write |hello|)}",
        "sp {b (state <s> ^x 1) --> (<s> ^y 1) (write |b|)}",
    ],
    "o-reject": [
        "sp {p (state <s> ^superstate nil ^n <n> < 3) --> (<s> ^operator <o> +) (<o> ^name inc)}",
        "sp {i (state <s> ^superstate nil -^n) --> (<s> ^n 0)}",
        "sp {a (state <s> ^operator.name inc ^n <n>) --> (<s> ^n <n> - (+ <n> 1) ^gone x -)"
        " (write <n>)}",
    ],
    "already-supported": [
        "sp {pi (state <s> ^superstate nil -^n) --> (<s> ^operator <o> +) (<o> ^name init)}",
        "sp {ai (state <s> ^operator.name init) --> (<s> ^n 0 ^note x)}",
        "sp {p (state <s> ^superstate nil ^n <n> < 2) --> (<s> ^operator <o> +) (<o> ^name inc)}",
        "sp {a (state <s> ^operator.name inc ^n <n>) --> (<s> ^n <n> - (+ <n> 1) ^note x"
        " ^note y)}",
        "sp {b (state <s> ^operator.name inc ^n 1) --> (<s> ^note x -)}",
    ],
    "goal-removal": [
        "sp {p (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name a)}",
        "sp {q (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name b)}",
        "sp {t (state <s> ^impasse tie ^superstate <ss> ^item <i>) (<i> ^name a)"
        " --> (<s> ^local yes) (<ss> ^operator <i> >)}",
        "sp {ap (state <s> ^operator.name a) --> (<s> ^done yes)}",
    ],
}


def assert_same(rules: list[str], path: Path | None, level: int, decisions: int,
                inputs: oracle.Inputs = ()) -> str:
    theirs = kernel_trace(rules, path, level, decisions, inputs)
    assert our_trace(rules, path, level, decisions, inputs) == theirs
    return theirs


@pytest.mark.parametrize("level", [4, 5])
@pytest.mark.parametrize("name", FILES)
def test_agent_files_trace_as_the_kernel(name: str, level: int) -> None:
    path = AGENTS / f"{name}.soar"
    spec = oracle.read_spec(path)
    trace = assert_same([], path, level, spec.decisions, spec.inputs)
    assert "=>WM: " in trace and ("\n+ (" in trace) == (level == 5)


@pytest.mark.parametrize("level", [4, 5])
@pytest.mark.parametrize("seed", [0, 1, 4, 5, 6, 8, 9, 10])
def test_generated_agents_trace_as_the_kernel(seed: int, level: int, tmp_path) -> None:
    path = tmp_path / "agent.soar"
    path.write_text(generated_agent(seed))
    assert_same([], path, level, 15)


@pytest.mark.parametrize("level", [4, 5])
@pytest.mark.parametrize("name", ["hanoi", "blocks", "cups"])
def test_rule_files_trace_as_the_kernel(name: str, level: int) -> None:
    """rules/: hanoi with three disks, blocks and cups without input (they wait)."""
    inputs = (("disks", 3),) if name == "hanoi" else ()
    assert_same([], HERE.parents[1] / "rules" / f"{name}.soar", level, 40, inputs)


@pytest.mark.parametrize("level", [4, 5])
def test_a_generated_substate_agent_traces_as_the_kernel(level: int, tmp_path) -> None:
    path = tmp_path / "agent.soar"
    path.write_text(generated_substate_agent(3))
    assert_same([], path, level, 20)


@pytest.mark.parametrize("level", [2, 3, 4, 5])
@pytest.mark.parametrize("name", sorted(CORNERS))
def test_corners_trace_as_the_kernel(name: str, level: int) -> None:
    assert_same(CORNERS[name], None, level, 4)


def test_the_rules_read_off_the_kernel_hold() -> None:
    """The texts the module docstring describes, as the kernel printed them."""
    batch = kernel_trace(CORNERS["batch-order"], None, 5, 1)
    assert ("+ (S1 ^y 1 +) (b)\n+ (S1 ^y 2 +) (b)\n+ (S1 ^y 3 +) (b)\n"
            "=>WM: (19: S1 ^y 3)\n=>WM: (18: S1 ^y 2)\n=>WM: (17: S1 ^y 1)\n") in batch
    assert kernel_trace(CORNERS["batch-order"], None, 1, 1).startswith("b3 b2 b1 ")
    assert "--- Decision Phase ---\n=>WM: (" in kernel_trace(CORNERS["halt-mid-phase"], None,
                                                              4, 2)
    halted = kernel_trace(CORNERS["halt-mid-phase"], None, 2, 3)
    assert halted.endswith("(PE) ---\n\nSystem halted.\nInterrupt received.This Agent halted.")
    writes = kernel_trace(CORNERS["writes-before-traces"], None, 5, 1)
    assert "hello\n+ (S1 ^x 1 +) (a)\n=>WM: (14: S1 ^x 1)\n" in writes
    assert "hello=>WM: (14: S1 ^x 1)\n" in kernel_trace(CORNERS["writes-before-traces"], None,
                                                         4, 1)
    supported = kernel_trace(CORNERS["already-supported"], None, 5, 4)
    assert "+ (S1 ^note x +  :O ) (a) ALREADY SUPPORTED ON TOP LEVEL.  IGNORING.\n" in supported
    assert "- (S1 ^note x +  :O ) (ai)\n- (S1 ^n 1 +  :O ) (a)\n" in supported
