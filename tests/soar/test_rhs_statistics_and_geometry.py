"""The kernel's arithmetic over working memory (``sum``, ``product``, the ``set-*``
statistics), its positions (``haversine``, ``extrapolate-x/y-position``) and
``compute-dice-probability``.

Expected values in the tables were printed by the real kernel (soar_sml 9.6), 17 digits of a
float read through ``(string ...)``; the tests at the end run the same rules in the kernel
and in our engine and compare what they write, what they store and the errors they report.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import pytest

from sann.soar.agent import Agent
from sann.soar.errors import SoarRuntimeError, SoarSemanticError
from sann.soar.memory import Identifier
from sann.soar.rhs import FUNCTIONS
from sann.soar.rhs.wm import SET_COUNT_ERROR, SET_NAN
from sann.soar.text import format_value


def call(name: str, *args):
    return FUNCTIONS[name](None, list(args))  # type: ignore[arg-type]


def run(text: str, decisions: int = 1) -> tuple[Agent, str]:
    out = io.StringIO()
    agent = Agent(out=out)
    agent.load(text)
    agent.run(decisions)
    return agent, out.getvalue()


def written(init: str, action: str) -> str:
    """What ``action`` writes once ``init`` has built ``<l>`` (see `RULES`)."""
    return run(RULES.format(init=init, action=action))[1]


RULES = """
sp {{init (state <s> ^superstate nil) --> (<s> ^l <l>) {init}}}
sp {{p (state <s> ^superstate nil ^l <l>) --> {action}}}
"""


# ------------------------------------------------------------------ sum and product

# (WMEs of <l>, the kernel's (sum <l>) and (product <l>))
SUMS = [
    ("(<l> ^x 1 ^y 2 ^z 3)", 6, 6), ("(<l> ^x 2 ^x 3 ^y 4)", 9, 24), ("", 0, 1),
    ("(<l> ^x 2147483647 ^y 1)", -2147483648, 2147483647), ("(<l> ^x 10000000000)", 1410065408,
     1410065408), ("(<l> ^x 9223372036854775807 ^y 1)", 0, -1), ("(<l> ^x -5 ^y 3)", -2, -15),
    ("(<l> ^x 0.1)", -1717986918, -1717986918), ("(<l> ^x 2.0)", 0, 0),
    ("(<l> ^x 1.5 ^y 2)", 2, 0), ("(<l> ^x 65536 ^y 65536)", 131072, 0),
    ("(<l> ^x <i>)", 4, 4), ("(<l> ^x <i> ^y <j>)", 5, 4),
]  # fmt: skip


@pytest.mark.parametrize(("init", "total", "product"), SUMS)
def test_sum_and_product_read_values_as_the_kernel_does(init: str, total: int, product: int):
    assert written(init, "(write (sum <l>) | | (product <l>))") == f"{total} {product}"


def test_sum_of_the_top_state_counts_only_its_slots() -> None:
    """S1's ``^reward-link R1 ^epmem E1 ^smem L1`` read 1 each (measured: 3)."""
    assert run("sp {p (state <s> ^superstate nil) --> (write (sum <s>))}")[1] == "3"


def test_sum_refuses_what_the_kernel_refuses_and_strings_it_reads_garbage_for() -> None:
    for name in ("sum", "product"):
        with pytest.raises(
            SoarRuntimeError, match=rf"^non-symbol \(a\) passed to {name} function$"
        ):
            call(name, "a")
        with pytest.raises(SoarRuntimeError, match=r"non-symbol \(2\.500000\)"):
            call(name, 2.5)
    agent, _ = run(RULES.format(init="(<l> ^x 1 ^y a)", action="(<s> ^r (sum <l>))"))
    assert [w for w in agent.wmes() if w.attr == "r"] == []
    assert "memory address for the string value a" in agent.errors[0]


# ---------------------------------------------------------------------- set-*

SET_INIT = "(<l> ^x 1 ^x 2.5 ^x -4 ^y a ^y 3 ^z <z> ^e <e>) (<z> ^w 4 ^w 5)"
# (function, path) -> what the kernel writes for (f <l> path) with SET_INIT
SETS = {
    "set-sum": ["-0.500000", "3.000000", "9.000000", "NaN", "NaN"],
    "set-multiply": ["-10.000000", "3.000000", "20.000000", "NaN", "NaN"],
    "set-min": ["-4.000000", "3.000000", "4.000000", "NaN", "NaN"],
    "set-max": ["2.500000", "3.000000", "5.000000", "NaN", "NaN"],
    "set-range": ["6.500000", "0.000000", "1.000000", "NaN", "NaN"],
    "set-mean": ["-0.166667", "3.000000", "4.500000", "NaN", "NaN"],
    "set-stdev": ["2.778889", "0.000000", "0.500000", "NaN", "NaN"],
}
PATHS = ["x", "y", "z w", "z", ""]


@pytest.mark.parametrize("name", sorted(SETS))
def test_set_statistics_follow_the_path_and_skip_what_is_not_a_number(name: str) -> None:
    action = "(write " + " | | ".join(f"({name} <l> {path})" for path in PATHS) + ")"
    assert written(SET_INIT, action) == " ".join(SETS[name])


def test_set_statistics_count_a_value_once_per_path_and_return_the_string_nan() -> None:
    init = "(<l> ^a <a> ^a <b>) (<a> ^x <c>) (<b> ^x <c>) (<c> ^v 5 ^v 0.1) (<l> ^1 7 ^2.5 8)"
    action = (
        "(write (set-sum <l> a x v) | | (set-sum <l> 1) | | (set-sum <l> 2.5) | |"
        " (string (set-mean <l> a x v)) | | (string (set-stdev <l> a x v))"
        " | | (ifeq (set-sum <l> q) |NaN| yes no))"
    )
    assert written(init, action) == "10.200000 7.000000 8.000000 2.54999999999999982 " + (
        "2.44999999999999973 yes"
    )
    assert SET_NAN == "NaN" and call("set-max", "a", "x") == SET_COUNT_ERROR


# ------------------------------------------------------------------ positions

HAVERSINES = [
    ((0, 0, 0, 1), "111.19492664453066766"), ((0, 0, 1, 0), "111.19492664453066766"),
    ((0.0, 0.0, 1.0, 1.0), "157.24938127190429782"), ((0, 0, 0, 0), "0.00000000000000000"),
    ((42.28, -83.74, 40.71, -74.0), "829.27983309431488124"),
    ((90, 0, -90, 0), "20015.08679602057236480"),
    ((-22.553, -10.987, 1.517, 50.12), "7133.87636256280529778"),
    ((43.892, -15.089, -44.576, -88.474), "12216.49754135072544159"),
]  # fmt: skip


@pytest.mark.parametrize(("points", "distance"), HAVERSINES)
def test_haversine_to_the_last_bit(points: tuple, distance: str) -> None:
    assert call("string", call("haversine", *points)) == distance


# (x heading speed time) -> the kernel's x and y
EXTRAPOLATIONS = [
    ((0, 0, 1, 1), 0, -1), ((1, 2, 3, 4), 1, -11), ((10, 0, 5, 2), 10, 0),
    ((10, 90, 5, 2), 20, 10), ((0, 15, 10, 1), 3, -10), ((0, 75, 10, 1), 10, -3),
    ((0, 255, 10, 1), -10, 3), ((0, 30, -3, 1), -1, 3), ((0, 60, 3, 1), 3, -2),
    ((0, 0, 3000000000, 4), 0, 2147483648), ((0, 45, 2147483647, 2), -2147483648, 2147483648),
    ((2147483647, 90, 1, 1), 2147483648, 2147483647),
    ((9223372036854775807, 90, 1, 1), -9223372036854775808, 9223372036854775807),
    ((0, 4294967386, 10, 1), -2, None), ((0, 90, 4611686018427387905, 4), 4, None),
    ((0, 90, 65536, 65536), -2147483648, None),
]  # fmt: skip


@pytest.mark.parametrize(("args", "x", "y"), EXTRAPOLATIONS)
def test_extrapolate_positions_like_the_kernel(args: tuple, x: int, y: int | None) -> None:
    assert call("extrapolate-x-position", *args) == x
    if y is not None:
        assert call("extrapolate-y-position", *args) == y


# ------------------------------------------------------------------------ dice

# (dice sides count) -> what the kernel's (string ...) shows for eq ne lt gt le ge
DICE = [
    ((5, 6, 2), ["0.16075102880658437", "0.83924897119341568", "0.80375514403292181",
                 "0.03549382716049385", "0.96450617283950613", "0.19624485596707822"]),
    ((8, 6, 7), ["0.00002381496723061", "0.99997618503276942", "0.99997558965858868",
                 "0.00000000000000000", "0.99999940462581927", "0.00002441034141137"]),
    ((5.9, 6.9, 2.9), ["0.16075102880658437", "0.83924897119341568", "0.80375514403292181",
                       "0.03549382716049385", "0.96450617283950613", "0.19624485596707822"]),
    ((-5, 6, -7), ["0.00000000000000000", "1.00000000000000000", "0.00000000000000000",
                   "1.00000000000000000", "0.00000000000000000", "1.00000000000000000"]),
    ((5, 0, 0), ["0.00000000000000000", "1.00000000000000000", "0.00000000000000000",
                 "0.00000000000000000", "1.00000000000000000", "1.00000000000000000"]),
    ((0, 6, 0), ["1.00000000000000000", "0.00000000000000000", "0.00000000000000000",
                 "0.00000000000000000", "1.00000000000000000", "1.00000000000000000"]),
    ((20, 2, 1), ["0.00001907348632812", "0.99998092651367188", "0.00000000000000000",
                  "0.99997997283935547", "0.00002002716064453", "0.99999904632568359"]),
]  # fmt: skip
PREDICATES = ("eq", "ne", "lt", "gt", "le", "ge")


@pytest.mark.parametrize(("args", "shown"), DICE)
def test_dice_probabilities_like_the_kernel(args: tuple, shown: list[str]) -> None:
    """Equal as ``write`` shows them; to 1e-12 in the last digits, where the kernel's
    arithmetic is a few units in the last place off the exact binomial we round."""
    got = [call("compute-dice-probability", *args, p) for p in PREDICATES]
    assert [format_value(g) for g in got] == [format_value(float(s)) for s in shown]
    assert got == [pytest.approx(float(s), rel=1e-12, abs=0) for s in shown]


# ----------------------------------------------------------------------- errors

#: An action, and the error line the kernel prints for it (measured, text included).
ERRORS = [
    ("(<s> ^r (sum a))", "non-symbol (a) passed to sum function"),
    ("(<s> ^r (product 5))", "non-symbol (5) passed to product function"),
    ("(<s> ^r (haversine a 0 0 0))", "non int/float (a) passed to haversine function."),
    ("(<s> ^r (haversine 0 0 0 |1|))", "non int/float (|1|) passed to haversine function."),
    ("(<s> ^r (haversine 0 0 0 <s>))", "non int/float (S1) passed to haversine function."),
    ("(<s> ^r (extrapolate-x-position 10 1.5 5 2))",
     "non int(1.500000) passed to extrapolate-x-position function."),
    ("(<s> ^r (extrapolate-y-position 0 0 0 a))",
     "non int(a) passed to extrapolate-y-position function."),
    ("(<s> ^r (compute-dice-probability a b c d))",
     "non-number (a) passed as 'dice' to - compute-dice-probability"),
    ("(<s> ^r (compute-dice-probability 5 a 2 eq))",
     "non-number (a) passed as 'sides' to - compute-dice-probability"),
    ("(<s> ^r (compute-dice-probability 5 6 |2| eq))",
     "non-number (|2|) passed as 'count' to - compute-dice-probability"),
    ("(<s> ^r (compute-dice-probability 5 6 2 3))",
     "non-string (3) passed as 'pred' to - compute-dice-probability"),
    ("(<s> ^r (compute-dice-probability 5 6 2 foo))",
     "invalid string (foo) passed as 'pred' to - compute-dice-probability"),
]  # fmt: skip
ERROR_RULE = "sp {{p (state <s> ^superstate nil) --> {}}}"


@pytest.mark.parametrize(("action", "message"), ERRORS)
def test_bad_arguments_are_reported_with_the_kernels_words(action: str, message: str) -> None:
    agent, _ = run(ERROR_RULE.format(action))
    assert agent.errors == [f"Error: production p: {message}"]
    assert [w for w in agent.wmes() if w.attr == "r"] == []


LOAD_ERRORS = [
    ("(<s> ^v (sum <s> <s>))", "Wrong number of arguments to function sum (expected 1)"),
    ("(<s> ^v (product))", "Wrong number of arguments to function product (expected 1)"),
    ("(<s> ^v (haversine 1 2 3))", "Wrong number of arguments to function haversine (expected 4)"),
    ("(<s> ^v (compute-dice-probability 1 2 3))",
     "Wrong number of arguments to function compute-dice-probability (expected 4)"),
    ("(<s> ^v (extrapolate-x-position 1))",
     "Wrong number of arguments to function extrapolate-x-position (expected 4)"),
    ("(<s> ^v (extrapolate-y-position 1 2 3 4 5))",
     "Wrong number of arguments to function extrapolate-y-position (expected 4)"),
    ("(sum <s>)", "Function sum cannot be used as a stand-alone action"),
    ("(set-sum <s> a)", "Function set-sum cannot be used as a stand-alone action"),
    ("(set-stdev)", "Function set-stdev cannot be used as a stand-alone action"),
    ("(haversine 1 2 3 4)", "Function haversine cannot be used as a stand-alone action"),
]  # fmt: skip


@pytest.mark.parametrize(("action", "message"), LOAD_ERRORS)
def test_load_checks_arity_and_placement(action: str, message: str) -> None:
    with pytest.raises(SoarSemanticError, match=re.escape("production p: " + message)):
        Agent().load(ERROR_RULE.format(action))


def test_set_functions_take_any_number_of_arguments() -> None:
    Agent().load(ERROR_RULE.format("(<s> ^a (set-mean <s>) ^b (set-min <s> a b c d e f))"))


# ------------------------------------------------------------- against the kernel


AGENT = """
sp {init (state <s> ^superstate nil) --> (<s> ^l <l> ^m <m>)
    (<l> ^x 1 ^x 2.5 ^x -4 ^y a ^y 3 ^z <z> ^z <z2> ^n 65536 ^n 65536)
    (<z> ^w 4 ^w 5 ^v 0.5) (<z2> ^w 6 ^v 0.25) (<m> ^i 7 ^i 2147483647 ^f 0.1 ^id <k>)}
sp {values (state <s> ^superstate nil ^l <l> ^m <m>) -->
    (<s> ^sum (sum <m>) ^product (product <m>) ^ssum (set-sum <l> x) ^smul (set-multiply <l> z w)
         ^smin (set-min <l> z w) ^smax (set-max <l> x) ^srange (set-range <l> n)
         ^smean (set-mean <l> z v) ^sdev (set-stdev <l> z w) ^snan (set-mean <l> y q)
         ^serr (set-sum abc x) ^hav (haversine 42.28 -83.74 40.71 -74.0)
         ^ex (extrapolate-x-position 3 37 12 5) ^ey (extrapolate-y-position 3 37 12 5)
         ^dice (compute-dice-probability 10 6 3 ge) ^dice2 (compute-dice-probability 6 4 1 lt))
    (write (sum <m>) | | (product <m>) | | (string (set-mean <l> x)) | | (set-sum <l> z w) | |
           (string (set-stdev <l> z w)) | | (set-range <l> x) | | (set-min <l> y) | |
           (set-multiply <l> n) | | (string (haversine -63.637 39.39 -61.159 36.829)) | |
           (extrapolate-x-position -40 -200 7 9) | | (extrapolate-y-position -40 -200 7 9) | |
           (compute-dice-probability 12 6 3 eq) | | (compute-dice-probability 13 6 2 le) | |
           (compute-dice-probability 20 2 0 le) (crlf))}
sp {done (state <s> ^dice) --> (halt)}
"""


def test_the_functions_agree_with_the_kernel(kernel, tmp_path: Path) -> None:
    path = tmp_path / "math.soar"
    path.write_text(AGENT)
    kernel.assert_agree(path, decisions=5)


@pytest.mark.parametrize(("init", "total", "product"), SUMS[:6] + SUMS[-2:])
def test_sums_agree_with_the_kernel(kernel_writes, init: str, total: int, product: int) -> None:
    action = "(write (sum <l>) | | (product <l>))"
    assert kernel_writes(RULES.format(init=init, action=action)) == written(init, action)


@pytest.mark.parametrize("name", sorted(SETS))
def test_set_statistics_agree_with_the_kernel(kernel_writes, name: str) -> None:
    action = "(write " + " | | ".join(f"({name} <l> {path})" for path in PATHS) + ")"
    theirs = kernel_writes(RULES.format(init=SET_INIT, action=action))
    assert written(SET_INIT, action) == theirs


@pytest.mark.parametrize(("args", "shown"), DICE)
def test_dice_agree_with_the_kernel(
    kernel_writes, our_writes, args: tuple, shown: list[str]
) -> None:
    words = " ".join(map(str, args))
    calls = [f"(compute-dice-probability {words} {p})" for p in PREDICATES]
    rule = ERROR_RULE.format("(write " + " | | ".join(calls) + ")")
    assert kernel_writes(rule) == our_writes(rule)
    exact = ERROR_RULE.format("(write " + " | | ".join(f"(string {c})" for c in calls) + ")")
    assert kernel_writes(exact) == " ".join(shown)


def test_positions_agree_with_the_kernel(kernel_writes, our_writes) -> None:
    calls = [f"(string (haversine {' '.join(map(str, p))}))" for p, _ in HAVERSINES]
    for args, _, y in EXTRAPOLATIONS:
        words = " ".join(map(str, args))
        calls.append(f"(extrapolate-x-position {words})")
        if y is not None:
            calls.append(f"(extrapolate-y-position {words})")
    rule = ERROR_RULE.format("(write " + " | | ".join(calls) + ")")
    assert kernel_writes(rule) == our_writes(rule)


def test_errors_agree_with_the_kernel(kernel_writes) -> None:
    for action, message in ERRORS:
        theirs = kernel_writes(ERROR_RULE.format(action))
        assert theirs.strip() == f"Error: {message}", action
        agent, _ = run(ERROR_RULE.format(action))
        assert agent.errors == [f"Error: production p: {message}"], action


def test_load_checks_agree_with_the_kernel(kernel) -> None:
    with kernel.KernelAgent() as ka:
        for action, message in LOAD_ERRORS:
            result = ka.agent.ExecuteCommandLine(ERROR_RULE.format(action))
            assert not ka.agent.GetLastCommandLineResult(), action
            assert result.splitlines()[0] == message
        ka.cmd(ERROR_RULE.format("(<s> ^a (set-mean <s>) ^b (set-min <s> a b c d e f))"))


def test_format_value_of_the_nan_symbol_is_its_text() -> None:
    assert format_value(SET_NAN) == "NaN" and format_value(Identifier("S", 1)) == "S1"
