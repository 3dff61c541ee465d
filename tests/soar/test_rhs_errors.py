"""Run-time errors of RHS functions and actions, printed as the Soar 9.6 kernel prints them.

When an action's function gets bad arguments the kernel prints ``Error: <text>`` and a
newline, naming no production, where the output stands: right after a ``write`` or the
watch-1 decision line (``xError: ...``), except that the messages of ``trim``,
``capitalize-symbol``, ``dont-learn``, ``force-learn`` and ``log`` start on a fresh line.
The action is dropped, the firing goes on. Every argument of a call is evaluated, each
failure reported, before the call is dropped. An action whose identifier is bound to a
constant is refused before its attribute and value are evaluated. Some bad arguments are
no error at all: ``int`` and ``float`` read strings as C's ``strtol``/``strtod`` do.

Every expected text below was printed by the real kernel (soar_sml 9.6); the live tests
run the same rules in both engines and compare the whole printed output and working memory.
"""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from sann.soar.agent import Agent
from sann.soar.decision import firing as firing_module

HEAD = "sp {{p (state <s> ^superstate nil ^type <c> ^io <io>) --> {}}}"

# An action of HEAD, and all the kernel prints in the decision that fires it (watch 0). At
# the start of a run the kernel's output column is not 0, so a fresh-line error starts with
# a newline there.
ERRORS = [
    ("(<s> ^r (+ a 1))", "Error: non-number (a) passed to + function\n"),
    ("(<s> ^r (+ 1 <s>))", "Error: non-number (S1) passed to + function\n"),
    ("(<s> ^r (+ |1| 1))", "Error: non-number (|1|) passed to + function\n"),
    ("(<s> ^r (- a))", "Error: non-number (a) passed to - function\n"),
    ("(<s> ^r (* 2 b a))", "Error: non-number (b) passed to * function\n"),
    ("(<s> ^r (/ 0 a))", "Error: non-number (a) passed to / function\n"),
    ("(<s> ^r (/ 1 2 0))", "Error: attempt to divide ('/') by zero.\n"),
    ("(<s> ^r (/ 0.0))", "Error: attempt to divide ('/') by zero.\n"),
    ("(<s> ^r (-))", "Error: '-' function called with no arguments\n"),
    ("(<s> ^r (/))", "Error: '/' function called with no arguments\n"),
    ("(<s> ^r (div 1.5 0))", "Error: non-integer (1.500000) passed to div function\n"),
    ("(<s> ^r (div 1 0))", "Error: attempt to divide ('div') by zero.\n"),
    ("(<s> ^r (mod 5 |a b|))", "Error: non-integer (|a b|) passed to mod function\n"),
    ("(<s> ^r (mod 1 0))", "Error: attempt to divide ('mod') by zero.\n"),
    ("(<s> ^r (abs <s>))", "Error: 'abs' function called with non-numeric argument S1\n"),
    ("(<s> ^r (sqrt |1|))", "Error: 'sqrt' function called with non-numeric argument |1|\n"),
    ("(<s> ^r (sin a))", "Error: 'sin' function called with non-numeric argument a\n"),
    ("(<s> ^r (cos |-|))", "Error: 'cos' function called with non-numeric argument |-|\n"),
    ("(<s> ^r (atan2 |<x>| 1))", "Error: non-number (|<x>|) passed to atan2\n"),
    ("(<s> ^r (atan2 1 a))", "Error: non-number (a) passed to atan2\n"),
    ("(<s> ^r (min a 1))", "Error: non-number (a) passed to min function\n"),
    ("(<s> ^r (max 1 |S1|))", "Error: non-number (|S1|) passed to max function\n"),
    ("(<s> ^r (int <s>))", "Error: identifier (S1) passed to 'int' RHS function.\n"),
    ("(<s> ^r (int |99999999999999999999|))",
     "Error: bad integer (|99999999999999999999|) given to 'int' RHS function\n"),
    ("(<s> ^r (int |-9223372036854775809|))",
     "Error: bad integer (|-9223372036854775809|) given to 'int' RHS function\n"),
    ("(<s> ^r (float <s>))", "Error: identifier (S1) passed to 'float' RHS function.\n"),
    ("(<s> ^r (float |1e999|))", "Error: bad float (1e999) given to 'float' RHS function\n"),
    ("(<s> ^r (float |-1e999 x|))",
     "Error: bad float (|-1e999 x|) given to 'float' RHS function\n"),
    ("(<s> ^r (float |1e-320|))", "Error: bad float (1e-320) given to 'float' RHS function\n"),
    ("(<s> ^r (float |2.2250738585072012e-308|))",
     "Error: bad float (|2.2250738585072012e-308|) given to 'float' RHS function\n"),
    ("(<s> ^r (size |1|))", "Error: non-symbol (|1|) passed to size function\n"),
    ("(<s> ^r (sum a))", "Error: non-symbol (a) passed to sum function\n"),
    ("(<s> ^r (compute-heading 0 0 0 |1|))",
     "Error: non-number (|1|) passed to - compute-heading\n"),
    ("(<s> ^r (compute-range 0 <s> 0 0))", "Error: non-number (S1) passed to - compute-range\n"),
    ("(<s> ^r (rand-int a))", "Error: non-number (a) passed to - rand-int\n"),
    ("(<s> ^r (rand-float |1.5|))", "Error: non-number (|1.5|) passed to - rand-float\n"),
    ("(<s> ^r (haversine a 0 0 0))", "Error: non int/float (a) passed to haversine function.\n"),
    ("(<s> ^r (extrapolate-x-position 10 1.5 5 2))",
     "Error: non int(1.500000) passed to extrapolate-x-position function.\n"),
    ("(<s> ^r (compute-dice-probability 5 6 2 foo))",
     "Error: invalid string (foo) passed as 'pred' to - compute-dice-probability\n"),
    ("(<s> ^r (trim 5))", "\nError: non-symbol (5) passed to 'trim' function.\n"),
    ("(<s> ^r (trim <s>))", "\nError: non-symbol (S1) passed to 'trim' function.\n"),
    ("(<s> ^r (capitalize-symbol 1.5))",
     "\nError: non-symbol (1.500000) passed to capitalize-symbol function.\n"),
    ("(dont-learn |a b|)", "\nError: non-identifier (|a b|) passed to dont-learn function.\n"),
    ("(force-learn <io>)", "\nError: identifier passed to force-learn is not a state: I1.\n"),
    ("(log |1| x)", "\nError: First argument of agent's (log) rhs-function must be an integer"
     " channel number between 1 and 100.  |1| is invalid.\n"),
    ("(log 1.0 x)", "\nError: First argument of agent's (log) rhs-function must be an integer"
     " channel number between 1 and 100.  1.000000 is invalid.\n"),
]  # fmt: skip

# Bad arguments the kernel takes without a word, and what it makes of them.
VALUES = [
    ("(write (int a) | | (int |12abc|) | | (int |1e5|) | | (int ||) | | (int |  -5x|)"
     " | | (int |0x10|) | | (int 1e300))", "0 12 1 0 -5 0 1"),
    ("(write (int (float |inf|)) | | (int (float |nan|)) | | (int (float |-1e19|)))",
     "-9223372036854775808 -9223372036854775808 -9223372036854775808"),
    ("(write (float a) | | (float |2.5x|) | | (float |0x1p3|) | | (float | -.5e1x|)"
     " | | (float |0x1p-1074|) | | (float |infinit|) | | (float |nanx|))",
     "0.000000 2.500000 8.000000 -5.000000 0.000000 inf nan"),
    ("(write (float |-nan|) | | (sqrt -1) | | (sqrt -0.0) | | (sin (float |inf|))"
     " | | (cos (float |-inf|)) | | (+ (float |inf|) (float |-inf|)))",
     "-nan -nan -0.000000 -nan -nan -nan"),
    ("(write (round-off 1.5 0.0) | | (round-off a 1) | | (round-off <s> 1.0)"
     " | | (round-off-heading a 10))", "-nan 0 0.000000 0"),
    ("(write (min) | | (max) | | (+) | | (*) | | (abs -9223372036854775808) | | (atan2 0 0))",
     "0 0 0 1 -9223372036854775808 0.000000"),
    ("(write (strlen 5) | | (strlen <s>) | | (trim |  a b  |) | | (set-count a))",
     "1 2 a b |ERROR: First parameter needs to be an identifier.|"),
]  # fmt: skip

# Several actions of HEAD in one firing: errors between writes, fresh-line errors, failed
# arguments of one call, identifiers bound to constants. All the kernel prints (watch 0).
FIRINGS = [
    ("(<s> ^x (+ a 1)) (<s> ^y (/ 1 0)) (write |after|)",
     "Error: non-number (a) passed to + function\nError: attempt to divide ('/') by zero.\n"
     "after"),
    ("(write |x|) (<s> ^r (+ a 1)) (write |y|)", "xError: non-number (a) passed to + function\ny"),
    ("(write |x|) (<s> ^r (trim 5)) (write |y|)",
     "x\nError: non-symbol (5) passed to 'trim' function.\ny"),
    ("(write |x| (crlf)) (<s> ^r (trim 5) ^q (capitalize-symbol 6) ^t (+ a 1))",
     "x\nError: non-symbol (5) passed to 'trim' function.\n"
     "Error: non-symbol (6) passed to capitalize-symbol function.\n"
     "Error: non-number (a) passed to + function\n"),
    ("(<s> ^r (+ a 1)) (<s> ^q (trim 5)) (write |z|) (dont-learn 5) (write |w| (crlf))"
     " (force-learn a)",
     "Error: non-number (a) passed to + function\n"
     "Error: non-symbol (5) passed to 'trim' function.\n"
     "z\nError: non-identifier (5) passed to dont-learn function.\nw\n"
     "Error: non-identifier (a) passed to force-learn function.\n"),
    ("(write |a| (+ a 1) (/ 1 0) (trim 3) |b|) (write |c|)",
     "Error: non-number (a) passed to + function\nError: attempt to divide ('/') by zero.\n"
     "Error: non-symbol (3) passed to 'trim' function.\nc"),
    ("(<s> ^r (+ (+ a 1) (- (* b 2)) (trim 3)) ^q 2)",
     "Error: non-number (a) passed to + function\nError: non-number (b) passed to * function\n"
     "Error: non-symbol (3) passed to 'trim' function.\n"),
    ("(<s> ^r (concat (+ a 1) x (div 1 0)) ^q (int <s>)) (write |.|)",
     "Error: non-number (a) passed to + function\nError: attempt to divide ('div') by zero.\n"
     "Error: identifier (S1) passed to 'int' RHS function.\n."),
    ("(write |x|) (<c> ^b (+ a 1)) (write |y|)",
     "xError: RHS of action           ([RETE-loc] ^b (+ a 1) +) makes a preference for state"
     " (not an identifier)\ny"),
    ("(<s> ^r <n>) (<c> ^b <n> ^|a b| 1.5 ^d (concat x (+ 1 <io>)) -)",
     "Error: RHS of action           ([RETE-loc] ^b <unbound-variable> +) makes a preference"
     " for state (not an identifier)\n"
     "Error: RHS of action           ([RETE-loc] ^|a b| 1.500000 +) makes a preference"
     " for state (not an identifier)\n"
     "Error: RHS of action           ([RETE-loc] ^d (concat x (+ 1 [RETE-loc])) -) makes a"
     " preference for state (not an identifier)\n"),
    ("(<c> ^operator <io> > <s>) (<c> ^operator <io> = 5.5) (<c> ^e <new>) (<new> ^f 1)",
     "Error: RHS of action           ([RETE-loc] ^operator [RETE-loc] > [RETE-loc]) makes a"
     " preference for state (not an identifier)\n"
     "Error: RHS of action           ([RETE-loc] ^operator [RETE-loc] = 5.500000) makes a"
     " preference for state (not an identifier)\n"
     "Error: RHS of action           ([RETE-loc] ^e <unbound-variable> +) makes a preference"
     " for state (not an identifier)\n"),
]  # fmt: skip

# Errors in operator application and elaboration, between writes and the decision trace.
OPERATOR_AGENT = """
sp {propose (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name go)}
sp {apply (state <s> ^operator.name go) --> (<s> ^done t) (<s> ^bad (+ a 1))
    (write |applied| (crlf)) (<s> ^worse (trim 5)) (write |end|)}
sp {elab (state <s> ^done t) --> (<s> ^x (/ 1 0) ^y (capitalize-symbol 5) ^z 1)
    (write (div 1 0) |no|)}
"""

# The same errors in every firing of rules that fire more than 100 times: their actions are
# compiled (`instantiation.COMPILE_AFTER`) part way through the run.
COUNTING_AGENT = """
sp {propose*init (state <s> ^superstate nil -^n) --> (<s> ^operator <o> +) (<o> ^name init)}
sp {apply*init (state <s> ^operator.name init) --> (<s> ^n 0 ^name count)}
sp {propose (state <s> ^n <n> < 120) --> (<s> ^operator <o> +) (<o> ^name inc ^n <n>)}
sp {apply (state <s> ^operator <o> ^n <n> ^name <c>) (<o> ^name inc)
   --> (<s> ^n <n> - (+ <n> 1)) (<s> ^bad (/ <n> 0) ^worse (+ (div <n> 0) (trim <n>) <o> (abs x)))
       (write |n=| <n>) (<c> ^q (+ a 1) ^r <new>) (write (concat (- x) <n>) (crlf))
       (<s> ^k (int <s>)) (<s> ^t (float |1e-400|)) (<s> ^u (capitalize-symbol <n>))
       (<new> ^v (sqrt <new>)) (write |;|)}
sp {elab (state <s> ^n <n>) --> (<s> ^m (* <n> x)) (<s> ^ok (sqrt 4))}
"""


def ours(rules: list[str], run: str = "run 1", watch: int = 0) -> tuple[str, str]:
    """What our engine prints while running, and then its top state."""
    out = io.StringIO()
    agent = Agent(out=out)
    for rule in rules:
        agent.load(rule)
    agent.load(f"watch {watch}")
    out.seek(0)
    out.truncate()
    agent.load(run)
    return out.getvalue(), agent.print("S1")


def split(text: str) -> list[str]:
    return ["sp {" + rule.strip() for rule in text.split("sp {") if rule.strip()]


@pytest.mark.parametrize(("action", "printed"), ERRORS + FIRINGS)
def test_errors_print_the_kernels_lines(action: str, printed: str) -> None:
    output, top = ours([HEAD.format(action)])
    assert output == printed
    if (action, printed) in ERRORS:
        assert " ^r " not in top  # the failed action made nothing


@pytest.mark.parametrize(("action", "written"), VALUES)
def test_bad_arguments_the_kernel_takes_make_its_values(action: str, written: str) -> None:
    assert ours([HEAD.format(action)])[0] == written


def test_compiled_actions_print_what_interpreted_ones_do(monkeypatch: pytest.MonkeyPatch):
    runs = []
    for compile_after in (1, 10**9):
        monkeypatch.setattr(firing_module, "COMPILE_AFTER", compile_after)
        runs.append(ours(split(COUNTING_AGENT), "run 125", watch=1))
    assert runs[0] == runs[1]
    assert runs[0][0].count("Error: RHS of action") == 2 * 120  # two per firing of apply


# ------------------------------------------------------------- against the kernel


def theirs(kernel, rules: list[str], run: str = "run 1", watch: int = 0) -> tuple[str, str]:
    """What the kernel prints while running (its print events), and then its top state."""
    with kernel.KernelAgent() as ka:
        for rule in rules:
            ka.cmd(rule)
        ka.cmd(f"watch {watch}")
        ka.take_log()
        ka.agent.ExecuteCommandLine(run)
        return ka.take_log(), ka.agent.ExecuteCommandLine("print s1")


@pytest.mark.parametrize(("action", "printed"), ERRORS + FIRINGS)
def test_errors_agree_with_the_kernel(kernel, action: str, printed: str) -> None:
    rules = [HEAD.format(action)]
    assert theirs(kernel, rules)[0] == printed
    assert ours(rules) == theirs(kernel, rules)


@pytest.mark.parametrize(("action", "written"), VALUES)
def test_values_agree_with_the_kernel(kernel, action: str, written: str) -> None:
    rules = [HEAD.format(action)]
    assert theirs(kernel, rules)[0] == written
    assert ours(rules)[0] == written


@pytest.mark.parametrize("watch", [0, 1])
def test_errors_between_writes_and_the_trace_agree_with_the_kernel(kernel, watch: int):
    rules = split(OPERATOR_AGENT)
    printed = theirs(kernel, rules, "run 3", watch)
    assert ours(rules, "run 3", watch) == printed
    if watch == 1:  # the decision line is not ended before the error
        assert "     1:    O: O1 (go)Error: non-number (a) passed to + function\n" in printed[0]


@pytest.mark.parametrize("compile_after", [1, 100, 10**9])
def test_errors_of_compiled_actions_agree_with_the_kernel(
    kernel, monkeypatch: pytest.MonkeyPatch, compile_after: int
) -> None:
    monkeypatch.setattr(firing_module, "COMPILE_AFTER", compile_after)
    rules = split(COUNTING_AGENT)
    printed = theirs(kernel, rules, "run 125", watch=1)
    assert ours(rules, "run 125", watch=1) == printed
    assert printed[0].count("Error:") == 12 * 120 + 1  # apply's 11, elab's 1 per count


def test_the_agent_file_loads_in_both(kernel, tmp_path: Path) -> None:
    """The agents above are plain Soar: the kernel sources them without a complaint."""
    for text in (OPERATOR_AGENT, COUNTING_AGENT):
        path = tmp_path / "agent.soar"
        path.write_text(text)
        with kernel.KernelAgent() as ka:
            ka.cmd(f"source {path}")
        Agent().source(path)
