"""Details of the Soar 9.6 kernel, measured in soar_sml and compared live, whole output.

- The order of a production's actions: the kernel reorders them when it loads the rule
  (reorder.cpp's ``reorder_action_list``): again and again it takes the first remaining
  action that can run, one whose variables are bound (a make-action: its identifier and the
  variables inside its function calls; a function-call action: all its variables). A taken
  make-action binds every variable it holds. The kernel runs the actions in that order (what
  is written, which errors come first, which new identifier gets which number, timetags)
  and prints the rule in that order.
- How symbols are printed in working memory, traces and messages: a float as ``%f`` with
  the sign of a NaN (``-nan``); a string in vertical bars when it is empty, holds a
  character that is not a constituent (letters, digits, ``$%&*+-/:<=>?_@``), reads as an
  integer, identifier or variable, or is shorter than four characters with a constituent
  that is not a letter or digit (``*`` alone excepted).
- The watch-2 line ``\t--- Change Working Memory (PE) ---`` goes on the line a ``write``
  left unfinished (``applied\t--- Change Working Memory (PE) ---``).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
from side_by_side import ours, same, theirs

from sann.soar.agent import Agent
from sann.soar.decision import firing as firing_module
from sann.soar.errors import SoarError

HEAD = "sp {{p (state <s> ^superstate nil) --> {}}}"


# --------------------------------------------------------------------- 1. action order

# Actions of HEAD; each needs the kernel's order to print, number or timestamp as it does.
ORDERS = [
    "(write 1) (<s> ^a (+ a <new>)) (write 2) (<s> ^b <new>)",
    "(write 1) (<s> ^a (+ a (+ 1 <new>))) (write 2) (<s> ^b <new>) (write 3)",
    "(write 1 <new>) (write 2) (<s> ^b <new>)",
    "(write (concat (+ 1 <q>) x)) (<s> ^q <q>)",
    "(<s> ^c 1) (<s> ^a (concat <n> x)) (<s> ^b <n>) (<s> ^d 2) (<s> ^e (concat <m> y))"
    " (<s> ^f <m>)",
    "(<s> ^a (concat <n1> x)) (<s> ^b <n2>) (<s> ^c <n1>)",
    "(<s> ^a (concat <y> 1)) (<s> ^<y> 2)",
    "(<n> ^x (concat <s> 1)) (write <n>) (<s> ^n <n>)",
    "(<b> ^v 1) (write b) (<a> ^b <b>) (write a) (<s> ^a <a>)",
    "(<s> ^a <n>) (<n> ^b (concat <m> 1)) (<n> ^c <m>) (<m> ^d (make-constant-symbol <n>))",
    "(<s> ^operator <o> +) (<o> ^name (concat x <q>)) (<s> ^q <q>) (<o> ^r <q>)",
    "(<s> ^a <n> ^b (concat <n> 1)) (write (crlf) |x| <n>)",
]

_WM_LINE = re.compile(r"=>WM: \((\d+): [^)]*\)")


def wm_lines(trace: str) -> list[str]:
    """The ``=>WM:`` lines of a watch-4 trace by timetag (the kernel prints each wave's
    newest first, we oldest first; the timetags are what is compared)."""
    lines = [m.group(0) for m in _WM_LINE.finditer(trace)]
    return sorted(lines, key=lambda line: int(_WM_LINE.match(line).group(1)))  # type: ignore[union-attr]


@pytest.mark.parametrize("actions", ORDERS)
def test_actions_run_and_print_in_the_kernels_order(kernel, actions: str) -> None:
    rules = [HEAD.format(actions)]
    commands = ["print p", "watch 1", "run 2", "print --depth 3 s1"]
    same(kernel, rules, commands)


@pytest.mark.parametrize("actions", ORDERS)
def test_timetags_follow_the_kernels_order(kernel, actions: str) -> None:
    rules = [HEAD.format(actions)]
    commands = ["watch 4", "run 1"]
    expected = theirs(kernel, rules, commands)[1]
    assert wm_lines(ours(rules, commands)[1]) == wm_lines(expected)
    assert len(wm_lines(expected)) > 3


def test_the_first_example_prints_as_the_kernel(kernel) -> None:
    rules = [HEAD.format(ORDERS[0])]
    printed = same(kernel, rules, ["run 1", "print p"])
    assert printed[0] == "12Error: non-number (a) passed to + function\n"
    assert "(write 1)\n    (write 2)\n    (<s> ^b <new> ^a (+ a <new>))\n}" in printed[1]


@pytest.mark.parametrize("compile_after", [1, 10**9])
def test_compiled_actions_keep_the_kernels_order(
    kernel, monkeypatch: pytest.MonkeyPatch, compile_after: int
) -> None:
    monkeypatch.setattr(firing_module, "COMPILE_AFTER", compile_after)
    rules = [
        "sp {propose (state <s> ^n <n> < 5) --> (<s> ^operator <o> +) (<o> ^name inc)}",
        "sp {inc (state <s> ^operator <o> ^n <n>) (<o> ^name inc) --> (write |[| <n>)"
        " (<s> ^n <n> - (+ <n> 1)) (<s> ^m (+ <new> <n>)) (<s> ^k <new>) (write |]|)}",
        "sp {init (state <s> ^superstate nil) --> (<s> ^n 0)}",
    ]
    printed = same(kernel, rules, ["watch 1", "run 8", "print inc", "print --depth 2 s1"])
    assert "(inc)[0Error: non-number (N1) passed to + function\n]\n" in printed[1]


#: The kernel, asked in a process of its own: refusing an ungrounded action leaves its action
#: printer's indentation changed for the rest of the process (measured: every later "RHS of
#: action ... (not an identifier)" error loses its padding), which would leak into the other
#: tests sharing this process's kernel.
REFUSAL = """
import sys
sys.path.insert(0, sys.argv[1])
from differential import kernel
with kernel.KernelAgent() as ka:
    try:
        ka.cmd(sys.argv[2])
    except RuntimeError as error:
        print(error)
"""


def test_an_action_that_can_never_run_is_refused_by_both(kernel) -> None:
    rule = HEAD.format("(<s> ^<x> (concat <y> 1)) (<s> ^<y> (concat <x> 1))")
    tests = str(Path(__file__).resolve().parent)
    done = subprocess.run([sys.executable, "-c", REFUSAL, tests, rule], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "ungrounded action" in done.stdout
    with pytest.raises(SoarError, match="neither tested"):
        Agent().load(rule)


# --------------------------------------------------------------------- 2. printed symbols

# Values written by a rule, and what the kernel prints for each (measured).
SYMBOLS = [
    ("(sqrt -1)", "-nan"), ("(- (sqrt -1))", "nan"), ("(float |inf|)", "inf"),
    ("(float |-inf|)", "-inf"), ("-0.0", "-0.000000"), ("1.5", "1.500000"),
    ("(concat S1 1.5)", "|S11.500000|"), ("|S11.5000001|", "|S11.5000001|"), ("|S1|", "|S1|"),
    ("|s1|", "|s1|"), ("|z99999999999999999999|", "|z99999999999999999999|"),
    ("|S1a|", "S1a"), ("|AB1|", "AB1"), ("|1|", "|1|"), ("|-1|", "|-1|"), ("|+1|", "|+1|"),
    ("|00|", "|00|"), ("|1.5|", "|1.5|"), ("|1.|", "|1.|"), ("|.5|", "|.5|"),
    ("|1e5|", "1e5"), ("|1e+|", "|1e+|"), ("|1e-7|", "1e-7"), ("|0x10|", "0x10"),
    ("|<x>|", "|<x>|"), ("|<x|", "|<x|"), ("|x>|", "|x>|"), ("|<abcd|", "<abcd"),
    ("|<ab>c|", "<ab>c"), ("|a b|", "|a b|"), ("|A|", "A"), ("|a-b|", "|a-b|"),
    ("|a-bc|", "a-bc"), ("|-->|", "|-->|"), ("|--->|", "--->"), ("|<=>a|", "<=>a"),
    ("|*|", "*"), ("|**|", "|**|"), ("|***|", "|***|"), ("|****|", "****"), ("|$|", "|$|"),
    ("|a_b|", "|a_b|"), ("|a_bc|", "a_bc"), ("|@|", "|@|"), ("|^|", "|^|"), ("|a.b|", "|a.b|"),
    ("|a,bcd|", "|a,bcd|"), ("|é|", "|é|"), ("||", "||"), ("|a\\|b|", "|a\\|b|"),
    ("|a\\\\b|", "|a\\\\b|"), ("|state|", "state"), ("|nan|", "nan"),
]  # fmt: skip


@pytest.mark.parametrize(("value", "printed"), SYMBOLS)
def test_symbols_print_as_the_kernels(kernel, value: str, printed: str) -> None:
    rules = [HEAD.format(f"(<s> ^operator <o> + ^v {value}) (<o> ^name {value} ^{value} 1)")]
    output = same(kernel, rules, ["watch 1", "run 1", "print --depth 2 s1"])
    assert f"O: O1 ({printed})" in output[1]
    assert f" ^v {printed}" in output[2].replace("\n      ", "")
    assert f" ^{printed} 1" in output[2].replace("\n      ", "")
    expected = theirs(kernel, rules, ["watch 4", "run 1"])[1]
    assert wm_lines(ours(rules, ["watch 4", "run 1"])[1]) == wm_lines(expected)
    assert f"^v {printed})" in expected


def test_an_error_shows_a_string_as_the_kernel(kernel) -> None:
    rules = [HEAD.format("(<s> ^r (+ |a-b| 1) ^q (- |1e5|) ^t (* |x.y|))")]
    printed = same(kernel, rules, ["run 1"])
    assert printed[0] == (
        "Error: non-number (|a-b|) passed to + function\n"
        "Error: non-number (1e5) passed to - function\n"
        "Error: non-number (|x.y|) passed to * function\n"
    )


# ----------------------------------------------------- 4. phase headers after a write

# Writes that do not end their line, in the application phase of the top state and of a
# substate (an operator no-change impasse).
WRITING_AGENT = [
    "sp {propose (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name go)"
    " (write |prop|)}",
    "sp {apply (state <s> ^operator.name go) --> (<s> ^done t) (write |applied|)}",
    "sp {elab (state <s> ^done t) --> (write |elab|)}",
    "sp {out (state <s> ^done t ^io.output-link <ol>) --> (<ol> ^x 1) (write |out| (crlf))}",
    "sp {sub*propose (state <s> ^superstate <ss>) (<ss> ^operator.name stay -^result)"
    " --> (<s> ^operator <o> +) (<o> ^name inner)}",
    "sp {sub*apply (state <s> ^operator.name inner ^superstate <ss>) --> (<ss> ^result 1)"
    " (write |inner|)}",
    "sp {top*stay (state <s> ^superstate nil ^done t) --> (<s> ^operator <o> +) (<o> ^name stay)}",
    "sp {top*result (state <s> ^result 1) --> (write |result|)}",
]


@pytest.mark.parametrize("watch", [1, 2, 3])
def test_phase_headers_after_a_partial_line_agree_with_the_kernel(kernel, watch: int) -> None:
    printed = same(kernel, WRITING_AGENT, [f"watch {watch}", "run 6", "print --depth 2 s1"])
    if watch >= 2:
        assert "applied\t--- Change Working Memory (PE) ---\n" in printed[1]
        assert "inner\t--- Change Working Memory (PE) ---\n" in printed[1]
    if watch == 2:
        assert "elabout\n\t--- Change Working Memory (IE) ---\n" in printed[1]


# ------------------------------------------------- 5. halt and interrupt messages

# The kernel prints its stop messages at every watch level, when the run stops at the end of
# the phase: '\nSystem halted.\nInterrupt received.This Agent halted.' after (halt), once;
# 'Interrupt received.' after (interrupt), after '\n\n' when the run has no decision limit
# or the interrupt came in its last decision; the goal-depth guard's message, then
# '\nSystem halted.\nInterrupt received.Interrupt received.'.
PROPOSE_GO = "sp {prop (state <s> ^superstate nil) --> (<s> ^operator <o> +) (<o> ^name go)}"
IN_SUBSTATE = "sp {s (state <s> ^superstate <ss>) (<ss> ^superstate nil) --> {}}"
STOPPING = {
    "halt": [HEAD.format("(write |bye|) (halt)")],
    "halt-crlf": [HEAD.format("(write |bye| (crlf)) (halt)")],
    "interrupt": [HEAD.format("(write |bye|) (interrupt)")],
    "halt-interrupt": [HEAD.format("(write |bye|) (interrupt) (halt)")],
    "two-halts": [HEAD.format("(write |bye|) (halt)"), HEAD.replace("{p ", "{q ").format("(halt)")],
    "apply-halt": [PROPOSE_GO, "sp {app (state <s> ^operator.name go) --> (write |a|) (halt)}"],
    "apply-interrupt": [
        PROPOSE_GO, "sp {app (state <s> ^operator.name go) --> (write |a|) (interrupt)}"
    ],
    "substate-halt": [IN_SUBSTATE.replace("{}", "(write |sub|) (halt)")],
    "substate-interrupt": [IN_SUBSTATE.replace("{}", "(write |sub|) (interrupt)")],
    "goal-depth": ["max-goal-depth 3"],
    "nothing": [],
}
RUNS = [["run 5", "run 1"], ["run 1", "run 5"], ["run 2", "run 1"], ["run"]]


@pytest.mark.parametrize("runs", RUNS, ids=" ".join)
@pytest.mark.parametrize("watch", [0, 1, 2])
@pytest.mark.parametrize("case", list(STOPPING))
def test_halt_and_interrupt_messages_agree_with_the_kernel(
    kernel, case: str, watch: int, runs: list[str]
) -> None:
    if case == "nothing" and "run" in runs:
        pytest.skip("runs forever")
    printed = same(kernel, STOPPING[case], [f"watch {watch}", *runs])
    if case == "halt" and watch < 2:
        assert printed[1] == "bye\nSystem halted.\nInterrupt received.This Agent halted."
        assert printed[2:] in ([], [""])
    if case == "interrupt" and watch == 0 and runs == ["run 5"]:
        assert printed[1] == "byeInterrupt received."


WIDE = "sp {wide (state <s> ^superstate nil) --> (<s> " + " ".join(
    f"^attribute{i} value{i}" for i in range(12)) + ")}"


@pytest.mark.parametrize("runs", [["run 5"], ["run 1"], ["run"]], ids=" ".join)
@pytest.mark.parametrize("case", ["halt", "halt-crlf", "interrupt", "apply-halt"])
def test_a_print_after_a_stop_wraps_where_the_kernels_does(kernel, case: str, runs) -> None:
    """'Interrupt received.' and 'This Agent halted.' leave the kernel's output column where
    it was, so a print after them wraps as if they were not there."""
    if case == "halt-crlf" and runs == ["run"]:
        pytest.skip("same as halt")
    same(kernel, [WIDE, *STOPPING[case]], [*runs, "print --depth 1 S1"])


# ------------------------------------------------- 6. run N after an interrupt

# A counter agent whose go operator is interrupted in its apply phase (count 3), or in the
# apply phase of a substate (count 2); it halts at 12.
COUNTER = [
    "sp {init (state <s> ^superstate nil -^count) --> (<s> ^operator <o> + >) (<o> ^name init)}",
    "sp {inita (state <s> ^operator.name init) --> (<s> ^count 0)}",
    "sp {prop (state <s> ^superstate nil ^count <c>) --> (<s> ^operator <o> +) (<o> ^name go)}",
    "sp {app (state <s> ^operator.name go ^count <c>) --> (<s> ^count <c> - (+ <c> 1))}",
    "sp {stop (state <s> ^superstate nil ^count 12) --> (halt)}",
]
INTERRUPTS = {
    "apply": "sp {int (state <s> ^operator.name go ^count 3) --> (interrupt)}",
    "substate": "sp {int (state <s> ^superstate.count 2) --> (interrupt)}",
}


@pytest.mark.parametrize("runs", [["run", "run 1", "run 1"], ["run", "run 2", "run 1"],
                                  ["run", "run 3", "run 2"], ["run 6", "run 4", "run"]],
                         ids=" ".join)
@pytest.mark.parametrize("where", list(INTERRUPTS))
def test_run_n_after_an_interrupt_in_an_apply_phase_counts_as_the_kernel(
    kernel, where: str, runs: list[str]
) -> None:
    """The rest of the interrupted cycle is one of the next run's N decisions (the watch-1
    text of every run compared: its decision lines and stop messages)."""
    printed = same(kernel, [*COUNTER, INTERRUPTS[where]], ["watch 1", *runs])
    if where == "apply" and runs[1] == "run 2":
        assert printed[2] == "\n     5:    O: O5 (go)"  # one decision, as after run 1
