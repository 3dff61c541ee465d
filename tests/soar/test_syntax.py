"""The Soar parser: every construct, the kernel's normalisations, every error path."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from sann.soar.errors import SoarSemanticError, SoarSyntaxError, SoarWarning
from sann.soar.parsing.actions import KNOWN_RHS_FUNCTIONS
from sann.soar.parsing.parser import parse, parse_file, parse_partial, parse_production
from sann.soar.printer import format_production
from sann.soar.production import (
    CallAction,
    Command,
    Condition,
    Conjunction,
    ConjunctiveNegation,
    Const,
    Disjunction,
    FuncCall,
    MakeAction,
    Production,
    Relational,
    Var,
)
from sann.soar.rhs import FUNCTIONS

ROOT = Path(__file__).resolve().parents[2]
S = Var("s")


def cond(ident, attr, value, **kw) -> Condition:
    """A condition from short arguments: strings are constants unless written ``<x>``."""
    return Condition(_t(ident), _t(attr), _t(value), **kw)


def _t(x):
    if isinstance(x, str) and x.startswith("<") and x.endswith(">") and len(x) > 2:
        return Var(x[1:-1])
    return x if not isinstance(x, str | int | float) else Const(x)


def make(ident, attr, value, pref="+", referent=None) -> MakeAction:
    ref = None if referent is None else _t(referent)
    return MakeAction(_t(ident), _t(attr), _t(value), pref, ref)


def lhs(text: str) -> tuple:
    return parse_production(f"sp {{p {text} --> (write x)}}").conditions


def rhs(text: str, conditions: str = "(state <s> ^a <x> ^operator <o> + ^operator <p> +)"):
    return parse_production(f"sp {{p {conditions} --> {text}}}").actions


# ------------------------------------------------------------------------- structure


def test_production_name_doc_flags_and_location() -> None:
    text = '\n\nsp {blocks*propose*move "Move a block." :o-support :default\n' \
        "  (state <s> ^a b)\n-->\n  (<s> ^c d)}"  # fmt: skip
    [p] = parse(text, file="rules/x.soar")
    assert p.name == "blocks*propose*move"
    assert p.doc == "Move a block."
    assert p.flags == ("o-support", "default")
    assert p.support == "o-support"
    assert (p.location.file, p.location.line, p.location.column) == ("rules/x.soar", 3, 1)
    assert p.conditions == (cond("<s>", "a", "b", goal="state"),)
    assert p.actions == (make("<s>", "c", "d"),)


def test_doc_string_escapes_and_quoted_name() -> None:
    p = parse_production(r'sp {|my rule| "say \"hi\" \\ now" (state <s> ^a b) --> }')
    assert p.name == "my rule"
    assert p.doc == 'say "hi" \\ now'
    assert p.actions == ()


def test_every_flag_is_kept() -> None:
    flags = ("o-support", "i-support", "default", "chunk", "interrupt")
    p = parse_production("sp {p " + " ".join(":" + f for f in flags) + " (state <s> ^a b) --> }")
    assert p.flags == flags


def test_impasse_keyword_and_missing_identifier() -> None:
    assert lhs("(impasse <g> ^type tie)") == (cond("<g>", "type", "tie", goal="impasse"),)
    # Like the kernel: a missing identifier test becomes <s*1> (state) or <i*1> (impasse).
    assert lhs("(state ^a b)") == (cond("<s*1>", "a", "b", goal="state"),)
    assert lhs("(impasse ^a b)") == (cond("<i*1>", "a", "b", goal="impasse"),)


def test_several_attribute_tests_become_several_conditions() -> None:
    assert lhs("(state <s> ^a b ^c <d>) (<d> ^e 1)") == (
        cond("<s>", "a", "b", goal="state"),
        cond("<s>", "c", "<d>", goal="state"),
        cond("<d>", "e", 1),
    )


def test_multi_valued_attribute_becomes_one_condition_per_value() -> None:
    assert lhs("(state <s> ^a b c <d>)") == tuple(
        cond("<s>", "a", v, goal="state") for v in ("b", "c", "<d>")
    )


def test_paths_chain_through_fresh_variables_named_like_the_kernel() -> None:
    # The kernel names them after the attribute's first letter, counting per letter.
    assert lhs("(state <s> ^a.b.c <v> ^apple.bear x)") == (
        cond("<s>", "a", "<a*1>", goal="state"),
        cond("<a*1>", "b", "<b*1>"),
        cond("<b*1>", "c", "<v>"),
        cond("<s>", "apple", "<a*2>", goal="state"),
        cond("<a*2>", "bear", "x"),
    )


def test_fresh_variables_skip_names_in_use_and_continue_on_the_rhs() -> None:
    p = parse_production("sp {p (state <s> ^a.b <a*1>) --> (<s> ^a.b c)}")
    assert p.conditions == (cond("<s>", "a", "<a*2>", goal="state"), cond("<a*2>", "b", "<a*1>"))
    assert p.actions == (make("<s>", "a", "<a*3>"), make("<a*3>", "b", "c"))


def test_fresh_variable_letters() -> None:
    conds = lhs("(state <s> ^Foo.x 1 ^<Zed>.x 2 ^7.x 3 ^|hi there|.x 4 ^{<q> <> a}.x 5)")
    links = [c.value_test.name for c in conds if c.goal]
    assert links == ["f*1", "Z*1", "i*1", "h*1", "q*1"]


def test_missing_value_becomes_a_fresh_variable() -> None:
    assert lhs("(state <s> ^a ^bc)") == (
        cond("<s>", "a", "<a*1>", goal="state"),
        cond("<s>", "bc", "<b*1>", goal="state"),
    )


def test_path_with_several_values_shares_the_chain_and_acceptable_goes_last() -> None:
    assert lhs("(state <s> ^x.y 1 2 ^operator.name <n> +)") == (
        cond("<s>", "x", "<x*1>", goal="state"),
        cond("<x*1>", "y", 1),
        cond("<x*1>", "y", 2),
        cond("<s>", "operator", "<o*1>", goal="state"),
        cond("<o*1>", "name", "<n>", acceptable=True),
    )


def test_acceptable_test() -> None:
    assert lhs("(state <s> ^operator <o> +)") == (
        cond("<s>", "operator", "<o>", acceptable=True, goal="state"),
    )


# ------------------------------------------------------------------------- negation


def test_negated_attribute_test_and_negated_condition() -> None:
    assert lhs("(state <s> ^a b -^c d) -(<s> ^e f)") == (
        cond("<s>", "a", "b", goal="state"),
        cond("<s>", "c", "d", negated=True, goal="state"),
        cond("<s>", "e", "f", negated=True),
    )


def test_negated_attribute_without_value() -> None:
    assert lhs("(state <s> ^x y -^a)")[1] == cond("<s>", "a", "<a*1>", negated=True, goal="state")


def test_negated_path_and_negated_multivalue_are_conjunctive_negations() -> None:
    # Kernel: -^d.e f prints as -{ (<s> ^d <d*1>) (<d*1> ^e f) }; -^a b c as -{ (<s> ^a b ^a c) }.
    assert lhs("(state <s> ^x y -^d.e f)")[1:] == (
        ConjunctiveNegation((cond("<s>", "d", "<d*1>", goal="state"), cond("<d*1>", "e", "f"))),
    )
    assert lhs("(state <s> ^x y -^a b c)")[1] == ConjunctiveNegation(
        (cond("<s>", "a", "b", goal="state"), cond("<s>", "a", "c", goal="state"))
    )


def test_conjunctive_negation_and_its_kernel_simplifications() -> None:
    conds = lhs("(state <s> ^x y) -{(<s> ^a b) (<s> ^c d)} -(<s> ^e f ^g h) -{(<s> ^i j)}")
    assert conds[1] == ConjunctiveNegation((cond("<s>", "a", "b"), cond("<s>", "c", "d")))
    assert conds[2] == ConjunctiveNegation((cond("<s>", "e", "f"), cond("<s>", "g", "h")))
    assert conds[3] == cond("<s>", "i", "j", negated=True)  # one condition: a plain negation
    # A negated negation is positive, as in the kernel.
    assert lhs("(state <s> ^x y) -(<s> -^g h)")[1] == cond("<s>", "g", "h")


def test_nested_conjunctive_negation_and_positive_group() -> None:
    conds = lhs("{(state <s> ^x y) (<s> ^z w)} -{(<s> ^a <b>) -{(<b> ^c d) (<b> ^e f)}}")
    assert conds[:2] == (cond("<s>", "x", "y", goal="state"), cond("<s>", "z", "w"))
    inner = ConjunctiveNegation((cond("<b>", "c", "d"), cond("<b>", "e", "f")))
    assert conds[2] == ConjunctiveNegation((cond("<s>", "a", "<b>"), inner))


# ------------------------------------------------------------------------- tests and constants


def test_predicates() -> None:
    ops = ["<>", "<", ">", "<=", ">=", "<=>", "@", "!@"]
    body = " ".join(f"^a{i} {op} <x>" for i, op in enumerate(ops))
    conds = lhs(f"(state <s> ^x <x> {body})")
    assert [c.value_test for c in conds[1:]] == [Relational(op, Var("x")) for op in ops]
    assert lhs("(state <s> ^a = 3)")[0].value_test == Const(3)  # `=` is plain equality


def test_disjunction_and_conjunction() -> None:
    [c] = lhs("(state <s> ^a << red |blue sky| 3 2.5 >>)")
    assert c.value_test == Disjunction((Const("red"), Const("blue sky"), Const(3), Const(2.5)))
    assert lhs("(state <s> ^a << >>)")[0].value_test == Disjunction(())  # legal in the kernel
    [c] = lhs("(state <s> ^a { <x> > 3 <> 7 << 4 5 >> })")
    assert c.value_test == Conjunction(
        (Var("x"), Relational(">", Const(3)), Relational("<>", Const(7)), Disjunction(
            (Const(4), Const(5))))
    )  # fmt: skip
    assert lhs("(state <s> ^a { <x> })")[0].value_test == Var("x")


def test_tests_in_identifier_and_attribute_positions() -> None:
    c, _ = lhs("(state { <s> <> <t> } ^{ <> name <> type }) (<s> ^b <t>)")
    assert c.id_test == Conjunction((S, Relational("<>", Var("t"))))
    assert c.attr_test == Conjunction(
        (Relational("<>", Const("name")), Relational("<>", Const("type")))
    )
    assert c.value_test == Var("v*1")  # no letter to take from the attribute test
    assert lhs("(state <s> ^<attr> <v>)")[0].attr_test == Var("attr")


def test_relational_tests_on_variables_nothing_binds_are_dropped() -> None:
    # The kernel drops them from positive conditions (in any field, also inside a
    # conjunctive negation) and prints (state <s> ^c <c*1>) for (state <s> ^c < <y>).
    [c] = lhs("(state { <s> <> <t> } ^{ <a> <> <u> } { < <y> <v> })")
    assert (c.id_test, c.attr_test, c.value_test) == (S, Var("a"), Var("v"))
    [c] = lhs("(state <s> ^c < <y>)")
    assert c.value_test == Var("c*1")
    [c, ncc] = lhs("(state <s> ^a <x>) -{(<s> ^b <z>) (<z> ^c { > <q> > <x> })}")
    assert ncc.conditions[1].value_test == Relational(">", Var("x"))
    [c, neg] = lhs("(state <s> ^c < <y>) -(<s> ^d <y>)")  # bound only by a negation
    assert c.value_test == Var("c*1") and neg.value_test == Var("y")


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("12", 12), ("-3", -3), ("+4", 4), ("1.5", 1.5), ("-2.5", -2.5), (".5", 0.5),
        ("-.5", -0.5),
        ("9223372036854775807", 2**63 - 1), ("-9223372036854775808", -(2**63)),
        ("5.", 5.0), ("1.5e2", 150.0), ("1.5e", 1.5), ("1e3", "1e3"),
        ("abc", "abc"), ("|abc|", "abc"), ("|12|", "12"), ("s1", "S1"), ("O23", "O23"),
        ("|s1|", "s1"), ("x@y", "x@y"), ("a-b*c/d:e?f%g$h&i", "a-b*c/d:e?f%g$h&i"),
        (r"|a\|b\\c|", "a|b\\c"), ("|a#b|", "a#b"), ("||", ""), ("-a", "-a"),
    ],
)  # fmt: skip
def test_constants_follow_the_kernel_lexer(text: str, value: object) -> None:
    [c] = lhs(f"(state <s> ^v {text})")
    assert c.value_test == Const(value)
    assert type(c.value_test.value) is type(value)


def test_keywords_are_symbols_elsewhere() -> None:
    [c] = lhs("(state <s> ^state impasse)")
    assert c.attr_test == Const("state") and c.value_test == Const("impasse")
    assert lhs("(state <s> ^a stateful)")[0].value_test == Const("stateful")


# ------------------------------------------------------------------------- actions


def test_actions_make_and_remove_and_call() -> None:
    assert rhs("(<s> ^b c -) (write |hello world| (crlf)) (halt)") == (
        make("<s>", "b", "c", "-"),
        CallAction(FuncCall("write", (Const("hello world"), FuncCall("crlf", ())))),
        CallAction(FuncCall("halt", ())),
    )


def test_every_unary_preference() -> None:
    actions = rhs("(<s> ^operator <o> + - ! ~ >, <, =)")
    assert [a.preference for a in actions] == ["+", "-", "!", "~", ">", "<", "="]
    assert all(a.referent is None for a in actions)


def test_non_operator_preferences_follow_the_kernel() -> None:
    # Off ^operator the kernel keeps each reject, and otherwise makes one acceptable,
    # ignoring (with a warning) any other unary sign.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        actions = rhs("(<s> ^f g ~ + ! h - i ^<x> j >)")
    messages = [str(w.message) for w in caught if w.category is SoarWarning]
    assert [m.split("preference ")[1][:3] for m in messages] == ["'~'", "'!'", "'>'"]
    assert all(m.startswith("<string>:1: production p: ") for m in messages)
    assert caught[0].filename == __file__  # points at the caller of parse()
    assert actions == (
        make("<s>", "f", "g"),
        make("<s>", "f", "h", "-"),
        make("<s>", "f", "i"),
        make("<s>", "<x>", "j"),
    )
    assert rhs("(<s> ^f g - -)") == (make("<s>", "f", "g", "-"),) * 2
    assert rhs("(<s> ^f g + -)") == (make("<s>", "f", "g", "-"),)


def test_binary_and_numeric_preferences() -> None:
    assert rhs("(<s> ^operator <o> > <p>, < <p> = <p> = 0.5 + )") == (
        make("<s>", "operator", "<o>", ">", "<p>"),
        make("<s>", "operator", "<o>", "<", "<p>"),
        make("<s>", "operator", "<o>", "=", "<p>"),
        make("<s>", "operator", "<o>", "=", 0.5),
        make("<s>", "operator", "<o>", "+"),
    )


def test_binary_sign_before_comma_caret_or_paren_is_unary() -> None:
    assert rhs("(<s> ^operator <o> >, <p> = ^operator <p> <)") == (
        make("<s>", "operator", "<o>", ">"),
        make("<s>", "operator", "<p>", "="),
        make("<s>", "operator", "<p>", "<"),
    )


def test_binary_sign_before_another_sign_is_unary() -> None:
    # Kernel: `< -` is worse-than-all then reject; `= ~ <o>` is =, ~ and a new value <o>.
    assert rhs("(<s> ^operator <o> < - > + = ~ <p>)") == (
        make("<s>", "operator", "<o>", "<"),
        make("<s>", "operator", "<o>", "-"),
        make("<s>", "operator", "<o>", ">"),
        make("<s>", "operator", "<o>", "+"),
        make("<s>", "operator", "<o>", "="),
        make("<s>", "operator", "<o>", "~"),
        make("<s>", "operator", "<p>", "+"),
    )


def test_semicolons_inside_a_production_are_white_space() -> None:
    assert lhs("(state <s> ^a b;c) ; (<s> ^d e)") == (
        cond("<s>", "a", "b", goal="state"),
        cond("<s>", "a", "c", goal="state"),
        cond("<s>", "d", "e"),
    )


def test_multi_valued_actions_and_commas() -> None:
    assert rhs("(<s> ^a b, c + <x> 1 2.5 |x y|)") == tuple(
        make("<s>", "a", v) for v in ("b", "c", "<x>", 1, 2.5, "x y")
    )


def test_rhs_paths_create_chains() -> None:
    # Kernel: (<s> ^a.b.c d e) gives one chain and two values.
    assert rhs("(<s> ^a.b.c d e) (<s> ^a.b.c f)") == (
        make("<s>", "a", "<a*1>"),
        make("<a*1>", "b", "<b*1>"),
        make("<b*1>", "c", "d"),
        make("<b*1>", "c", "e"),
        make("<s>", "a", "<a*2>"),
        make("<a*2>", "b", "<b*2>"),
        make("<b*2>", "c", "f"),
    )


def test_function_calls_nested_in_values_and_attributes() -> None:
    [a] = rhs("(<s> ^(concat a <x>) (+ <x> (* 2 (- <x>)) (div 7 2) (mod 7 2)))")
    assert a.attr == FuncCall("concat", (Const("a"), Var("x")))
    assert a.value == FuncCall("+", (Var("x"), FuncCall("*", (Const(2), FuncCall(
        "-", (Var("x"),)))), FuncCall("div", (Const(7), Const(2))), FuncCall(
        "mod", (Const(7), Const(2)))))  # fmt: skip


@pytest.mark.parametrize("name", sorted(KNOWN_RHS_FUNCTIONS))
def test_every_known_function_parses(name: str) -> None:
    [a] = rhs(f"({name} 1 <x>)")
    assert a == CallAction(FuncCall(name, (Const(1), Var("x"))))


def test_created_identifiers_ground_later_actions() -> None:
    actions = rhs("(<x> ^c d) (<s> ^b <x>) (<x> ^e.f g) (write <x>) (<s> ^new <n>) (<n> ^a b)")
    assert actions[0] == make("<x>", "c", "d")


def test_caller_may_extend_the_function_set() -> None:
    text = "sp {p (state <s> ^a b) --> (<s> ^c (sqrt 4))}"
    with pytest.raises(SoarSemanticError):
        parse(text)
    [p] = parse(text, functions=KNOWN_RHS_FUNCTIONS | {"sqrt"})
    assert p.actions[0].value == FuncCall("sqrt", (Const(4),))


# ------------------------------------------------------------------------- files and commands


def test_commands_comments_and_separators() -> None:
    text = (
        "# a comment\n"
        "source ../common/elaborations.soar ;# trailing comment\n"
        'echo "hello world" plain # comment\n'
        "watch 1; srand 42\n"
        "sp {p # a comment inside\n (state <s> ^a |#not a comment|) # another\n --> (halt)}\n"
        "indifferent-selection --epsilon-greedy\n"
        "multi-attributes ontop 3\n"
        "learn --off\n"
        "gp {x [a {b}]}\n"
    )
    items = parse(text, "agent.soar")
    commands = [(i.name, i.args) for i in items if isinstance(i, Command)]
    assert commands == [
        ("source", ("../common/elaborations.soar",)),
        ("echo", ("hello world", "plain")),
        ("watch", ("1",)),
        ("srand", ("42",)),
        ("indifferent-selection", ("--epsilon-greedy",)),
        ("multi-attributes", ("ontop", "3")),
        ("learn", ("--off",)),
        ("gp", ("x [a {b}]",)),
    ]
    assert [type(i).__name__ for i in items].index("Production") == 4
    assert items[4].conditions[0].value_test == Const("#not a comment")
    assert items[3].location.line == 4 and items[3].location.column == 10


def test_productions_separated_by_semicolons_and_empty_input() -> None:
    items = parse("sp {p (state <s> ^a b) --> }; sp {q (state <s> ^a b) --> }")
    assert [p.name for p in items] == ["p", "q"]
    assert parse("") == [] and parse("\n# only a comment\n;\n") == []


def test_byte_order_mark_and_windows_line_ends() -> None:
    items = parse("\ufeffwatch 1\r\nsp {p\r\n (state <s> ^a b)\r\n-->\r\n}\r\n")
    assert items[0] == Command("watch", ("1",)) and items[1].name == "p"
    assert items[1].location.line == 2


def test_parse_file_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "bad.soar"
    path.write_text("sp {p (state <s> ^a b) --> (<s> ^b c)}\nsp {q (state <s>) --> }\n")
    with pytest.raises(SoarSyntaxError) as info:
        parse_file(path)
    assert info.value.file == str(path) and info.value.line == 2


def test_parse_production_wants_exactly_one_production() -> None:
    for text in ("", "watch 1", "sp {p (state <s> ^a b) --> }\nsp {q (state <s> ^a b) --> }"):
        with pytest.raises(SoarSyntaxError, match="exactly one production"):
            parse_production(text)


# ------------------------------------------------------------------------- errors


def _syntax_error(text: str) -> SoarSyntaxError:
    with pytest.raises(SoarSyntaxError) as info:
        parse(text, file="f.soar")
    return info.value


@pytest.mark.parametrize(
    ("text", "line", "column", "words"),
    [
        ("sp {p (state <s> ^a b) -> (write x)}", 1, 24, ["'-->'"]),
        ("sp {p (state <s> ^a b)\n  --> (<s> ^b c)", 2, 17, ["'}'", "end of input"]),
        ("sp {p (state <s> ^a b)\n  --> (<s> ^b c)\n\n  \n", 2, 17, ["end of input"]),
        ("sp {p (state <s> a b) --> }", 1, 18, ["'^'", "symbol 'a'"]),
        ("sp {p (state <s> ^a b) --> (s ^a b)}", 1, 31, ["'^'"]),
        ("sp {p :foo (state <s> ^a b) --> }", 1, 7, ["flag"]),
        ("sp {p (state <s> ^a b) --> (<s> ^a + b)}", 1, 36, ["a value before"]),
        ("sp {p (state <s> ^a b) --> (<s> ^a b ^c)}", 1, 40, ["')'"]),
        ("sp {p (state <s> ^a b) --> (<s> ^operator b @)}", 1, 45, ["'@'"]),
        ("sp {p (state <s> ^a b) --> (<s> ^operator b &)}", 1, 45, ["'&'"]),
        ("sp {p (state <s> ^a { }) --> }", 1, 23, ["'}'"]),
        ("sp {p (state <s> ^a << <x> >>) --> }", 1, 24, ["variable '<x>'"]),
        ("sp {p (state <s> ^a 1.5abc) --> }", 1, 22, ["'.'"]),
        ("sp {p (state <s>) --> (write x)}", 1, 17, ["attribute test after '(state'"]),
        ("sp {p (impasse <s>) --> (write x)}", 1, 19, ["'(impasse'"]),
        ("sp {t1 (state <s> ^a b) --> }", 1, 5, ["looks like an identifier"]),
        ("sp {p (state <s> ^a b) --> (<s> ^a b)}}", 1, 39, ["'}'"]),
        ("watch 1\n}", 2, 1, ["'}'"]),
        ("exec ls -l", 1, 1, ["never runs shell commands"]),
        ("cmd print", 1, 1, ["never runs shell commands"]),
        ("sp {p (state <s> ^a b\u0001) --> }", 1, 22, ["'\\x01'"]),
        ("sp {p (state <s> ^a |unterminated) --> }", 1, 21, ["unterminated string"]),
        ("sp", 1, 3, ["'{'"]),
        ("sp {p (state <s> ^a 9223372036854775808) --> }", 1, 21, ["64 bits"]),
        ("sp {p (state <s> ^a -1.0e999) --> }", 1, 21, ["too large"]),
    ],
)
def test_syntax_errors_have_position_caret_and_words(text, line, column, words) -> None:
    error = _syntax_error(text)
    assert (error.file, error.line, error.column) == ("f.soar", line, column)
    rendered = str(error)
    assert rendered.startswith(f"f.soar:{line}:{column}: ")
    assert error.source_line == text.splitlines()[line - 1] if text.strip() else True
    lines = rendered.splitlines()
    caret_line = next(i for i, item in enumerate(lines) if item.strip() == "^")
    assert lines[caret_line].index("^") - 4 == column - 1
    for word in words:
        assert word in rendered


def test_expected_tokens_are_words_not_lark_names() -> None:
    error = _syntax_error("sp {p (state <s> ^a b) -> }")
    assert error.expected == ("'('", "'-'", "'-->'", "'{'")
    error = _syntax_error("sp {p (state <s> ^ ) --> }")
    assert "variable" in error.expected and "constant" in error.expected
    assert not any(name.isupper() for name in error.expected)


def test_caret_keeps_tabs_aligned() -> None:
    error = _syntax_error("sp {p\n\t(state <s> ^a b) -> }")
    assert str(error).splitlines()[2] == "    \t" + " " * 17 + "^"


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("sp {p (state <s> ^a b) --> (<y> ^b c)}", ["<y>", "(<y> ^b c)"]),
        ("sp {p (state <s> ^a b) --> (<s> ^a (+ <z> 1))}", ["<z>"]),
        ("sp {p (state <s> ^a b) --> (write <z>)}", ["<z>"]),
        ("sp {p (state <s> ^a b) --> (<x> ^c d) (<y> ^b <x>)}", ["<x>"]),
        ("sp {p (state <s> ^x y -^a <n>) --> (<n> ^b c)}", ["<n>"]),
        ("sp {p (state <s> ^a b) -{(<s> ^c <n>) (<n> ^d e)} --> (<n> ^b c)}", ["<n>"]),
        ("sp {p (state <s> ^a > <n>) --> (write <n>)}", ["<n>"]),
        ("sp {p (state <s> ^a b) --> (<s> ^c (foo 1))}", ["unknown RHS function 'foo'"]),
        ("sp {p (state <s> ^a b) --> (<s> ^c (exec ls))}", ["'exec' is refused", "shell"]),
        ("sp {p (state <s> ^a b) --> (cmd print)}", ["'cmd' is refused"]),
        ("sp {p (state <s> ^a b) --> (write (exec rm))}", ["'exec' is refused"]),
        ("sp {p (state <s> ^a b) --> (<s> ^c d > e)}", ["binary preference", "^operator"]),
        ("sp {p :template (state <s> ^a b) --> (<s> ^c d)}", ["':template'", "not supported"]),
        ("sp {p (state <s> ^a <x>) --> (<s> ^<x> d = e)}", ["binary preference"]),
    ],
)
def test_semantic_errors_name_the_production(text: str, words: list[str]) -> None:
    with pytest.raises(SoarSemanticError) as info:
        parse("\n" + text, file="g.soar")
    assert info.value.production == "p"
    message = str(info.value)
    assert message.startswith("g.soar:2: production p: ")
    for word in words:
        assert word in message


def test_parse_partial_returns_what_precedes_the_first_error() -> None:
    good = "watch 1\nsp {p (state <s> ^a b) --> }\n"
    for bad, kind in [
        ("sp {q (state <s> ^a b) -> }\n", SoarSyntaxError),
        ("sp {q (state <s> ^a b) --> (foo)}\n", SoarSemanticError),
        ("exec rm -rf /\n", SoarSyntaxError),
    ]:
        items, error = parse_partial(good + bad + "echo never\n", "h.soar")
        assert [getattr(i, "name", None) for i in items] == ["watch", "p"]
        assert isinstance(error, kind) and "h.soar:3" in str(error)
    items, error = parse_partial(good)
    assert error is None and len(items) == 2


def test_first_error_stops_the_file() -> None:
    with pytest.raises(SoarSyntaxError) as info:
        parse("sp {p (state <s> ^a b) --> }\nsp {q (state <s> ^a) -> }\nsp {r oops}")
    assert info.value.line == 2


# ------------------------------------------------------------------------- real rule files


def _rule_files() -> list[Path]:
    files = sorted(ROOT.glob("rules/**/*.soar")) + sorted(ROOT.glob("tests/**/*.soar"))
    return [f for f in files if "/_build/" not in str(f)]


@pytest.mark.parametrize("path", _rule_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_rule_files_parse_and_round_trip(path: Path) -> None:
    items = parse_file(path, FUNCTIONS)  # the functions an Agent knows, as Agent.load checks
    productions = [item for item in items if isinstance(item, Production)]
    for production in productions:
        assert parse(format_production(production), functions=FUNCTIONS) == [production], (
            production.name)


def test_a_file_of_200_productions_parses_to_all_200_in_order() -> None:
    """How long it takes is measured by benchmarks/parsing.py, against the kernel."""
    rule = (
        "sp {{rule-{i} (state <s> ^a.b <x> ^c {{ <y> > 3 }} -^d e) (<x> ^f << g h >>)\n"
        "--> (<s> ^operator <o> + =) (<o> ^name n{i} ^value (+ <y> 1))\n"
        "    (write <y> (crlf))}}\n"
    )
    text = "".join(rule.format(i=i) for i in range(200))
    items = parse(text)
    assert [p.name for p in items] == [f"rule-{i}" for i in range(200)]


# ------------------------------------------------------------------------- the real kernel

# Tricky productions: the kernel must accept exactly those we accept. Not listed, because we
# differ on purpose: unknown RHS functions and exec/cmd (the kernel rewrites an unknown
# function into `exec`; we refuse both); numbers too large for 64 bits, which the kernel
# reports as "bad integer" and then loads anyway. The matcher's load-time checks (conditions
# not linked to a state, relational tests on unbound variables) are compared with the kernel
# in test_load_checks.py.
KERNEL_AGREEMENT = [
    "(state <s> ^a.b.c <v> -^d.e f) --> (<s> ^x.y z)",
    "(state <s>) --> (write hi)",
    "(impasse <s>) --> (write hi)",
    "(state <s> ^a) --> (<s> ^b <x>) (<x> ^c d)",
    "(state <s> ^a 1e3 ^b 1.5e2 ^c .5 ^d -.5 ^e 5. ^f |12| ^g 1.5e) --> (write hi)",
    "(state <s> ^g 1.5abc) --> (write hi)",
    "(state <s> ^a <x>) --> (<y> ^b c)",
    "(state <s> ^a <x>) --> (write <z>)",
    "(state <s> ^a b) --> (<s> ^a (+ <z> 1))",
    "(state <s> ^a b) --> (<s> ^a <n>) (write <n>)",
    "(state <s> ^a b) --> (<x> ^c d) (<s> ^b <x>) (<x> ^e.f g)",
    "(state <s> ^a b) --> (<x> ^c d) (<y> ^b <x>)",
    "(state <s> ^a b) --> (<s> ^<new> c)",
    "(state <s> ^operator <o> +) --> (<s> ^operator <o> > <new>)",
    "(state <s> ^operator <o> + ^operator <p> +) --> (<s> ^operator <o> > <p>, = 0.5, + )",
    "(state <s> ^operator <o> +) --> (<s> ^operator <o> + - ! ~ >, <, =)",
    "(state <s> ^operator <o> +) --> (<s> ^operator <o> +, -, !, ~, >, <, =)",
    "(state <s> ^operator <o> +) --> (<s> ^operator <o> @)",
    "(state <s> ^operator <o> +) --> (<s> ^operator <o> &)",
    "(state <s> ^operator <o> +) --> (<s> ^operator <o> < -)",
    "(state <s> ^a b) --> (<s> ^f g ~ + ! h - i)",
    "(state <s> ^a <x>) --> (<s> ^<x> g > h)",
    "(state <s> ^a b) --> (<s> ^z <w> = <v>)",
    "(state <s> ^a b) --> (<s> ^a b ^c)",
    "(state <s> ^a b) --> (<s> ^a b, +)",
    "(state <s> ^a b) --> (<s> ^a b c <d> 1 2.5 |x y|)",
    "(state <s> ^a b) --> (<s> ^a.b.c d e) (<s> ^a.b.c f)",
    "(state <s> ^a <x>) --> (<s> ^b (+ <x> (* 2 <x>)) ^c (concat |a b| <x>) (crlf))",
    "(state <s> ^x y) --> (<s> ^(concat a b) c)",
    "(state <s> ^x <y>) --> (<s> ^a (+ 1 (- <y>)) ^b (div 7 2) ^c (mod 7 2) ^d (abs -1))",
    "(state <s> ^x y) --> (write (int 2.5) (float 2) (make-constant-symbol a) (timestamp))",
    "(state <s> ^x y) --> (interrupt) (halt)",
    "(state <s> ^a {<x> <> 3 < 5} ^b << a b 1 >> ^c <=> <x> ^<att> @ <x> ^e !@ <x>) --> ",
    "(state <s> ^x << >>) --> (write hi)",
    "(state <s> ^x { }) --> (write hi)",
    "(state <s> ^x {<a> {<b> <c>}}) --> (write hi)",
    "(state <s> ^x << <a> b >>) --> (write hi)",
    "(state <s> ^x < <a>) --> (write hi)",
    "(state <s> ^x { <> <y> <y> }) --> (write hi)",
    "(state <s> ^a @) --> (write hi)",
    "(state <s> ^a b) -(<s> ^c d ^e f) -{(<s> ^g h)} -(<s> -^i j) --> (write hi)",
    "(state <s> ^x y -^a b c -^d.e f g) --> (write hi)",
    "{ (state <s> ^a b) (<s> ^c d) } -(<s> ^e) --> (write hi)",
    "(state ^a b) (impasse ^c d) --> (write hi)",
    '"doc" :o-support :default (state <s> ^a b) --> (<s> ^c d)',
    ":i-support :chunk :interrupt :default :default (state <s> ^a b) --> (<s> ^c d)",
    ":template (state <s> ^a b) --> (<s> ^c d)",
    "(state <s> ^operator <o> +) --> (<s> ^operator <o> > + = ~ <o>)",
    "(state <s> ^a b;c) --> (write hi)",
    ":foo (state <s> ^x y) --> (write hi)",
    "(state <s> ^x y) --> ",
    "(state <s> ^a s1 ^b x@y ^c |a\\|b| ^d |a\\\\b|) --> (<s> ^c S1 ^d |x#y|)",
    "(state <s> ^a b) ; (<s> ^c d) --> (write hi)",
    "(state <s> ^a b) -> (write hi)",
    "(state <s> ^a b) --> (s ^a b)",
    "(state <s> ^a b) (<s> ^c d --> (write hi)",
    "(state <s> ^a b) # a comment with } and { braces\n--> (write |}{#|)",
    "(state <s> ^a b) --> (write |x|) # trailing\n",
]


def _kernel_accepts(kernel, text: str) -> bool:
    kernel.agent.ExecuteCommandLine(text)
    return bool(kernel.agent.GetLastCommandLineResult())


def _we_accept(text: str) -> bool:
    try:
        parse(text)
    except (SoarSyntaxError, SoarSemanticError):
        return False
    return True


@pytest.mark.parametrize("body", KERNEL_AGREEMENT)
def test_the_kernel_accepts_exactly_what_we_accept(body: str) -> None:
    pytest.importorskip("soar_sml")
    from differential.kernel import KernelAgent

    text = f"sp {{agreement {body}}}"
    with KernelAgent() as kernel, warnings.catch_warnings():
        warnings.simplefilter("ignore", SoarWarning)
        assert _we_accept(text) == _kernel_accepts(kernel, text)


def test_the_kernel_also_refuses_identifier_like_names() -> None:
    pytest.importorskip("soar_sml")
    from differential.kernel import KernelAgent

    with KernelAgent() as kernel:
        assert not _kernel_accepts(kernel, "sp {t1 (state <s> ^a b) --> (write hi)}")
        assert _kernel_accepts(kernel, "sp {|t1| (state <s> ^a b) --> (write hi)}")
    assert _we_accept("sp {|t1| (state <s> ^a b) --> (write hi)}")


# ------------------------------------------------------------------------- the Pygments lexer


def test_highlighting_lexer_covers_every_rule_file_without_errors() -> None:
    from pygments.token import Error

    from sann.soar.lexer import SoarLexer

    for path in _rule_files():
        text = path.read_text(encoding="utf-8")
        tokens = list(SoarLexer().get_tokens(text))
        assert "".join(value for _, value in tokens).rstrip("\n") == text.rstrip("\n")
        assert not [value for kind, value in tokens if kind in Error], path


def test_highlighting_lexer_token_kinds() -> None:
    from pygments.token import Comment, Keyword, Name, Number, Operator, String

    from sann.soar.lexer import SoarLexer

    text = 'sp {a*b "doc" (state <s> ^a.b <x> -^c |x y| ^d 1.5) # note\n--> (<s> ^e (+ 1 2) >)}'
    kinds = {value: kind for kind, value in SoarLexer().get_tokens(text) if value.strip()}
    assert kinds["sp"] in Keyword and kinds["state"] in Keyword and kinds["-->"] in Keyword
    assert kinds["a*b"] in Name.Function and kinds['"doc"'] in String.Doc
    assert kinds["<s>"] in Name.Variable and kinds["b"] in Name.Attribute
    assert kinds["|x y|"] in String and kinds["1.5"] in Number.Float
    assert kinds["# note"] in Comment and kinds[">"] in Operator and kinds["+"] in Name.Builtin


def test_an_unchanged_text_is_parsed_once_and_warnings_come_back() -> None:
    """Re-sourcing an unchanged file (a notebook re-run) reuses its parse: equal items in a
    fresh list, the productions themselves shared (they are immutable); a text that warns is
    parsed again so that it warns again; another file name or RHS function set is another
    parse (errors and locations name the file)."""
    text = (ROOT / "rules" / "hanoi.soar").read_text()
    first = parse(text, "hanoi.soar")
    first.append("scribble")
    second = parse(text, "hanoi.soar")
    assert second == first[:-1] and all(a is b for a, b in zip(first, second, strict=False))
    elsewhere = parse(text, "other.soar")
    assert elsewhere == second and elsewhere[0] is not second[0]
    assert elsewhere[0].location.file == "other.soar"
    for _ in range(2):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            parse("sp {p (state <s> ^type state) --> (<s> ^f g ~)}")
        assert [w.category for w in caught] == [SoarWarning]
