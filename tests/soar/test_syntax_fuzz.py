"""Property tests of the parser (hypothesis, derandomised so every run is the same).

(a) random text and (b) mutated valid rule files either parse or raise a Soar error with a
position, never anything else; (c) random productions round-trip through print -> parse.
"""

from __future__ import annotations

import string
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from sann.soar.errors import SoarSemanticError, SoarSyntaxError
from sann.soar.parsing.actions import KNOWN_RHS_FUNCTIONS
from sann.soar.parsing.checks import kernel_refusals
from sann.soar.parsing.normalise import drop_unbound_relations
from sann.soar.parsing.parser import parse
from sann.soar.printer import format_production
from sann.soar.production import (
    RELATIONS,
    CallAction,
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

ROOT = Path(__file__).resolve().parents[2]
# Mutations often make a preference land on a non-operator attribute: the kernel's warning.
pytestmark = pytest.mark.filterwarnings("ignore::sann.soar.errors.SoarWarning")
FUZZ = settings(
    derandomize=True,
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)


def _parses_or_fails_cleanly(text: str) -> None:
    """The property: a list of items, or a Soar error that says where."""
    try:
        items = parse(text, file="fuzz.soar")
    except SoarSyntaxError as error:
        assert error.file == "fuzz.soar"
        assert error.line >= 1 and error.column >= 1
        assert error.line <= text.count("\n") + 1
        assert str(error).startswith(f"fuzz.soar:{error.line}:{error.column}: ")
    except SoarSemanticError as error:
        assert error.production and str(error).startswith("fuzz.soar:")
        assert error.location.line >= 1 and error.location.column >= 1
    else:
        assert isinstance(items, list)


# ------------------------------------------------------------------------ (a) garbage

SOAR_CHARS = 'sp{}()^<>=-+!~@.,;|"#\n\t *$%&/:?_<<>>012345.eE' + string.ascii_letters[:8]
SOAR_WORDS = [
    "sp", "{", "}", "(", ")", "state", "impasse", "<s>", "<x>", "^", "^a", ".", "-->", "-",
    "+", "<<", ">>", "<>", "<=>", "@", "!@", "|x y|", '"doc"', ":o-support", "1", "2.5",
    "(write", "(crlf)", ",", ";", "#c\n", "\n", "exec", "watch", "source", "-{", "-^",
]  # fmt: skip


@FUZZ
@given(st.text(alphabet=SOAR_CHARS, max_size=80))
def test_random_characters_never_crash(text: str) -> None:
    _parses_or_fails_cleanly(text)


@FUZZ
@given(st.text(max_size=60))
def test_random_unicode_never_crashes(text: str) -> None:
    _parses_or_fails_cleanly(text)


@FUZZ
@given(st.lists(st.sampled_from(SOAR_WORDS), max_size=30))
def test_random_token_soup_never_crashes(words: list[str]) -> None:
    _parses_or_fails_cleanly(" ".join(words))


# ------------------------------------------------------------------------ (b) mutations

VALID = """\
sp {propose*move "doc" :o-support
   (state <s> ^name blocks ^block <b> ^a.b.c {<x> > 3} -^done true)
   (<b> ^color << red blue >> ^size <= 10 -^on |the table|)
   -{(<b> ^clear no) (<s> ^holding <b>)}
-->
   (<s> ^operator <o> + =, ^operator <o> > <b>)
   (<o> ^name move ^value (+ <x> (* 2 1.5)))
   (write |moved | <b> (crlf))}
"""


def _files() -> list[str]:
    texts = [VALID]
    for path in sorted(ROOT.glob("rules/*.soar"))[:4]:
        texts.append(path.read_text(encoding="utf-8")[:1500])
    return texts


@st.composite
def mutated(draw: st.DrawFn) -> str:
    text = draw(st.sampled_from(_files()))
    for _ in range(draw(st.integers(1, 4))):
        if not text:
            break
        i = draw(st.integers(0, len(text) - 1))
        kind = draw(st.sampled_from(["delete", "insert", "swap", "duplicate"]))
        if kind == "delete":
            text = text[:i] + text[i + draw(st.integers(1, 5)) :]
        elif kind == "insert":
            text = text[:i] + draw(st.sampled_from(SOAR_WORDS + list(SOAR_CHARS))) + text[i:]
        elif kind == "swap" and i + 1 < len(text):
            text = text[:i] + text[i + 1] + text[i] + text[i + 2 :]
        else:
            text = text[:i] + text[i : i + 12] + text[i:]
    return text


@FUZZ
@given(mutated())
def test_mutated_rule_files_never_crash(text: str) -> None:
    _parses_or_fails_cleanly(text)


# ------------------------------------------------------------------------ (c) round trip

NAMES = st.from_regex(r"[a-z][a-z0-9*_\-]{0,6}", fullmatch=True)
VARS = st.builds(Var, st.sampled_from(["s", "x", "y", "o", "a*1", "b*2", "block", "Z"]))
SYMBOLS = st.one_of(
    NAMES,
    st.sampled_from(["state", "impasse", "s1", "S1", "12", "1e3", "-", "+", "<x>", "<<", "@",
                     "-->", ":o-support", "a b", "a|b", "back\\slash", "#hash", "", "nil"]),
    st.text(max_size=6),
)  # fmt: skip
CONSTS = st.builds(
    Const,
    st.one_of(
        SYMBOLS,
        st.integers(-(2**63), 2**63 - 1),
        st.floats(allow_nan=False, allow_infinity=False),
    ),
)
SINGLE = st.one_of(VARS, CONSTS)
SIMPLE = st.one_of(
    SINGLE,
    st.builds(Relational, st.sampled_from([op for op in RELATIONS if op != "="]), SINGLE),
    st.builds(Disjunction, st.lists(CONSTS, max_size=3).map(tuple)),
)
TESTS = st.one_of(
    SIMPLE, st.builds(Conjunction, st.lists(SIMPLE, min_size=2, max_size=3).map(tuple))
)


def conditions(depth: int = 0) -> st.SearchStrategy:
    condition = st.builds(
        Condition,
        TESTS,
        TESTS,
        TESTS,
        negated=st.booleans(),
        acceptable=st.booleans(),
        goal=st.sampled_from([None, "state", "impasse"]),
    )
    if depth >= 2:
        return condition
    inner = conditions(depth + 1)
    # The parser's normal form: a conjunctive negation holds two or more elements (as in the
    # kernel, a single negated condition is a plain negated condition, and the negation of
    # a single conjunctive negation its conditions).
    ncc = st.lists(inner, min_size=2, max_size=3).map(tuple).map(ConjunctiveNegation)
    return st.one_of(condition, condition, ncc)


@st.composite
def productions(draw: st.DrawFn) -> Production:
    bound = draw(st.lists(VARS, min_size=1, max_size=3, unique=True))
    first = Condition(bound[0], draw(TESTS), bound[-1], goal=draw(st.sampled_from([None, "state"])))
    more = [Condition(draw(st.sampled_from(bound)), draw(CONSTS), var) for var in bound[1:-1]]
    conds = [first, *more, *draw(st.lists(conditions(), max_size=4))]
    grounded = st.sampled_from(bound)
    rhs_value = st.recursive(
        st.one_of(grounded, CONSTS),
        lambda inner: st.builds(
            FuncCall,
            st.sampled_from(sorted(KNOWN_RHS_FUNCTIONS)),
            st.lists(inner, max_size=3).map(tuple),
        ),
        max_leaves=4,
    )
    # The parser's normal form (the kernel's rule): any preference on ^operator; elsewhere
    # only + and -, and binary preferences only on ^operator.
    operator = st.just(Const("operator"))
    on_operator = st.builds(
        MakeAction,
        grounded,
        operator,
        rhs_value,
        st.sampled_from(["+", "-", "!", "~", ">", "<", "="]),
    )
    elsewhere = st.builds(
        MakeAction,
        grounded,
        rhs_value.filter(lambda v: v != Const("operator")),
        rhs_value,
        st.sampled_from(["+", "-"]),
    )
    binary = st.builds(
        MakeAction, grounded, operator, rhs_value, st.sampled_from([">", "<", "="]), rhs_value
    )
    call = st.builds(CallAction, rhs_value.filter(lambda v: isinstance(v, FuncCall)))
    actions = draw(st.lists(st.one_of(on_operator, elsewhere, binary, call), max_size=5))
    return Production(
        name=draw(st.one_of(NAMES, SYMBOLS).filter(lambda n: n not in ("s1", "S1"))),
        conditions=tuple(conds),
        actions=tuple(actions),
        doc=draw(st.one_of(st.none(), st.text(max_size=10))),
        flags=tuple(draw(st.lists(st.sampled_from(["o-support", "i-support", "default"]),
                                  max_size=2))),
    )  # fmt: skip


def _in_kernel_form(production: Production) -> bool:
    """Whether the parser gives the production back unchanged: the kernel (and the parser)
    refuses one without a root or with a negated relational test on an unbound variable,
    and drops a positive condition's relational test on a variable nothing binds."""
    try:
        kernel_refusals(production)
    except SoarSemanticError:
        return False
    kept = drop_unbound_relations(production.conditions, set(), lambda letter: Var(letter))
    return kept == production.conditions


@settings(derandomize=True, max_examples=120, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])  # fmt: skip
@given(productions())
def test_random_productions_round_trip(production: Production) -> None:
    assume(_in_kernel_form(production))
    text = format_production(production)
    assert parse(text) == [production], text
