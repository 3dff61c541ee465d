"""Duplicate productions: the kernel refuses a rule that repeats a loaded one under another
name ("Ignoring b because it is a duplicate of a"). Every verdict below was measured with
soar_sml 9.6; the last test asks the kernel again."""

from __future__ import annotations

import io

import pytest

from sann.soar import Agent

# (rule a, rule b, does the kernel refuse b as a duplicate of a?)
CASES = [
    ("(state <s> ^superstate nil) --> (<s> ^x 1)", "(state <s> ^superstate nil) --> (<s> ^x 1)",
     True),
    ("(state <s> ^superstate nil) --> (<s> ^x 1)", "(state <t> ^superstate nil) --> (<t> ^x 1)",
     True),
    ("(state <s> ^superstate nil ^y 2) --> (<s> ^x 1)",
     "(state <s> ^y 2 ^superstate nil) --> (<s> ^x 1)", True),
    ("(state <s> ^superstate nil) --> (<s> ^x 1)", "(state <s> ^superstate nil) --> (<s> ^x 2)",
     False),
    ("(state <s> ^superstate nil) --> (<s> ^x 1 ^z 2)",
     "(state <s> ^superstate nil) --> (<s> ^z 2 ^x 1)", False),
    ("(state <s> ^superstate nil) --> (<s> ^x <n>)",
     "(state <s> ^superstate nil) --> (<s> ^x <m>)", True),
    ("\"doc\" (state <s> ^superstate nil) --> (<s> ^x 1)",
     ":o-support (state <s> ^superstate nil) --> (<s> ^x 1)", True),
    ("(state <s> ^superstate nil -^q) --> (<s> ^x 1)",
     "(state <s> -^q ^superstate nil) --> (<s> ^x 1)", True),
    ("(state <s> ^superstate nil) -{(<s> ^p <x>) (<x> ^v 1)} --> (<s> ^x 1)",
     "(state <s> ^superstate nil) -{(<s> ^p <y>) (<y> ^v 1)} --> (<s> ^x 1)", True),
    ("(state <s> ^superstate nil ^v << a b >>) --> (<s> ^x 1)",
     "(state <s> ^superstate nil ^v << b a >>) --> (<s> ^x 1)", False),
    ("(state <s> ^superstate nil) --> (<s> ^x 1)",
     "(impasse <s> ^superstate nil) --> (<s> ^x 1)", False),
    ("(state <s> ^superstate nil ^v { <x> > 2 }) --> (<s> ^x <x>)",
     "(state <s> ^superstate nil ^v { > 2 <y> }) --> (<s> ^x <y>)", True),
    ("(state <s> ^superstate nil ^v <x> ^w <y>) --> (<s> ^x <x>)",
     "(state <s> ^superstate nil ^v <y> ^w <x>) --> (<s> ^x <x>)", False),
    ("(state <s> ^superstate nil) --> (<s> ^operator <o> + >) (<o> ^name a)",
     "(state <s> ^superstate nil) --> (<s> ^operator <o> > +) (<o> ^name a)", False),
]


def _text(a: str, b: str) -> str:
    return f"sp {{a {a}}}\nsp {{b {b}}}\n"


@pytest.mark.parametrize(("a", "b", "duplicate"), CASES)
def test_duplicates_are_refused_as_by_the_kernel(a: str, b: str, duplicate: bool) -> None:
    out = io.StringIO()
    agent = Agent(out=out)
    agent.load(_text(a, b))
    loaded = sorted(info.production.name for info in agent._productions.values())
    assert loaded == (["a"] if duplicate else ["a", "b"])
    said = "Ignoring b because it is a duplicate of a" in out.getvalue()
    assert said == duplicate


def test_an_excised_rule_no_longer_blocks_its_duplicate() -> None:
    agent = Agent(out=io.StringIO())
    agent.load(_text(*CASES[0][:2]))
    agent.excise("a")
    agent.load("sp {c (state <s> ^superstate nil) --> (<s> ^x 1)}")
    assert sorted(agent._productions) == ["c"]


def test_the_kernel_still_says_so(kernel, tmp_path) -> None:
    for n, (a, b, duplicate) in enumerate(CASES[:5]):
        path = tmp_path / f"dup{n}.soar"
        path.write_text(_text(a, b))
        with kernel.KernelAgent() as ka:
            ka.agent.ExecuteCommandLine(f"source {{{path}}}")
            names = sorted(ka.agent.ExecuteCommandLine("print").split())
        assert names == (["a"] if duplicate else ["a", "b"])
