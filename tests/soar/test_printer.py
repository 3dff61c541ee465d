"""The printer: canonical Soar text, constants that read back as themselves, and agreement
with the real kernel's ``print`` (modulo the kernel's condition reordering)."""

from __future__ import annotations

from collections import Counter

import pytest

from sann.soar.parsing.parser import parse, parse_production
from sann.soar.printer import (
    format_action,
    format_command,
    format_condition,
    format_production,
)
from sann.soar.production import (
    Command,
    Condition,
    Conjunction,
    ConjunctiveNegation,
    Const,
    FuncCall,
    MakeAction,
    Production,
    Var,
)
from sann.soar.text import format_constant

SOURCE = """\
sp {blocks*propose*move "Move a clear block."
   :o-support
   (state <s> ^name blocks ^block.top <b> -^done ^operator <o> +)
   (<b> ^size { <z> > 3 } ^color << red |light blue| >>)
   -{(<b> ^on <c>) (<c> ^type table)}
   -(<s> ^holding <b>)
-->
   (<s> ^operator <o> > <p>, = 0.5 ^result.count (+ <z> 1))
   (<o> ^name move -)
   (write |Block: | <b> (crlf))}
"""

EXPECTED = """\
sp {blocks*propose*move
    "Move a clear block."
    :o-support
    (state <s> ^name blocks ^block <b*1>)
    (<b*1> ^top <b>)
    (state <s> -^done <d*1> ^operator <o> +)
    (<b> ^size { <z> > 3 } ^color << red |light blue| >>)
   -{ (<b> ^on <c>)
      (<c> ^type table)}
    -(<s> ^holding <b>)
    -->
    (<s> ^operator <o> > <p> ^operator <o> = 0.5 ^result <r*1>)
    (<r*1> ^count (+ <z> 1))
    (<o> ^name move -)
    (write |Block: | <b> (crlf))
}"""


def test_a_production_prints_in_the_canonical_layout_and_reads_back() -> None:
    production = parse_production(SOURCE)
    assert format_production(production) == EXPECTED
    assert parse(EXPECTED) == [production]
    assert format_production(parse_production(EXPECTED)) == EXPECTED  # a fixed point


@pytest.mark.parametrize(
    ("value", "text"),
    [
        ("abc", "abc"), ("a-b*c", "a-b*c"), ("1e3", "1e3"), ("x@y", "|x@y|"), ("-a", "|-a|"),
        ("x@yz", "x@yz"), ("-abc", "-abc"), ("*", "*"), ("***", "|***|"), ("<=>a", "<=>a"),
        ("a b", "|a b|"), ("12", "|12|"), ("-3", "|-3|"), ("1.5", "|1.5|"), ("s1", "|s1|"),
        ("S1", "|S1|"), ("<x>", "|<x>|"), ("-", "|-|"), ("-->", "|-->|"), ("<<", "|<<|"),
        ("<=>", "|<=>|"), ("@", "|@|"), ("", "||"), ("a|b", r"|a\|b|"), ("a\\b", r"|a\\b|"),
        ("#x", "|#x|"), ("a.b", "|a.b|"), (12, "12"), (-3, "-3"), (1.5, "1.5"),
        (150.0, "150.0"), (1e20, "1.0e+20"), (-2.5e-7, "-2.5e-07"), (0.0, "0.0"),
    ],
)  # fmt: skip
def test_constants_print_as_text_that_reads_back_as_themselves(value: object, text: str) -> None:
    assert format_constant(value) == text
    [c] = parse_production(f"sp {{p (state <s> ^v {text}) --> }}").conditions
    assert c.value_test == Const(value) and type(c.value_test.value) is type(value)


def test_keywords_are_quoted_only_as_identifier_tests() -> None:
    assert format_constant("state") == "state"
    assert format_constant("state", keyword_safe=True) == "|state|"
    state = Condition(Var("s"), Const("a"), Const("b"), goal="state")
    production = Production("p", (state, Condition(Const("state"), Const("a"), Const("state"))), ())
    assert "(|state| ^a state)" in format_production(production)
    assert parse(format_production(production)) == [production]


def test_unprintable_constants_are_refused() -> None:
    with pytest.raises(ValueError, match="float"):
        format_constant(float("nan"))
    with pytest.raises(TypeError, match="boolean"):
        format_constant(True)


def test_negations_nccs_and_actions_print_alone() -> None:
    negated = Condition(Var("s"), Const("a"), Const("b"), negated=True, goal="state")
    assert format_condition(negated) == "-(state <s> ^a b)"
    ncc = ConjunctiveNegation((Condition(Var("s"), Const("a"), Var("x")), negated))
    assert format_condition(ncc) == "-{ (<s> ^a <x>)\n-(state <s> ^a b)}"
    assert format_action(MakeAction(Var("s"), Const("operator"), Var("o"), "=", Const(0.5))) == (
        "(<s> ^operator <o> = 0.5)"
    )
    assert format_action(MakeAction(Var("s"), Const("a"), FuncCall("+", (Const(1),)))) == (
        "(<s> ^a (+ 1))"
    )


def test_unary_binary_signs_print_unambiguously() -> None:
    text = "sp {p (state <s> ^operator <o> +) --> (<s> ^operator <o> >, = ^operator <o> < <o>)}"
    production = parse_production(text)
    printed = format_production(production)
    assert "(<s> ^operator <o> > ^operator <o> = ^operator <o> < <o>)" in printed
    assert parse(printed) == [production]


def test_commands_print_quoted_and_read_back() -> None:
    assert format_command(Command("watch", ("1",))) == "watch 1"
    assert format_command(Command("source", ("my rules.soar",))) == 'source "my rules.soar"'
    assert format_command(Command("echo", ('say "x"', ""))) == r'echo "say \"x\"" ""'
    assert format_command(Command("gp", ("x [a b]",))) == 'gp "x [a b]"'
    for command in parse('source "my rules.soar"; echo "say \\"x\\"" {a;b}; gp {x [a b]}'):
        assert parse(format_command(command)) == [command]


# ------------------------------------------------------------------ the kernel's print

KERNEL_CASES = [
    "sp {kernel-1 (state <s> ^a.b.c <v> -^d.e f) --> (<s> ^x.y z)}",
    "sp {kernel-2 (state <s> ^a) --> (<s> ^b <x>) (<x> ^c d)}",
    "sp {kernel-3 (state <s> ^a.b <a*1>) --> (<s> ^a.b c)}",
    "sp {kernel-4 (state <s> ^Foo.bar x ^<Zed>.x y ^1.x z ^|hello world|.x w) --> (write hi)}",
    "sp {kernel-5 (state <s> ^operator <o> + ^operator <p> +)"
    " --> (<s> ^operator <o> > <p>, = 0.5, + ^operator <p> <)}",
    "sp {kernel-6 (state <s> ^x y) -(<s> ^a b ^c d) -{(<s> ^e f)} -(<s> -^g h) --> (write hi)}",
    "sp {kernel-7 (state <s> ^x y -^a b c -^d.e f g) --> (write hi)}",
    "sp {kernel-8 (state <s> ^a b) --> (<s> ^a.b.c d e) (<s> ^a.b.c f)}",
    "sp {kernel-9 (state <s> ^a <x>) --> (<s> ^b (+ <x> (* 2 <x>)) ^c (concat |a b| <x>) (crlf))}",
    'sp {kernel-10 "doc" :o-support (state <s> ^a { <x> <> 3 < 5 } ^b s1) --> (<s> ^c |S2| -)}',
    "sp {kernel-11 (state ^a b) (impasse ^c d) --> (write hi)}",
    "sp {kernel-12 (state <s> ^x y) --> (<s> ^z <w>) (<w> ^<att> v) (<att> ^q r)}",
    "sp {kernel-13 { (state <s> ^a b) (<s> ^c d) } -(<s> ^e) --> (<s> ^f g - h ^operator o ~ ! =)}",
]


def _unordered(production: Production) -> tuple:
    """Compare modulo the kernel's reordering (and its merging of `state` into groups)."""

    def test(t):
        return ("conj", frozenset(t.tests)) if isinstance(t, Conjunction) else t

    def element(e):
        if isinstance(e, ConjunctiveNegation):
            return ("ncc", frozenset(Counter(element(c) for c in e.conditions).items()))
        tests = (test(e.id_test), test(e.attr_test), test(e.value_test))
        return tests, e.negated, e.acceptable

    conditions = Counter(element(e) for e in production.conditions)
    return (
        production.name,
        production.doc,
        frozenset(production.flags),
        conditions,
        Counter(production.actions),
    )


@pytest.mark.parametrize("text", KERNEL_CASES, ids=lambda t: t.split()[1].lstrip("{"))
def test_kernel_prints_the_same_production(text: str) -> None:
    pytest.importorskip("soar_sml")
    from differential.kernel import KernelAgent

    ours = parse_production(text)
    with KernelAgent() as kernel:
        kernel.cmd(text)
        printed = kernel.cmd(f"print {ours.name}")
    assert _unordered(parse_production(printed)) == _unordered(ours), printed
