"""The RHS functions the kernel has beyond arithmetic and text: random numbers, symbols,
headings, working-memory counts and stand-alone actions, plus the kernel's load-time checks of
where a function is called and with how many arguments.

Expected values in the tables were printed by the real kernel (soar_sml 9.6); the tests at the
end run the same rule text in the kernel and in our engine and compare them live.
"""

from __future__ import annotations

import io
import re
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from sann.soar.agent import Agent
from sann.soar.errors import SoarRuntimeError, SoarSemanticError
from sann.soar.memory import Identifier
from sann.soar.parsing.actions import KNOWN_RHS_FUNCTIONS
from sann.soar.parsing.parser import parse
from sann.soar.rhs import FUNCTIONS
from sann.soar.rhs.rand import kernel_random
from sann.soar.rhs.wm import SET_COUNT_ERROR
from sann.soar.text import format_value


class Ctx:
    """An RHS context with the kernel's generator after ``srand 7`` and no working memory."""

    def __init__(self, seed: int = 7) -> None:
        self.exploration = SimpleNamespace(rng=kernel_random(seed))
        self.written: list[str] = []

    def write_output(self, text: str) -> None:
        self.written.append(text)

    def wmes(self) -> list:
        return []


def call(name: str, *args, ctx: Ctx | None = None):
    return FUNCTIONS[name](ctx or Ctx(), list(args))


def draws(call_text: str, times: int = 6, seed: int = 7) -> str:
    """What ``(write (f ...) | | (f ...) ...)`` prints after ``srand seed``."""
    name, *words = call_text.split()
    args = [float(w) if "." in w else int(w) for w in words]
    ctx = Ctx(seed)
    return " ".join(format_value(call(name, *args, ctx=ctx)) for _ in range(times))


def run(text: str, decisions: int = 1, seed: int | None = None) -> tuple[Agent, str]:
    out = io.StringIO()
    agent = Agent(out=out)
    agent.load(text)
    if seed is not None:
        agent.srand(seed)
    agent.run(decisions)
    return agent, out.getvalue()


def values(agent: Agent, attr: str) -> list:
    return [w.value for w in agent.wmes() if w.attr == attr]


# ------------------------------------------------------------------ random numbers


@pytest.mark.parametrize(
    ("seed", "first"),
    [(7, [327741615, 976413892, 3349725721, 1369975286, 1882953283, 4201435347]),
     (-1, [419326371]), (4294967303, [327741615])],
)  # fmt: skip
def test_kernel_random_draws_the_kernels_32_bit_numbers(seed: int, first: list[int]) -> None:
    rng = kernel_random(seed)
    assert [rng.getrandbits(32) for _ in first] == first


@pytest.mark.parametrize(
    ("call_text", "printed"),
    [  # (write (f) | | (f) ...) six times after srand 7, in the kernel
        ("rand-int", "327741615 976413892 3349725721 1369975286 1882953283 4201435347"),
        ("rand-int 1", "1 0 1 0 1 1"),
        ("rand-int 9", "4 9 6 3 3 7"),
        ("rand-int 2.0", "0 1 2 0 1 2"),
        ("rand-int 4294967297", "1 0 1 0 1 1"),
        ("rand-int 10000000000",
         "327741615 976413892 1202242073 1369975286 959775639 1322904761"),
        ("rand-int 1000000000", "327741615 976413892 128500249 296233462 809211459 980209875"),
        ("rand-int -1000000000",
         "327741615 976413892 3349725721 1369975286 1882953283 4201435347"),
        ("rand-float 2.5", "0.190771 0.568348 1.949797 0.797431 1.096023 2.445557"),
        ("rand-float -2.5", "0.076308 0.227339 0.779919 0.318972 0.438409 0.978223"),
        ("rand-float", "0.076308 0.227339 0.779919 0.318972 0.438409 0.978223"),
    ],
)  # fmt: skip
def test_rand_int_and_rand_float_draw_what_the_kernel_draws(call_text: str, printed: str) -> None:
    assert draws(call_text) == printed


def test_rand_float_has_the_kernels_very_bits() -> None:
    """``(string ...)`` shows 17 decimals: the kernel's draws over 2**32 - 1, exactly."""
    ctx = Ctx()
    shown = [call("string", call("rand-float", *args, ctx=ctx)) for args in ((), (2.5,), (-1,))]
    assert shown == ["0.07630829119037565", "0.56834768749967857", "0.77991879586594148"]


def test_rand_int_of_a_power_of_two_beyond_32_bits_is_zero_like_the_kernel() -> None:
    assert draws("rand-int 4294967296", 2) == "0 0"  # n modulo 2**32 is 0: [0, 0]


def test_rand_ignores_extra_arguments_and_refuses_non_numbers() -> None:
    assert call("rand-int", 10, 20) == 4  # the kernel's value after srand 7
    for name in ("rand-int", "rand-float"):
        with pytest.raises(SoarRuntimeError, match=rf"non-number \(abc\) passed to - {name}"):
            call(name, "abc")
        with pytest.raises(SoarRuntimeError, match=r"non-number \(S1\)"):
            call(name, Identifier("S", 1))


def test_srand_makes_runs_repeatable_and_values_stay_in_range() -> None:
    text = (
        "srand {seed}\n"
        "sp {{p (state <s> ^superstate nil) --> (<s> ^i (rand-int 10) ^i (rand-int 10)"
        " ^i (rand-int 10) ^f (rand-float) ^f (rand-float 3) ^big (rand-int))}}"
    )
    first, _ = run(text.format(seed=3))
    again, _ = run(text.format(seed=3))
    other, _ = run(text.format(seed=4))
    picked = [sorted(map(str, values(a, k))) for a in (first, again, other) for k in "if"]
    assert picked[:2] == picked[2:4] and picked[:2] != picked[4:]
    assert all(0 <= v <= 10 and type(v) is int for v in values(first, "i"))
    assert all(0.0 <= v <= 3.0 and type(v) is float for v in values(first, "f"))
    assert 0 <= values(first, "big")[0] < 2**32


def test_rand_int_shares_the_generator_of_indifferent_selection() -> None:
    """As in the kernel, one generator: after ``srand 7`` an indifferent choice between two
    operators takes the first draw and ``(rand-int)`` gets the second (measured)."""
    text = """
sp {o (state <s> ^superstate nil) --> (<s> ^operator <o> + = ^operator <p> + =)}
sp {r (state <s> ^operator <o>) --> (<s> ^r (rand-int))}
"""
    agent, _ = run(text, decisions=2, seed=7)
    assert values(agent, "r") == [976413892]


# ----------------------------------------------------------------------- symbols


@pytest.mark.parametrize(
    ("value", "expected"),
    [("abc", "Abc"), ("Abc", "Abc"), ("aBC", "ABC"), ("hello world", "Hello world"),
     ("1abc", "1abc"), ("", ""), ("éa", "éa"), (" x", " x")],
)  # fmt: skip
def test_capitalize_symbol_like_the_kernel(value: str, expected: str) -> None:
    assert call("capitalize-symbol", value) == expected


@pytest.mark.parametrize(
    ("value", "shown"), [(5, "5"), (-5, "-5"), (2.5, "2.500000"), (Identifier("S", 1), "S1")]
)
def test_capitalize_symbol_refuses_what_is_not_a_symbol(value, shown: str) -> None:
    message = rf"non-symbol \({shown}\) passed to capitalize-symbol function\."
    with pytest.raises(SoarRuntimeError, match=message):
        call("capitalize-symbol", value)


@pytest.mark.parametrize(
    ("value", "expected"),
    [("abc", "abc"), ("hello world", "hello world"), (5, "5"), (-5, "-5"),
     (2.5, "2.50000000000000000"), (-0.0, "-0.00000000000000000"), (3.0, "3.00000000000000000"),
     (0.1, "0.10000000000000001"), (123456.789, "123456.78900000000430737"),
     (1e20, "100000000000000000000.00000000000000000"), (1 / 3, "0.33333333333333331"),
     (Identifier("S", 1), "S1"), ("", "")],
)  # fmt: skip
def test_string_like_the_kernel(value, expected: str) -> None:
    assert call("string", value) == expected


# ---------------------------------------------------------------------- headings

# (x1 y1 x2 y2) -> the kernel's (compute-heading ...) and (compute-range ...)
HEADINGS = [
    ((0, 0, 1, 1), 44), ((0, 0, 0, 1), 0), ((0, 0, 1, 0), 90), ((0, 0, 0, -1), -179),
    ((0, 0, -1, 0), -90), ((0, 0, -1, -1), -134), ((0, 0, 0, 0), 90),
    ((1.5, 2.5, 3.7, -4.2), 161), ((0, 0, 3, 4), 36), ((10, 10, 0, 0), -134),
    ((0, 0, 1, -1), 135), ((0, 0, -1, 1), -45), ((0, 0, 1, 100), 0), ((0, 0, -1, -100), -179),
    ((0, 0, 1, -100), 179), ((0, 0, -1, 100), 0), ((-4, -1, -4, 2), 0), ((3, -0.5, 2, 1), -45),
    ((78.663, -22.038, 21.488, 53.432), -37), ((-46.734, 60.365, 18.231, -79.555), 155),
    ((-5, -5, 5, 3), 51),
]  # fmt: skip
RANGES = [
    ((0, 0, 3, 4), 5), ((0, 0, 1, 1), 1), ((0, 0, 0, 0), 0), ((1.5, 2.5, 3.7, -4.2), 7),
    ((-3, -4, 0, 0), 5), ((0, 0, 3.0, 4), 5), ((-46.734, 60.365, 18.231, -79.555), 154),
    ((-30.86, 35.37, 52.19, 90.449), 99), ((1.685, 55.689, 4.188, -21.349), 77),
    ((-5, -5, 5, 3), 12), ((3, -0.5, 2, 1), 1),
]  # fmt: skip


@pytest.mark.parametrize(("points", "heading"), HEADINGS)
def test_compute_heading_like_the_kernel(points: tuple, heading: int) -> None:
    result = call("compute-heading", *points)
    assert result == heading and type(result) is int


@pytest.mark.parametrize(("points", "distance"), RANGES)
def test_compute_range_like_the_kernel(points: tuple, distance: int) -> None:
    result = call("compute-range", *points)
    assert result == distance and type(result) is int


def test_heading_functions_refuse_non_numbers() -> None:
    for name in ("compute-heading", "compute-range"):
        with pytest.raises(SoarRuntimeError, match=rf"non-number \(a\) passed to - {name}"):
            call(name, "a", 0, 1, 1)
        with pytest.raises(SoarRuntimeError, match="exactly 4 arguments"):
            call(name, 0, 1, 1)


# (heading precision) -> what the kernel writes for (round-off-heading heading precision)
ROUND_OFF_HEADING = [
    (0, 1, "0"), (45, 10, "50"), (44, 10, "40"), (-45, 10, "-50"), (181, 1, "-179"),
    (180, 1, "180"), (-180, 1, "180"), (359, 1, "-1"), (360, 1, "0"), (361, 1, "1"),
    (-181, 1, "179"), (-360, 1, "0"), (-359, 1, "1"), (725, 1, "5"), (45.5, 1, "45"),
    (45.5, 1.0, "46.000000"), (37, 10.0, "40.000000"), (37.5, 2.5, "37.500000"),
    (-37, 10, "-40"), (3, -10, "0"), (370, 10, "10"), (35, 10, "40"), (-35, 10, "-40"),
    (45, 0.5, "45.000000"), (179.6, 1, "179"), (-179.6, 1, "-179"), (180.5, 1, "180"),
    (179.6, 1.0, "180.000000"), (175, 10, "180"), (-175, 10, "180"), (355, 10, "0"),
    (185, 10, "-170"), (-185, 10, "170"), (185.0, 10.0, "-170.000000"),
    (-175.0, 10.0, "180.000000"), (1.25, 0.25, "1.200000"), (37, -10, "30"),
    (720.5, 1.0, "1.000000"), (-540, 1, "180"), (540, 1, "180"), (1000000, 1, "-80"),
    (-1000000, 1, "80"), (-360.0, 1.0, "0.000000"), (360.0, 1.0, "0.000000"),
    (-540.0, 1.0, "180.000000"), (-1.25, 3.0, "-0.000000"), (1000000.5, 1.0, "-79.000000"),
    (-0.4, 1.0, "-0.000000"), (-179.5, 1.0, "180.000000"), (7, 2, "8"), (-7, 2, "-8"),
]  # fmt: skip


@pytest.mark.parametrize(("heading", "precision", "printed"), ROUND_OFF_HEADING)
def test_round_off_heading_like_the_kernel(heading, precision, printed: str) -> None:
    result = call("round-off-heading", heading, precision)
    assert type(result) is (int if isinstance(precision, int) else float)
    assert format_value(result) == printed


def test_round_off_heading_refuses_a_zero_precision_where_the_kernel_crashes() -> None:
    for precision in (0, "a"):  # the kernel reads a non-number as 0 and dies (SIGFPE)
        with pytest.raises(SoarRuntimeError, match=r"^attempt to divide \('round-off-heading'\)"):
            call("round-off-heading", 3, precision)
    assert format_value(call("round-off-heading", 3, 0.0)) == "-nan"  # measured
    assert call("round-off-heading", 10**18 + 7, 1) == (10**18 + 7) % 360 - 360


# ---------------------------------------------------------------- working memory

SIZES = """
sp {init (state <s> ^superstate nil) --> (<s> ^l <l> ^e <e> ^m <m>)
    (<l> ^a 1 ^b 2 ^c 3 ^d 4 ^d 5 ^x <x>) (<x> ^y 1 ^z 2) (<m> ^a <x>)}
sp {sz (state <s> ^l <l> ^e <e> ^m <m>) (<l> ^x <x>) --> (write |l=| (size <l>) | e=| (size <e>)
    | x=| (size <x>) | s=| (size <s>) | m=| (size <m>) (crlf))}
"""
SET_COUNTS = """
sp {init (state <s> ^superstate nil) --> (<s> ^l <l> ^l <l2> ^e <e>) (<l> ^a 1 ^d 4 ^d 5
    ^x <x> ^x <x2>) (<l2> ^d 6 ^x <x>) (<x> ^y 1 ^z 2) (<x2> ^y 3) (<s> ^operator <o> +)}
sp {sz (state <s> ^l <l> ^e <e>) (<l> ^a 1) --> (write (set-count <s> l d) | |
    (set-count <s> l x) | | (set-count <s> l x y) | | (set-count <s> l) | |
    (set-count <s> operator) | | (set-count <s> l a d) | | (set-count <l>) (crlf))}
"""
STATE_SIZES = """
sp {prop (state <s> ^superstate nil) --> (<s> ^operator <o> +) (<o> ^name a)}
sp {sz (state <s> ^superstate nil ^operator <o> ^epmem <e> ^smem <m> ^reward-link <r>
    ^io.output-link <ol>) (<e> ^command <c>) --> (<ol> ^x 1) (write |s=| (size <s>) | e=|
    (size <e>) | m=| (size <m>) | r=| (size <r>) | c=| (size <c>) | ol=| (size <ol>) (crlf))}
sp {sub (state <s> ^superstate <ss> ^impasse <i>) --> (write |sub=| (size <s>) (crlf))}
"""


@pytest.mark.parametrize(
    ("text", "decisions", "printed"),
    [(SIZES, 1, "l=6 e=0 x=2 s=6 m=1\n"), (SET_COUNTS, 1, "3 3 3 2 0 0 0\n"),
     (STATE_SIZES, 3, "s=4 e=3 m=2 r=0 c=0 ol=0\nsub=3\n")],
)  # fmt: skip
def test_size_and_set_count_count_what_the_kernel_counts(
    text: str, decisions: int, printed: str
) -> None:
    assert run(text, decisions)[1] == printed


def test_size_and_set_count_do_not_see_input() -> None:
    agent = Agent(out=io.StringIO())
    agent.load(
        "sp {p (state <s> ^superstate nil ^io <io>) (<io> ^input-link <il>)"
        " --> (<s> ^n (size <il>) ^io-size (size <io>) ^c (set-count <s> io input-link))}"
    )
    agent.input_link.add("a", 1)
    agent.input_link.add("item").add("x", 1)
    agent.run(1)
    assert (values(agent, "n"), values(agent, "io-size"), values(agent, "c")) == ([0], [0], [0])


def test_size_and_set_count_refuse_non_identifiers_as_the_kernel_does() -> None:
    with pytest.raises(SoarRuntimeError, match=r"non-symbol \(abc\) passed to size function"):
        call("size", "abc")
    assert call("set-count", "abc", "x") == SET_COUNT_ERROR
    assert call("set-count") == SET_COUNT_ERROR  # the kernel crashes here
    assert SET_COUNT_ERROR == "|ERROR: First parameter needs to be an identifier.|"


# --------------------------------------------------------------- stand-alone actions


def test_log_writes_its_text_and_checks_the_channel() -> None:
    _, out = run(
        "sp {p (state <s> ^superstate nil) --> (write a) (log 1 |hello | world 3 2.5) (write c)"
        " (log 100 x (crlf)) (log 2)}"
    )
    assert out == "ahello world32.500000cx\n"
    for bad in ("a", 0, 101, 1.0, -1):
        with pytest.raises(SoarRuntimeError) as caught:
            call("log", bad, "x")
        assert str(caught.value) == (
            "First argument of agent's (log) rhs-function must be an integer channel number"
            f" between 1 and 100.  {format_value(bad)} is invalid."
        )


def test_count_dont_learn_and_force_learn_change_nothing() -> None:
    agent, out = run(
        "sp {p (state <s> ^superstate nil) --> (count foo) (count) (dont-learn <s>)"
        " (force-learn <s>) (<s> ^done yes)}"
    )
    assert out == "" and agent.errors == [] and values(agent, "done") == ["yes"]


@pytest.mark.parametrize(
    ("action", "message"),
    [("(dont-learn 5)", "non-identifier (5) passed to dont-learn function."),
     ("(force-learn abc)", "non-identifier (abc) passed to force-learn function."),
     ("(dont-learn <io>)", "identifier passed to dont-learn is not a state: I1.")],
)  # fmt: skip
def test_learning_actions_check_their_state_like_the_kernel(action: str, message: str) -> None:
    agent, _ = run(f"sp {{p (state <s> ^superstate nil ^io <io>) --> {action}}}")
    assert agent.errors == [f"Error: production p: {message}"]


def test_wait_sleeps_milliseconds_and_ignores_anything_else() -> None:
    start = time.perf_counter()
    run("sp {p (state <s> ^superstate nil) --> (wait 60) (wait 5000.0) (wait abc) (wait -9)}")
    assert 0.06 <= time.perf_counter() - start < 2


# -------------------------------------------------------------- load-time checks

RULE = "sp {{p (state <s> ^superstate nil) --> {}}}"


@pytest.mark.parametrize(
    ("action", "message"),
    [("(<s> ^v (capitalize-symbol a b))",
      "Wrong number of arguments to function capitalize-symbol (expected 1)"),
     ("(<s> ^v (compute-heading 1 2 3))",
      "Wrong number of arguments to function compute-heading (expected 4)"),
     ("(<s> ^v (round-off-heading 5))",
      "Wrong number of arguments to function round-off-heading (expected 2)"),
     ("(<s> ^v (string))", "Wrong number of arguments to function string (expected 1)"),
     ("(<s> ^v (abs 1 2))", "Wrong number of arguments to function abs (expected 1)"),
     ("(wait)", "Wrong number of arguments to function wait (expected 1)"),
     ("(dont-learn <s> <s>)", "Wrong number of arguments to function dont-learn (expected 1)"),
     ("(halt 1)", "Wrong number of arguments to function halt (expected 0)"),
     ("(rand-int 1 2)", "Function rand-int cannot be used as a stand-alone action"),
     ("(compute-range 1 2 3)", "Function compute-range cannot be used as a stand-alone action"),
     ("(crlf)", "Function crlf cannot be used as a stand-alone action"),
     ("(<s> ^v (log 1 a))", "Function log can only be used as a stand-alone action"),
     ("(<s> ^v (wait 1))", "Function wait can only be used as a stand-alone action"),
     ("(<s> ^v (count a))", "Function count can only be used as a stand-alone action"),
     ("(write (force-learn <s>))", "Function force-learn can only be used as a stand-alone action"),
     ("(<s> ^v (write a))", "Function write can only be used as a stand-alone action")],
)  # fmt: skip
def test_load_refuses_calls_as_the_kernel_does(action: str, message: str) -> None:
    with pytest.raises(SoarSemanticError, match=re.escape("production p: " + message)):
        Agent().load(RULE.format(action))


@pytest.mark.parametrize(
    ("action", "reason"),
    [("(<s> ^v (accept))", "standard input"),
     ("(link-stm-to-ltm <s> 5)", "semantic memory")],
)  # fmt: skip
def test_functions_this_engine_cannot_honour_are_refused_at_load(action: str, reason: str) -> None:
    name = action.split("(")[-1].split()[0].rstrip(")")
    with pytest.raises(SoarSemanticError, match=f"production p: RHS function '{name}' is refused"):
        Agent().load(RULE.format(action))
    with pytest.raises(SoarSemanticError, match=reason):
        Agent().load(RULE.format(action))


def test_parsing_without_an_engine_checks_names_only() -> None:
    """The default name list reads rule text without the kernel's signatures."""
    [p] = parse(RULE.format("(+ 1 2) (<s> ^v (halt 3))"))
    assert len(p.actions) == 2
    with pytest.raises(SoarSemanticError, match="cannot be used as a stand-alone"):
        parse(RULE.format("(+ 1 2)"), functions=frozenset(KNOWN_RHS_FUNCTIONS))


# ------------------------------------------------------------- against the kernel

VALUES_AGENT = """# input: a=1
# input: item x=1
sp {values (state <s> ^superstate nil) -->
    (<s> ^cap (capitalize-symbol hello) ^cap2 (capitalize-symbol |hello world|)
         ^str (string 2.5) ^str2 (string 42) ^str3 (string <s>) ^heading (compute-heading 0 0 1 1)
         ^heading2 (compute-heading 1.5 2.5 3.7 -4.2) ^range (compute-range 1.5 2.5 3.7 -4.2)
         ^roh (round-off-heading 185 10) ^roh2 (round-off-heading -175.0 10.0)
         ^roh3 (round-off-heading 720.5 1.0) ^list <l>)
    (<l> ^a 1 ^b 2 ^d 4 ^d 5 ^x <x>) (<x> ^y 1)
    (write |cap=| (capitalize-symbol abc) | | (string 0.1) (crlf))
    (log 1 |logged | 3 | | 2.5 (crlf)) (count foo) (dont-learn <s>) (force-learn <s>) (wait 1)}
sp {sizes (state <s> ^superstate nil ^list <l> ^io.input-link <il>) (<l> ^x <x>) -->
    (<s> ^size-l (size <l>) ^size-s (size <s>) ^size-il (size <il>) ^sc (set-count <s> list d)
         ^sc2 (set-count <s> list x y) ^sc3 (set-count abc))
    (write |sizes | (size <l>) | | (size <s>) | | (set-count <s> list x) (crlf))}
sp {done (state <s> ^size-l) --> (halt)}
"""

RANDOM_AGENT = """srand 7
sp {random (state <s> ^superstate nil) -->
    (<s> ^a (rand-int) ^b (rand-int 10) ^c (rand-float) ^d (rand-float 2.5) ^e (rand-int 3.7))
    (write (rand-int 1000) | | (string (rand-float 2.5)) | | (rand-int -5) (crlf)) (halt)}
"""


def test_new_functions_agree_with_the_kernel(kernel, tmp_path: Path) -> None:
    path = tmp_path / "values.soar"
    path.write_text(VALUES_AGENT)
    kernel.assert_agree(path, decisions=5)


def test_random_numbers_agree_with_the_kernel_after_srand_7(kernel) -> None:
    """The same file, ``srand 7`` included, in the kernel and in our agent: the same numbers
    (Agent.srand puts the generator in the kernel's state, see `kernel_random`)."""
    with kernel.KernelAgent() as ka:
        for line in RANDOM_AGENT.strip().split("\n", 1):
            ka.cmd(line)
        ka.take_log()
        ka.cmd("run 1")
        written, _ = ka.take_log().split("\n", 1)
        wmes = kernel.parse_internal(ka.cmd("print --internal s1"))
    theirs = sorted((attr[1], value) for _, attr, value, _ in wmes if len(attr[1]) == 1)
    agent, out = run(RANDOM_AGENT)
    ours = sorted((w.attr, kernel._our_symbol(w.value)) for w in agent.wmes() if len(w.attr) == 1)
    assert out.split("\n")[0] == written
    assert [(a, _rounded(v)) for a, v in ours] == [(a, _rounded(v)) for a, v in theirs]


@pytest.mark.parametrize("text", [SIZES, SET_COUNTS, STATE_SIZES])
def test_counts_agree_with_the_kernel(kernel_writes, our_writes, text: str) -> None:
    written = kernel_writes(text, 3)
    assert our_writes(text, 3) == written


def _rounded(value: tuple) -> tuple:
    """The kernel prints floats with six decimals."""
    kind, number = value
    return (kind, round(number, 6)) if kind == "float" else value


def test_load_time_checks_agree_with_the_kernel(kernel) -> None:
    actions = [
        "(<s> ^v (size))", "(<s> ^v (deep-copy a b))", "(<s> ^v (compute-range 1 2 3 4 5))",
        "(<s> ^v (accept 1))", "(link-stm-to-ltm a)", "(force-learn)", "(round-off-heading 5)",
        "(<s> ^v (dont-learn <s>))", "(<s> ^v (link-stm-to-ltm <s> 1))", "(set-count a)",
        "(<s> ^v (set-count))", "(<s> ^v (rand-float 1 2 3))", "(log)", "(count a b)",
        "(write (wait 1))", "(<s> ^v (trim))", "(<s> ^v (ifeq 1 2))", "(<s> ^v (timestamp 1))",
    ]  # fmt: skip
    with kernel.KernelAgent() as ka:
        for action in actions:
            result = ka.agent.ExecuteCommandLine(RULE.format(action))
            loaded = ka.agent.GetLastCommandLineResult()
            ka.agent.ExecuteCommandLine("excise -a")
            try:
                Agent().load(RULE.format(action))
            except SoarSemanticError as error:
                assert not loaded, (action, str(error))
                assert f"production p: {result.splitlines()[0]}" in str(error), action
            else:
                assert loaded, (action, result)
