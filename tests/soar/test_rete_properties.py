"""Property tests: after any sequence of WME changes, production additions and excises, the
Rete's matches equal the brute-force join's, and take_changes() reports a consistent stream.

The symbol alphabets are tiny so that joins, negations and relational tests actually fire.
"""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sann.soar.errors import SoarSemanticError
from sann.soar.matching.matches import Match
from sann.soar.matching.oracle import BruteForceMatcher
from sann.soar.matching.rete import Rete
from sann.soar.memory import WME, Identifier
from sann.soar.production import (
    Condition,
    Conjunction,
    ConjunctiveNegation,
    Const,
    Disjunction,
    MakeAction,
    Production,
    Relational,
    Var,
)

STATES = [Identifier("S", 1, level=1), Identifier("S", 2, level=2)]
OTHERS = [Identifier("A", 1), Identifier("B", 2), Identifier("C", 3)]
IDS = STATES + OTHERS
ATTRS = ["a", "b", "c", "a", "b", 1]
VALUES = OTHERS * 4 + STATES + [1, 2, 1.0, "x", "y", "1"]
VARS = ["s", "x", "y", "z"]
CONSTS = [1, 2, 1.0, 2.5, "x", "y", "1", "a", "b"]

wme_specs = st.tuples(
    st.sampled_from(IDS),
    st.sampled_from(ATTRS),
    st.sampled_from(VALUES),
    st.sampled_from([False, False, False, True]),
)

variables = st.sampled_from(VARS).map(Var)
constants = st.sampled_from(CONSTS).map(Const)
relations = st.builds(
    Relational,
    st.sampled_from(["<>", "<", ">", "<=", ">=", "<=>", "@", "!@"]),
    variables | constants,
)
simple_tests = (
    variables
    | constants
    | relations
    | st.builds(Disjunction, st.lists(constants, min_size=1, max_size=3).map(tuple))
)
tests = simple_tests | st.builds(
    Conjunction,
    st.tuples(
        variables,
        st.sampled_from(
            [Relational("<>", Var("s")), Relational(">", Var("y")), Relational("<=>", Const(1))]
        ),
    ),
)
attr_tests = (
    st.sampled_from(["a", "b", "c"]).map(Const)
    | variables
    | st.builds(Disjunction, st.just((Const("a"), Const("b"))))
)


@st.composite
def linked_condition(
    draw: st.DrawFn, bound: list[str], negated: bool = False, local: str = "n"
) -> Condition:
    """A condition joining on a bound identifier; binds a new variable or tests a bound one."""
    ident = draw(st.sampled_from(bound))
    fresh = [v for v in VARS if v not in bound]
    value = draw(
        st.sampled_from(
            ["new", "new", "bound", "const", "test"]
            if fresh or negated
            else ["bound", "const", "test"]
        )
    )
    if value == "new":
        name = local if negated else fresh[0]
        value_test = Var(name)
        if draw(st.booleans()):
            value_test = Conjunction(
                (
                    Var(name),
                    draw(
                        st.builds(
                            Relational,
                            st.sampled_from(["<>", "<", ">=", "<=>"]),
                            st.sampled_from(bound).map(Var) | constants,
                        )
                    ),
                )
            )
        if not negated:
            bound.append(name)
    elif value == "bound":
        value_test = Var(draw(st.sampled_from(bound)))
    elif value == "const":
        value_test = draw(
            constants
            | st.builds(Disjunction, st.lists(constants, min_size=1, max_size=3).map(tuple))
        )
    else:
        value_test = draw(
            st.builds(
                Relational,
                st.sampled_from(["<>", "<", ">", "<=", ">=", "<=>", "@", "!@"]),
                st.sampled_from(bound).map(Var) | constants,
            )
        )
    attr = draw(
        st.sampled_from(
            [
                Const("a"),
                Const("b"),
                Const("c"),
                Const("a"),
                Var("s") if negated else Const("b"),
                Disjunction((Const("a"), Const("c"))),
            ]
        )
    )
    return Condition(
        Var(ident),
        attr,
        value_test,
        negated=negated,
        acceptable=draw(st.integers(0, 7)) == 0,
        goal="state" if ident == "s" and draw(st.integers(0, 3)) == 0 else None,
    )


@st.composite
def linked_ncc(draw: st.DrawFn, bound: list[str], depth: int = 0) -> ConjunctiveNegation:
    inner_bound = list(bound)
    inner: list = [draw(linked_condition(inner_bound)) for _ in range(draw(st.integers(1, 2)))]
    if draw(st.booleans()):
        inner.append(draw(linked_condition(inner_bound, negated=True, local="m")))
    if depth == 0 and draw(st.integers(0, 2)) == 0:
        inner.append(draw(linked_ncc(inner_bound, depth=1)))
    return ConjunctiveNegation(tuple(inner))


@st.composite
def linked_productions(draw: st.DrawFn, name: str) -> Production:
    bound = ["s"]
    first = draw(linked_condition(bound))
    first = Condition(first.id_test, first.attr_test, first.value_test, goal="state")
    rest: list = []
    for _ in range(draw(st.integers(0, 4))):
        kind = draw(st.sampled_from(["pos", "pos", "neg", "ncc"]))
        if kind == "pos":
            rest.append(draw(linked_condition(bound)))
        elif kind == "neg":
            rest.append(draw(linked_condition(bound, negated=True)))
        else:
            rest.append(draw(linked_ncc(bound)))
    if draw(st.booleans()):  # written order differs from the join order
        rest = draw(st.permutations(rest))
    return Production(name, (first, *rest), ())


@st.composite
def conditions(draw: st.DrawFn, negated: bool = False) -> Condition:
    return Condition(
        id_test=draw(variables),
        attr_test=draw(attr_tests),
        value_test=draw(tests),
        negated=negated,
        acceptable=draw(st.integers(0, 9)) == 0,
        goal=draw(st.sampled_from([None, None, None, "state"])),
    )


@st.composite
def nccs(draw: st.DrawFn, depth: int = 0) -> ConjunctiveNegation:
    inner: list = draw(st.lists(conditions(), min_size=1, max_size=2))
    if draw(st.booleans()):
        inner.append(draw(conditions(negated=True)))
    if depth == 0 and draw(st.integers(0, 3)) == 0:
        inner.append(draw(nccs(depth=1)))
    return ConjunctiveNegation(tuple(inner))


@st.composite
def productions(draw: st.DrawFn, name: str) -> Production:
    """Mostly linked productions; sometimes free-form ones (most fail the semantic checks,
    and both matchers must then refuse them)."""
    if draw(st.integers(0, 4)) > 0:
        return draw(linked_productions(name))
    first = Condition(Var("s"), draw(attr_tests), draw(tests), goal="state")
    rest = draw(st.lists(conditions() | conditions(negated=True) | nccs(), min_size=0, max_size=4))
    return Production(name, (first, *rest), ())


@st.composite
def scripts(draw: st.DrawFn) -> list[tuple]:
    steps: list[tuple] = []
    for i in range(draw(st.integers(1, 4))):
        steps.append(("production", draw(productions(f"p{i}"))))
    steps += [("add", spec) for spec in draw(st.lists(wme_specs, min_size=5, max_size=25))]
    steps += draw(
        st.lists(
            st.tuples(st.just("add"), wme_specs)
            | st.tuples(st.just("add"), wme_specs)
            | st.tuples(st.just("remove"), st.integers(0, 99))
            | st.tuples(st.just("remove"), st.integers(0, 99))
            | st.tuples(st.just("excise"), st.integers(0, 9))
            | st.tuples(st.just("production"), productions("q")),
            min_size=5,
            max_size=30,
        )
    )
    steps += [("remove", i) for i in draw(st.lists(st.integers(0, 99), max_size=15))]
    steps += [("add", spec) for spec in draw(st.lists(wme_specs, max_size=10))]
    return draw(st.permutations(steps)) if draw(st.integers(0, 3)) == 0 else steps


def _key(match: Match) -> tuple:
    bindings = tuple(
        sorted(
            (name, type(v).__name__, v if not isinstance(v, Identifier) else id(v))
            for name, v in match.bindings.items()
        )
    )
    return match.production.name, tuple(id(w) for w in match.wmes), bindings


class _Observer:
    """Replays take_changes() and checks the stream: a retracted match was reported
    before, a new one was not live, and the live set is the matcher's current matches."""

    def __init__(self, matcher: Rete | BruteForceMatcher) -> None:
        self.matcher = matcher
        self.live: dict[Match, None] = {}

    def sync(self, added_production: str | None = None) -> set[tuple]:
        """Replay the changes; right after ``added_production`` was added, the only
        changes are its own new matches."""
        added, removed = self.matcher.take_changes()
        if added_production is not None:
            assert removed == []
            assert {m.production.name for m in added} <= {added_production}
        for match in removed:
            assert match in self.live, f"retracted but never reported: {match}"
            del self.live[match]
        for match in added:
            assert match not in self.live, f"reported twice: {match}"
            self.live[match] = None
        current = {m for p in self.matcher.productions() for m in self.matcher.matches(p.name)}
        assert current == set(self.live)
        keys = [_key(m) for m in current]
        assert len(keys) == len(set(keys)), "duplicate matches"
        return set(keys)


def _run(script: list[tuple], check_links: bool = True) -> None:
    rete, brute = Rete(check_links), BruteForceMatcher(check_links)
    observers = [_Observer(rete), _Observer(brute)]
    memory: list[WME] = []
    timetag = 0
    names: list[str] = []
    counter = 0
    for step in script:
        kind = step[0]
        if kind == "add":
            identifier, attr, value, acceptable = step[1]
            timetag += 1
            wme = WME(identifier, attr, value, timetag, acceptable)
            memory.append(wme)
            rete.add_wme(wme)
            brute.add_wme(wme)
        elif kind == "remove" and memory:
            wme = memory.pop(step[1] % len(memory))
            rete.remove_wme(wme)
            brute.remove_wme(wme)
        elif kind == "excise" and names:
            name = names.pop(step[1] % len(names))
            rete.excise(name)
            brute.excise(name)
        elif kind == "production":
            counter += 1
            production = step[1]
            # Some rules remove an attribute: the Rete then treats checks of it as volatile
            # and rebuilds the rules already built (their matches must survive unchanged).
            actions = () if counter % 3 else (
                MakeAction(Var("s"), Const("abc"[counter % 9 // 3]), Const("x"), "-"),)
            production = Production(f"{production.name}-{counter}", production.conditions,
                                    actions)
            assert observers[0].sync() == observers[1].sync()
            try:
                brute.add_production(production)
            except SoarSemanticError:
                try:
                    rete.add_production(production)
                except SoarSemanticError:
                    continue
                raise AssertionError("the Rete accepted a production the checks reject") from None
            rete.add_production(production)
            names.append(production.name)
            for observer in observers:
                observer.sync(added_production=production.name)
        if counter % 2 == 0 or kind != "add":
            assert observers[0].sync() == observers[1].sync()
    assert observers[0].sync() == observers[1].sync()


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scripts())
def test_rete_matches_equal_brute_force(script: list[tuple]) -> None:
    _run(script)


@st.composite
def joins(draw: st.DrawFn) -> list[tuple]:
    """Positive joins only, long chains and big memories: the hashed-join paths."""
    steps: list[tuple] = []
    for i in range(3):
        conds = [Condition(Var("s"), Const("a"), Var("x"), goal="state")]
        for _ in range(draw(st.integers(1, 4))):
            conds.append(
                Condition(
                    draw(st.sampled_from([Var("x"), Var("y")])),
                    draw(st.sampled_from([Const("b"), Const("c"), Var("z")])),
                    draw(st.sampled_from([Var("y"), Var("z"), Const(1)])),
                )
            )
        steps.append(("production", Production(f"j{i}", tuple(conds), ())))
    steps += draw(
        st.lists(
            st.tuples(st.just("add"), wme_specs.filter(lambda s: not s[3]))
            | st.tuples(st.just("remove"), st.integers(0, 99)),
            min_size=10,
            max_size=60,
        )
    )
    return steps


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(joins())
def test_rete_positive_joins_equal_brute_force(script: list[tuple]) -> None:
    _run(script)


NEGATION_RULES = [
    # (written conditions after (state <s> ^a <x>))
    (Condition(Var("x"), Const("b"), Var("n"), negated=True),),
    (Condition(Var("x"), Const("b"), Var("s"), negated=True),
     Condition(Var("x"), Const("c"), Var("y"))),
    (ConjunctiveNegation((Condition(Var("x"), Const("b"), Var("y")),
                          Condition(Var("y"), Const("c"), Var("z")))),),
    (ConjunctiveNegation((Condition(Var("x"), Const("b"), Var("y")),
                          Condition(Var("y"), Const("c"), Var("x"), negated=True))),),
    (ConjunctiveNegation((Condition(Var("x"), Const("b"), Var("y")),
                          ConjunctiveNegation((Condition(Var("y"), Const("c"), Var("z")),
                                               Condition(Var("z"), Const("a"), Var("x")))))),),
    (Condition(Var("x"), Const("c"), Var("y")),
     ConjunctiveNegation((Condition(Var("y"), Const("b"), Var("z")),
                          Condition(Var("z"), Const("b"), Var("x")))),
     Condition(Var("y"), Const("a"), Var("n"), negated=True)),
    # value-hashed ("reverse") joins: (<y> ^c <x>) is joined on <x> before <y> is bound
    (Condition(Var("s"), Const("b"), Var("y")), Condition(Var("y"), Const("c"), Var("x"))),
    (Condition(Var("x"), Const("a"), Var("z")), Condition(Var("s"), Const("b"), Var("y")),
     Condition(Var("y"), Const("c"), Var("z"))),
    (ConjunctiveNegation((Condition(Var("s"), Const("b"), Var("y")),
                          Condition(Var("y"), Const("c"), Var("x")))),),
]
SMALL_IDS = [STATES[0], OTHERS[0], OTHERS[1]]


@st.composite
def negation_scripts(draw: st.DrawFn) -> list[tuple]:
    """Fixed rules with negations and nested NCCs over a three-identifier memory, so
    that blocking and unblocking happen all the time."""
    small = st.tuples(st.sampled_from(SMALL_IDS), st.sampled_from(["a", "b", "c"]),
                      st.sampled_from(SMALL_IDS[1:] + ["x"]), st.just(False))
    steps: list[tuple] = [("add", spec) for spec in draw(st.lists(small, max_size=8))]
    for i in draw(st.lists(st.integers(0, len(NEGATION_RULES) - 1), min_size=1, max_size=3,
                           unique=True)):
        first = Condition(Var("s"), Const("a"), Var("x"), goal="state")
        steps.append(("production", Production(f"n{i}", (first, *NEGATION_RULES[i]), ())))
    steps += draw(st.lists(st.tuples(st.just("add"), small)
                           | st.tuples(st.just("remove"), st.integers(0, 99)),
                           min_size=5, max_size=40))
    return steps


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(negation_scripts())
def test_rete_negations_equal_brute_force(script: list[tuple]) -> None:
    _run(script)


@st.composite
def unlinked_scripts(draw: st.DrawFn) -> list[tuple]:
    """Free-form rules (conditions need not be linked to a state, the first need not test a
    state nor be positive, as in the kernel): cross products and joins on any bound
    variable."""
    steps: list[tuple] = [("add", spec) for spec in draw(st.lists(wme_specs, max_size=12))]
    for i in range(draw(st.integers(1, 3))):
        first = draw(conditions())
        rest = draw(st.lists(conditions() | conditions(negated=True) | nccs(), max_size=2))
        elements = tuple(draw(st.permutations([first, *rest])))
        steps.append(("production", Production(f"u{i}", elements, ())))
    steps += draw(st.lists(st.tuples(st.just("add"), wme_specs)
                           | st.tuples(st.just("remove"), st.integers(0, 99)),
                           min_size=3, max_size=20))
    return steps


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(unlinked_scripts())
def test_unlinked_rules_equal_brute_force(script: list[tuple]) -> None:
    _run(script, check_links=False)
