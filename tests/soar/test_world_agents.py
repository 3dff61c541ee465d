"""Random agents compared with the real Soar 9.6 kernel (soar_sml), whole behaviour.

World agents:
Each agent makes a few objects with kinds, values and links, elaborates them (predicates,
disjunctions, negations, conjunctive negations, math), proposes operators on them with
random preferences (several instantiations of one rule tie), prefers some over others,
and resolves its impasses in substates (ties and conflicts by result preferences, by an
evaluation operator, state and operator no-change). Halting, the operator sequence, the
written output, the counts of the ``stats`` command and the final working memory must be
the kernel's. Found this way (each now a kernel rule in the engine): the order of the
matches one WME makes at one join, the order of an alpha memory's joins relinked in one
batch, the items of a conflict impasse, when the application phase checks the goal stack,
and what an impasse's ``^item`` WME backtraces to.

Deep agents: a top operator on an item has no application, so a substate works it out
(counting steps, results of either support, a third level whose one firing makes results
one and two levels up), with ties, elaborations of the items and goal dependency sets.
Found this way: justifications chained level by level, an o-supported justification's
reject taking the rule's own, the goal dependency set through rejected elaborations, the
order of tokens one WME made.

Preference agents: up to five top operators with random unary preferences (acceptable,
indifferent with and without numbers, best, worst, require, prohibit, reject) and binary
ones, both selection policies and numeric-indifferent modes, phases that switch which
rules propose, and substates for tie, conflict and constraint-failure impasses. Found
this way: the order of joins one WME relinks.

Matching agents: objects with typed values (ints, floats, strings, identifier-like
constants) under a few attributes, elaborated by rules with predicates against constants
and variables, attribute variables, paths, disjunctions, negations, conjunctive negations
and joins between objects; operators that double values, replace them by strings, add
halves or remove objects. Found this way: relational tests between values of different
kinds, and where the kernel's reorderer moves a test on a later-bound variable.
"""

from __future__ import annotations

import random

import pytest
from differential.kernel import run_kernel, run_ours

pytest.importorskip("soar_sml")

KINDS = ["a", "b", "c"]
PREDICATES = ["<", ">", "<=", ">=", "<>"]


def world_agent(seed: int) -> str:
    """The rule file of one random world agent."""
    r = random.Random(seed)
    lines = [f"indifferent-selection --{r.choice(['first', 'last'])}"]
    lines += _init(r)
    lines += [_elaboration(r, k) for k in range(r.randint(1, 4))]
    limit = r.randint(3, 7)
    ops = [f"op{i}" for i in range(r.randint(2, 4))]
    for op in ops:
        lines += _operator(r, op, limit)
    lines += [_preference(r, ops, k) for k in range(r.randint(0, 3))]
    lines += _impasses(r)
    lines.append(
        f"sp {{done (state <s> ^superstate nil ^count >= {limit})"
        " --> (write |done| (crlf)) (halt)}"
    )
    return "\n".join(lines) + "\n"


def _init(r: random.Random) -> list[str]:
    count = r.randint(2, 4)
    things = " ".join(f"<t{i}>" for i in range(count))
    body = " ".join(
        f"(<t{i}> ^kind {r.choice(KINDS)} ^val {r.randint(0, 5)}"
        + (f" ^link <t{i - 1}>" if i and r.random() < 0.5 else "")
        + ")"
        for i in range(count)
    )
    return [
        "sp {init (state <s> ^superstate nil -^count) --> (<s> ^operator <o> + >)"
        " (<o> ^name init)}",
        f"sp {{init*a (state <s> ^operator.name init) --> (<s> ^count 0 ^thing {things}) {body}}}",
    ]


def _elaboration(r: random.Random, k: int) -> str:
    head = f"sp {{elab{k} "
    kind = r.randrange(6)
    if kind == 0:
        value = f"{{<v> {r.choice(PREDICATES)} {r.randint(0, 5)}}}"
        return head + f"(state <s> ^thing <t>) (<t> ^val {value}) --> (<t> ^mark m{k})}}"
    if kind == 1:
        kinds = " ".join(r.sample(KINDS, 2))
        return head + (
            f"(state <s> ^superstate nil ^thing <t>) (<t> ^kind << {kinds} >>) -(<t> ^mark)"
            " --> (<s> ^plain <t>)}"
        )
    if kind == 2:
        return head + (
            "(state <s> ^superstate nil ^thing <t>) (<t> ^val <v>)"
            " -{(<s> ^thing <u>) (<u> ^val > <v>)} --> (<s> ^max <v>)}"
        )
    if kind == 3:
        return head + "(state <s> ^thing <t>) (<t> ^link.val <v>) --> (<t> ^linkval (+ <v> 1))}"
    if kind == 4:
        return head + (
            "(state <s> ^superstate nil ^count <c>) --> (<s> ^half (div <c> 2) ^ratio (/ <c> 4.0))}"
        )
    return head + (
        "(state <s> ^thing <t> ^thing {<u> <> <t>}) (<t> ^kind <k> ^val <v>)"
        " (<u> ^kind <k> ^val < <v>) --> (<s> ^pair <p>) (<p> ^hi <t> ^lo <u>)}"
    )


def _operator(r: random.Random, op: str, limit: int) -> list[str]:
    pref = r.choice(["+", "+", "+ =", "+ >", "+ <", "+ = 0.3", "+ ~", "+ !", "+ -", "+ = <"])
    kind = r.choice([*KINDS, "<k>"])
    test = r.choice(["", f" ^val < {r.randint(2, 9)}", " -^mark", " ^mark"])
    effect = r.choice([
        "(<t> ^val <v> - (+ <v> 1))",
        "(<t> ^val <v> - (- <v> 2))",
        "(<s> ^thing <t> -)",
        "(<s> ^thing <n>) (<n> ^kind c ^val <c>)",
        "(<t> ^mark x)",
        "",
    ])
    return [
        f"sp {{p{op} (state <s> ^superstate nil ^count <c> < {limit} ^thing <t>)"
        f" (<t> ^kind {kind}{test}) --> (<s> ^operator <o> {pref}) (<o> ^name {op} ^target <t>)}}",
        f"sp {{a{op} (state <s> ^operator <o> ^count <c>) (<o> ^name {op} ^target <t>)"
        f" (<t> ^val <v>) --> (<s> ^count <c> - (+ <c> 1)) {effect} (write |{op} | <v> (crlf))}}",
    ]


def _preference(r: random.Random, ops: list[str], k: int) -> str:
    x, y = r.sample(ops, 2) if r.random() < 0.7 else (ops[0], ops[0])
    relation = r.choice([">", "<", "="])
    test = r.choice([">", "<", "<>", ">="])
    return (
        f"sp {{pr{k} (state <s> ^operator <x> + ^operator {{<y> <> <x>}} +)"
        f" (<x> ^name {x} ^target.val <v>) (<y> ^name {y} ^target.val {test} <v>)"
        f" --> (<s> ^operator <x> {relation} <y>)}}"
    )


def _impasses(r: random.Random) -> list[str]:
    kind = r.randrange(4)
    lines = []
    if kind == 0:
        lines.append(
            "sp {tie (state <s> ^impasse << tie conflict >> ^superstate <ss> ^item <i>"
            " -^item {<j> > <i>}) --> (<ss> ^operator <i> >)}"
        )
    elif kind == 1:
        lines += [
            "sp {tie*p (state <s> ^impasse << tie conflict >> ^item <i>) (<i> ^target.val <v>)"
            " --> (<s> ^operator <e> +) (<e> ^name eval ^item <i> ^v <v>)}",
            "sp {tie*pref (state <s> ^impasse tie ^operator <a> + ^operator <b> +) (<a> ^v <v>)"
            " (<b> ^v < <v>) --> (<s> ^operator <a> > <b>)}",
            "sp {tie*a (state <s> ^operator <e> ^superstate <ss>) (<e> ^name eval ^item <i>)"
            " --> (<ss> ^operator <i> >) (<s> ^evaluated <i>)}",
        ]
    elif kind == 2:
        lines += [
            "sp {tie (state <s> ^impasse tie ^superstate <ss> ^item <i>) (<i> ^target.kind a)"
            " --> (<ss> ^operator <i> !)}",
            "sp {conf (state <s> ^impasse conflict ^superstate <ss> ^item <i>)"
            " --> (<ss> ^operator <i> -)}",
        ]
    return lines + [
        "sp {snc (state <s> ^impasse no-change ^attribute state ^superstate <ss>)"
        " (<ss> ^count <c>) --> (<ss> ^count <c> - (+ <c> 1)) (<ss> ^snc yes)}",
        "sp {onc (state <s> ^impasse no-change ^attribute operator ^superstate <ss>)"
        " (<ss> ^operator <o>) --> (<s> ^operator <q> +) (<q> ^name fix)}",
        "sp {oncfix (state <s> ^operator.name fix ^superstate <ss>) (<ss> ^count <c>)"
        " --> (<ss> ^count <c> - (+ <c> 10))}",
    ]


def deep_agent(seed: int) -> str:
    """The rule file of one random deep agent."""
    r = random.Random(seed)
    lines = [f"indifferent-selection --{r.choice(['first', 'last'])}"]
    count = r.randint(2, 4)
    items = " ".join(f"<i{k}>" for k in range(count))
    body = " ".join(
        f"(<i{k}> ^id {k} ^w {r.randint(1, 9)} ^tag |t{r.randint(0, 2)}|)" for k in range(count)
    )
    lines += [
        "sp {init (state <s> ^superstate nil -^count) --> (<s> ^operator <o> + >)"
        " (<o> ^name init)}",
        f"sp {{init*a (state <s> ^operator.name init) --> (<s> ^count 0 ^box <b>)"
        f" (<b> ^item {items}) {body}}}",
    ]
    limit = r.randint(2, 5)
    pref = r.choice(["+", "+ =", "+ = 0.5", "+ <", "+ >"])
    test = r.choice(["", " ^w > 3", " ^tag |t1|", " -^done"])
    lines.append(
        f"sp {{top*work (state <s> ^superstate nil ^count <c> < {limit} ^box.item <i>)"
        f" (<i> ^id <k>{test}) --> (<s> ^operator <o> {pref}) (<o> ^name work ^item <i>)}}"
    )
    if r.random() < 0.5:
        lines.append(
            "sp {top*pref (state <s> ^operator <a> + ^operator <b> +) (<a> ^item.w <x>)"
            " (<b> ^item.w < <x>) --> (<s> ^operator <a> > <b>)}"
        )
    else:
        lines += [
            "sp {top*tie (state <s> ^impasse tie ^superstate <ss> ^item <o>) (<o> ^item.id 0)"
            " --> (<ss> ^operator <o> >)}",
            "sp {top*tie2 (state <s> ^impasse tie ^superstate <ss> ^item <o>)"
            " (<o> ^item.id <> 0) --> (<ss> ^operator <o> <)}",
        ]
    lines.append(
        "sp {sub*elab (state <s> ^impasse no-change ^attribute operator"
        " ^superstate.operator <o>) (<o> ^item <i>) --> (<s> ^target <i> ^steps 0)}"
    )
    lines += _deep_work(r)
    if r.random() < 0.5:
        lines.append(
            "sp {sub*gds (state <s> ^superstate.count <c> ^target <i>) --> (<s> ^seen <c>)}"
        )
    if r.random() < 0.5:
        lines.append(
            f"sp {{top*mark (state <s> ^superstate nil ^count > {r.randint(0, 2)}"
            " ^box.item <i>) (<i> ^w <w> < 5) --> (<i> ^small (- 5 <w>))}"
        )
    lines += [
        "sp {snc (state <s> ^impasse no-change ^attribute state ^superstate <ss>)"
        " (<ss> ^count <c>) --> (<ss> ^count (+ <c> 1) <c> -)}",
        f"sp {{done (state <s> ^superstate nil ^count >= {limit})"
        " --> (write |done | (crlf)) (halt)}",
    ]
    return "\n".join(lines) + "\n"


def _deep_work(r: random.Random) -> list[str]:
    """How the substate works its operator out."""
    mode = r.randrange(4)
    if mode == 0:  # an o-supported result at once
        return [
            "sp {sub*p (state <s> ^target <i> ^steps 0) --> (<s> ^operator <o> +)"
            " (<o> ^name finish)}",
            "sp {sub*a (state <s> ^operator.name finish ^target <i> ^superstate <ss>)"
            " (<ss> ^count <c>) (<i> ^w <w>) --> (<ss> ^count (+ <c> 1) <c> -)"
            f" (<i> ^done yes) (write |fin | (* <w> {r.randint(2, 5)}) (crlf))}}",
        ]
    if mode == 1:  # a local counter, then the result
        steps = r.randint(1, 3)
        return [
            f"sp {{sub*p (state <s> ^steps <n> < {steps}) --> (<s> ^operator <o> +)"
            " (<o> ^name step)}",
            "sp {sub*a (state <s> ^operator.name step ^steps <n>)"
            " --> (<s> ^steps <n> - (+ <n> 1))}",
            f"sp {{sub*p2 (state <s> ^steps {steps}) --> (<s> ^operator <o> +)"
            " (<o> ^name finish)}",
            "sp {sub*a2 (state <s> ^operator.name finish ^superstate <ss> ^target <i>)"
            " (<ss> ^count <c>) (<i> ^tag <t>) --> (<ss> ^count (+ <c> 1) <c> -)"
            " (write (concat |done-| <t>) (crlf))}",
        ]
    if mode == 2:  # an i-supported result that the top applies
        return [
            "sp {sub*res (state <s> ^target <i> ^superstate <ss>) (<i> ^w <w>)"
            " --> (<ss> ^suggest (+ <w> 10))}",
            "sp {top*use (state <s> ^superstate nil ^operator <o> ^suggest <x> ^count <c>)"
            " (<o> ^name work) --> (<s> ^count (+ <c> 1) <c> -) (write |use | <x> (crlf))}",
        ]
    return [  # a third level whose one firing makes results one and two levels up
        "sp {sub*p (state <s> ^target <i> -^went) --> (<s> ^operator <o> +)"
        " (<o> ^name deeper)}",
        "sp {deep*a (state <s> ^superstate.operator.name deeper ^superstate <mid>)"
        " (<mid> ^superstate <top>) (<top> ^count <c>) --> (<top> ^count (+ <c> 1) <c> -)"
        " (<mid> ^went yes)}",
    ]


PREFERENCES = ["+", "+", "+", "+ =", "+ = 0.4", "+ = 0.9", "+ >", "+ <", "+ !", "+ ~", "+ -",
               "+ > =", "+ < ="]


def preference_agent(seed: int) -> str:
    """The rule file of one random preference agent."""
    r = random.Random(seed)
    lines = [f"indifferent-selection --{r.choice(['first', 'last'])}"]
    if r.random() < 0.3:
        lines.append(f"numeric-indifferent-mode --{r.choice(['sum', 'avg'])}")
    count = r.randint(2, 5)
    lines += [
        "sp {init (state <s> ^superstate nil -^count) --> (<s> ^operator <o> + >)"
        " (<o> ^name init)}",
        "sp {init*a (state <s> ^operator.name init) --> (<s> ^count 0 ^phase a)}",
    ]
    for k in range(count):
        pref = r.choice(PREFERENCES)
        phase = r.choice(["a", "b", "<p>"])
        lines.append(
            f"sp {{prop{k} (state <s> ^superstate nil ^count <c> < 6 ^phase {phase})"
            f" --> (<s> ^operator <o> {pref}) (<o> ^name op{k} ^v {r.randint(0, 4)})}}"
        )
    for k in range(r.randint(0, 4)):
        x, y = r.sample(range(count), 2)
        relation = r.choice([">", "<", "=", "= 0.2"])
        lines.append(
            f"sp {{bet{k} (state <s> ^operator <x> + ^operator <y> +) (<x> ^name op{x})"
            f" (<y> ^name op{y}) --> (<s> ^operator <x> {relation} <y>)}}"
        )
    if r.random() < 0.5:
        lines.append(
            "sp {bv (state <s> ^operator <x> + ^operator <y> +) (<x> ^v <a>) (<y> ^v > <a>)"
            " --> (<s> ^operator <y> > <x>)}"
        )
    lines += [
        "sp {apply (state <s> ^operator <o> ^count <c> ^phase <p>) (<o> ^name <n> ^v <v>)"
        " --> (<s> ^count (+ <c> 1) <c> -) (write <n> | | <v> (crlf))}",
        "sp {flip (state <s> ^operator <o> ^phase a) (<o> ^v > 2) --> (<s> ^phase a - b)}",
        "sp {flop (state <s> ^operator <o> ^phase b) (<o> ^v < 2) --> (<s> ^phase b - a)}",
    ]
    for kind in ("tie", "conflict", "constraint-failure"):
        lines += _impasse_rule(r, kind)
    lines += [
        "sp {snc (state <s> ^impasse no-change ^attribute state ^superstate <ss>)"
        " (<ss> ^count <c>) --> (<ss> ^count (+ <c> 1) <c> -) (write |snc| (crlf))}",
        "sp {i*any (state <s> ^impasse <i> ^superstate.count <c> ^choices <ch>)"
        " --> (write |impasse | <i> | | <ch> (crlf))}",
        "sp {done (state <s> ^superstate nil ^count >= 6) --> (write |done| (crlf)) (halt)}",
    ]
    return "\n".join(lines) + "\n"


def _impasse_rule(r: random.Random, kind: str) -> list[str]:
    action = r.choice(["best", "reject", "none", "require"])
    head = f"sp {{i*{kind} (state <s> ^impasse {kind} ^superstate <ss> ^item <i>"
    if action == "best":
        return [head + " -^item {<j> > <i>}) --> (<ss> ^operator <i> >)}"]
    if action == "reject":
        return [head + ") (<i> ^v < 2) --> (<ss> ^operator <i> -)}"]
    if action == "require":
        return [head + ") (<i> ^v 3) --> (<ss> ^operator <i> !)}"]
    return []


VALUES = ["1", "2", "3", "1.5", "2.0", "|x|", "|y z|", "a", "b", "-1", "0"]
RELATIONS = ["<", ">", "<=", ">=", "<>", "<=>", ""]
ATTRIBUTES = ["p", "q", "r"]


def matching_agent(seed: int) -> str:
    """The rule file of one random matching agent."""
    r = random.Random(seed)
    count = r.randint(3, 6)
    body = []
    for i in range(count):
        parts = [f"^{r.choice(ATTRIBUTES)} {r.choice(VALUES)}" for _ in range(r.randint(1, 3))]
        if i and r.random() < 0.4:
            parts.append(f"^next <x{i - 1}>")
        body.append(f"(<x{i}> {' '.join(parts)})")
    objects = " ".join(f"<x{i}>" for i in range(count))
    lines = [
        "sp {init (state <s> ^superstate nil -^stage) --> (<s> ^operator <o> + >)"
        " (<o> ^name init)}",
        f"sp {{init*a (state <s> ^operator.name init) --> (<s> ^stage 0 ^obj {objects})"
        f" {' '.join(body)}}}",
    ]
    lines += [_matching_rule(r, k) for k in range(r.randint(2, 6))]
    for k in range(r.randint(1, 3)):
        lines += _matching_operator(r, k)
    lines += [
        "sp {tie (state <s> ^impasse << tie conflict >> ^superstate <ss> ^item <i>"
        " -^item {<j> > <i>}) --> (<ss> ^operator <i> >)}",
        "sp {snc (state <s> ^impasse no-change ^superstate <ss>) (<ss> ^stage <g>)"
        " --> (<ss> ^stage (+ <g> 1) <g> -)}",
        "sp {done (state <s> ^superstate nil ^stage >= 4) --> (write |done| (crlf)) (halt)}",
    ]
    return "indifferent-selection --first\n" + "\n".join(lines) + "\n"


def _matching_rule(r: random.Random, k: int) -> str:
    kind = r.randrange(8)
    a1, a2 = r.choice(ATTRIBUTES), r.choice(ATTRIBUTES)
    relation, value = r.choice(RELATIONS), r.choice(VALUES)
    test = f"{{<v> {relation} {value}}}" if relation else "<v>"
    head = f"sp {{e{k}x (state <s> ^obj <x>)"
    if kind == 0:
        return f"{head} (<x> ^{a1} {test}) --> (<s> ^found{k} <v>)}}"
    if kind == 1:
        return f"{head} (<x> ^<att> {test}) --> (<s> ^attr{k} <att>)}}"
    if kind == 2:
        return f"{head} (<x> ^next.{a1} <v>) --> (<x> ^prev{k} <v>)}}"
    if kind == 3:
        return (f"{head} (<x> ^{a1} <v> ^{a2} {{<w> <> <v>}})"
                f" --> (<s> ^pairs{k} (concat <v> |-| <w>))}}")
    if kind == 4:
        return f"{head} -(<x> ^{a1} {value}) --> (<s> ^lacks{k} <x>)}}"
    if kind == 5:
        return f"{head} (<x> ^{a1} << {' '.join(r.sample(VALUES, 3))} >>) --> (<s> ^in{k} <x>)}}"
    if kind == 6:
        return (f"sp {{e{k}x (state <s> ^obj <x> ^obj {{<y> <> <x>}}) (<x> ^{a1} <v>)"
                f" (<y> ^{a1} <v>) --> (<s> ^same{k} <v>)}}")
    return (f"{head} (<x> ^{a1} <v>) -{{(<s> ^obj <y>) (<y> ^{a1} > <v>)}}"
            f" --> (<s> ^top{k} <v>)}}")


def _matching_operator(r: random.Random, k: int) -> list[str]:
    attr = r.choice(ATTRIBUTES)
    effect = r.choice([
        f"(<x> ^{attr} <v> - (* <v> 2))",
        f"(<x> ^{attr} <v> - |changed|)",
        "(<s> ^obj <x> -)",
        f"(<x> ^{attr} (+ <v> 0.5))",
        f"(<x> ^{attr} (div 7 2) (mod 7 3) (abs -2) (int 2.7) (float 3))",
    ])
    return [
        f"sp {{op{k}x (state <s> ^superstate nil ^stage <g> < 4 ^obj <x>)"
        f" (<x> ^{attr} {{<v> > 0}}) --> (<s> ^operator <o> + =)"
        f" (<o> ^name op{k}x ^x <x> ^v <v>)}}",
        f"sp {{ap{k}x (state <s> ^operator <o> ^stage <g>) (<o> ^name op{k}x ^x <x> ^v <v>)"
        f" (<x> ^{attr} <v>) --> (<s> ^stage (+ <g> 1) <g> -) {effect}"
        f" (write |op{k} | <v> (crlf))}}",
    ]


def _agree(path, decisions: int) -> None:
    theirs = run_kernel(path, decisions=decisions)
    ours = run_ours(path, decisions=decisions)
    assert "rror" not in theirs.trace
    assert ours.halted == theirs.halted
    assert ours.operators == theirs.operators
    assert ours.output == theirs.output
    keys = ("decisions", "production_firings", "elaboration_cycles", "wme_changes", "wm_size")
    assert [getattr(ours, k) for k in keys] == [getattr(theirs, k) for k in keys]
    assert sorted(ours.wm) == sorted(theirs.wm)


@pytest.mark.parametrize("seed", range(64))
def test_world_agent_behaves_as_in_the_kernel(seed: int, tmp_path) -> None:
    path = tmp_path / "world.soar"
    path.write_text(world_agent(seed))
    _agree(path, 40)


@pytest.mark.parametrize("seed", range(48))
def test_deep_agent_behaves_as_in_the_kernel(seed: int, tmp_path) -> None:
    path = tmp_path / "deep.soar"
    path.write_text(deep_agent(seed))
    _agree(path, 40)


@pytest.mark.parametrize("seed", range(48))
def test_preference_agent_behaves_as_in_the_kernel(seed: int, tmp_path) -> None:
    path = tmp_path / "preferences.soar"
    path.write_text(preference_agent(seed))
    _agree(path, 40)


# Seeds whose firing or retraction order still differs from the kernel's (the operators
# chosen then differ): see the note of issue 2.
MATCHING_ORDER: set[int] = set()  # 8 and 21 agree since joins keep their link (_join_link)


@pytest.mark.parametrize(
    "seed",
    [pytest.param(seed, marks=pytest.mark.xfail(reason="firing order", strict=True))
     if seed in MATCHING_ORDER else seed for seed in range(48)],
)
def test_matching_agent_behaves_as_in_the_kernel(seed: int, tmp_path) -> None:
    path = tmp_path / "matching.soar"
    path.write_text(matching_agent(seed))
    _agree(path, 40)
