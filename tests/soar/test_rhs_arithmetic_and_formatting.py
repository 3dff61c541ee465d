"""RHS functions with the kernel's arithmetic and formatting (figures from soar_sml 9.6)."""

from __future__ import annotations

import pytest

from sann.soar.errors import SoarRuntimeError
from sann.soar.memory import Identifier
from sann.soar.rhs import FUNCTIONS
from sann.soar.text import format_value


class Ctx:
    def __init__(self) -> None:
        self.written: list[str] = []
        self.halted = self.interrupted = False
        self.counter = 0

    def write_output(self, text: str) -> None:
        self.written.append(text)

    def request_halt(self) -> None:
        self.halted = True

    def request_interrupt(self) -> None:
        self.interrupted = True

    def decision_count(self) -> int:
        return 7

    def gensym(self, prefix: str) -> str:
        self.counter += 1
        return f"{prefix}{self.counter}"

    def mark_learning(self, function: str, state: object) -> None:
        self.marked = (function, state)


def call(name: str, *args):
    return FUNCTIONS[name](Ctx(), list(args))


@pytest.mark.parametrize(
    ("name", "args", "expected"),
    [
        ("+", (), 0),
        ("+", (1, 2), 3),
        ("+", (1, 2.0), 3.0),
        ("*", (), 1),
        ("*", (1.5, 2), 3.0),
        ("-", (5,), -5),
        ("-", (5, 1, 1), 3),
        ("/", (7, 2), 3.5),
        ("/", (6, 2), 3.0),
        ("/", (4,), 0.25),
        ("div", (7, 2), 3),
        ("div", (-7, 2), -3),
        ("mod", (-7, 2), -1),
        ("mod", (7, -2), 1),
        ("abs", (-2,), 2),
        ("abs", (-2.5,), 2.5),
        ("int", (3.7,), 3),
        ("int", (-3.7,), -3),
        ("int", ("12",), 12),
        ("float", (3,), 3.0),
        ("round-off", (3.456, 0.1), 3.4),
        ("round-off", (37, 10), 40),
        ("concat", ("a", 1, 2.5, "x y"), "a12.500000x y"),
        ("ifeq", ("a", "a", "yes", "no"), "yes"),
        ("ifeq", (1, 1.0, "yes", "no"), "no"),
        ("min", (3, 1, 2), 1),
        ("max", (3, 1, 2.5), 3.0),  # a float argument: a float (measured)
        ("strlen", ("abc",), 3),
        ("trim", ("  x ",), "x"),
        ("sqrt", (4,), 2.0),
    ],
)
def test_functions_return_the_kernels_values_and_types(name: str, args: tuple, expected) -> None:
    result = call(name, *args)
    assert result == pytest.approx(expected) if isinstance(expected, float) else result == expected
    assert type(result) is type(expected)


def test_int_and_float_types_are_kept() -> None:
    assert type(call("+", 1, 2)) is int
    assert type(call("/", 6, 2)) is float


@pytest.mark.parametrize(
    ("name", "args"),
    [
        ("/", (1, 0)),
        ("div", (1, 0)),
        ("mod", (1.5, 2)),
        ("+", ("a", 1)),
        ("-", ()),
        ("int", ("99999999999999999999",)),  # (int x) is 0, as C's strtol reads it
    ],
)
def test_bad_arguments_raise_a_runtime_error(name: str, args: tuple) -> None:
    with pytest.raises(SoarRuntimeError):
        call(name, *args)


def test_write_crlf_halt_interrupt_dc_and_gensym() -> None:
    ctx = Ctx()
    FUNCTIONS["write"](ctx, ["x", 1, 2.5, Identifier("O", 3), FUNCTIONS["crlf"](ctx, [])])
    assert ctx.written == ["x12.500000O3\n"]
    FUNCTIONS["halt"](ctx, [])
    FUNCTIONS["interrupt"](ctx, [])
    assert ctx.halted and ctx.interrupted
    assert FUNCTIONS["dc"](ctx, []) == 7
    assert FUNCTIONS["make-constant-symbol"](ctx, []) == "constant1"
    assert FUNCTIONS["make-constant-symbol"](ctx, ["foo"]) == "foo2"


def test_timestamp_has_the_kernels_layout() -> None:
    stamp = call("timestamp")
    assert len(stamp) == 23 and stamp[4] == "-" and stamp[19] == "."


def test_format_value_prints_floats_with_six_decimals_and_identifiers_by_name() -> None:
    assert format_value(0.1) == "0.100000"
    assert format_value(1e-7) == "0.000000"
    assert format_value(Identifier("S", 1)) == "S1"


# (value, precision) -> what the kernel (soar_sml 9.6) writes for (round-off value precision).
ROUND_OFF_KERNEL = [
    (37, 10, "40"), (35, 10, "40"), (-35, 10, "-40"), (-45, 10, "-50"), (7, 2, "8"),
    (-7, 2, "-8"), (7, -2, "6"), (7, -10, "0"), (37, 3, "36"), (38, 3, "39"),
    (3.7, 1, "3"), (2.5, 1, "2"), (-3.7, 1, "-3"), (-0.5, 1, "0"), (37.0, 10, "40"),
    (3.14159, 0.1, "3.100000"), (3.14159, 0.5, "3.000000"), (1.25, 0.5, "1.000000"),
    (1.25, 0.25, "1.200000"), (7.5, 0.25, "7.600000"), (7, 0.5, "7.000000"),
    (7, -0.5, "6.500000"), (1.0, -0.25, "0.800000"), (5, 0.9, "5.400000"),
    (2.5, 1.0, "3.000000"), (3.7, 1.0, "4.000000"), (37, 10.0, "40.000000"),
    (1.75, 3.0, "3.000000"), (5, -1.5, "3.000000"), (-5, -1.5, "-3.000000"),
    (-1.25, 3.0, "-0.000000"), (0.3, -0.5, "0.000000"), (-1.29, -1.5, "0.000000"),
]  # fmt: skip


@pytest.mark.parametrize(("value", "precision", "printed"), ROUND_OFF_KERNEL)
def test_round_off_matches_the_kernel(value, precision, printed: str) -> None:
    result = call("round-off", value, precision)
    assert type(result) is (int if isinstance(precision, int) else float)
    assert format_value(result) == printed


def test_round_off_below_a_tenth_rounds_where_the_kernel_returns_nan() -> None:
    assert format_value(call("round-off", 3.14159, 0.01)) == "3.140000"
    assert format_value(call("round-off", -1.2345, 0.05)) == "-1.250000"
    with pytest.raises(SoarRuntimeError, match="zero"):  # the kernel dies (SIGFPE)
        call("round-off", 5, 0)
    assert format_value(call("round-off", 1.5, 0.0)) == "-nan"  # measured
    assert call("round-off", "a", 10) == 0 and call("round-off", "a", 1.0) == 0.0  # measured


@pytest.mark.parametrize(
    ("name", "args", "expected"),
    [  # measured in soar_sml 9.6: a float argument makes the result a float
        ("max", (3, 1.5, 2), 3.0),
        ("min", (1, 2.5), 1.0),
        ("max", (3, 2), 3),
        ("min", (3, 2.0), 2.0),
        ("max", (2.0, 3), 3.0),
    ],
)
def test_min_max_result_types_follow_the_kernel(name: str, args: tuple, expected) -> None:
    result = call(name, *args)
    assert result == expected and type(result) is type(expected)


@pytest.mark.parametrize(
    ("name", "args", "expected"),
    [  # measured in soar_sml 9.6: 64-bit integers that wrap around
        ("*", (4000000000, 4000000000), -2446744073709551616),
        ("+", (9223372036854775807, 1), -9223372036854775808),
        ("-", (-9223372036854775807, 2), 9223372036854775807),
        ("-", (-9223372036854775808,), -9223372036854775808),
    ],
)
def test_integers_wrap_at_64_bits_like_the_kernel(name: str, args: tuple, expected) -> None:
    assert call(name, *args) == expected
