"""The RHS function ``deep-copy``: its copies are preferences of the firing rule.

Expected texts were printed by the real kernel (soar_sml 9.6); the tests at the end run the
same rules in the kernel and in our engine and compare output and working memory live,
timetags and identifier names included.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import pytest

from sann.soar.agent import Agent
from sann.soar.rhs import FUNCTIONS
from sann.soar.rhs.deep_copy import DEEP_COPY_NOT_ID
from sann.soar.trace import trace_wme

# Shared substructure (^y and ^z lead to one identifier) and a cycle (^back), several values
# in one slot, a state copied whole (with its io link and an input WME), a constant argument.
SHARED = """
sp {build (state <s> ^superstate nil) --> (<s> ^orig <b>)
    (<b> ^x 1 ^x 2 ^x 3 ^y <c> ^z <c> ^name foo) (<c> ^back <b> ^w 2.5 ^t |a b|)}
sp {copy (state <s> ^orig <b>) -->
    (<s> ^other <n> ^copy (deep-copy <b>) ^third <m>)
    (<n> ^k 1 ^s (deep-copy <s>) ^c (deep-copy 5))}
sp {show (state <s> ^copy <d>) (<d> ^y <c>) --> (write |copy | <d> | | <c> (crlf))}
"""

# An o-supported copy of a state with its selected operator, one made later from a
# structure changed in between, and i-supported copies that come and go with their rules.
SUPPORT = """
sp {init (state <s> ^superstate nil) --> (<s> ^orig <b>) (<b> ^x 1 ^y <c>) (<c> ^z 2 ^up <b>)}
sp {propose (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name go)}
sp {apply (state <s> ^operator <o> ^orig <b>) (<o> ^name go) -->
    (<s> ^done yes ^ocopy (deep-copy <b>))}
sp {copy-selected (state <s> ^operator <o>) --> (<s> ^selcopy (deep-copy <s>))}
sp {more (state <s> ^done yes ^orig <b>) --> (<b> ^x 5 ^w 1)}
sp {copy-later (state <s> ^done yes ^orig <b>) (<b> ^w 1) --> (<s> ^late (deep-copy <b>))}
"""

RETRACT = """
sp {propose (state <s> ^superstate nil -^phase) --> (<s> ^operator <o> + =) (<o> ^name start)}
sp {apply (state <s> ^operator.name start) -->
    (<s> ^phase 1 ^orig <b>) (<b> ^a 1 ^b <c>) (<c> ^v 2)}
sp {propose2 (state <s> ^phase 1) --> (<s> ^operator <o> +) (<o> ^name stop)}
sp {apply2 (state <s> ^operator.name stop ^phase 1) --> (<s> ^phase 1 - ^phase 2)}
sp {copy (state <s> ^phase 1 ^orig <b>) --> (<s> ^copy (deep-copy <b>))}
sp {seen (state <s> ^copy <d>) (<d> ^b.v <v>) --> (write |seen | <d> | | <v> (crlf))}
sp {gone (state <s> ^phase 2 -^copy) --> (write |gone| (crlf)) (halt)}
"""


def run(text: str, decisions: int, item: bool = False) -> tuple[Agent, str]:
    out = io.StringIO()
    agent = Agent(out=out)
    agent.load(text)
    if item:
        agent.input_link.add("item").add("n", 3)
    agent.run(decisions)
    return agent, out.getvalue()


def words(text: str) -> list[str]:
    """Printed text without its line breaks (the kernel breaks ``print D2`` here before 80
    columns, our printer at them: a difference of ``print``, not of the copy)."""
    return text.split()


def test_a_constant_is_not_copied() -> None:
    assert FUNCTIONS["deep-copy"](None, [5]) == DEEP_COPY_NOT_ID  # type: ignore[arg-type]
    agent, _ = run(SHARED, 1)
    [k] = [w for w in agent.wmes() if w.attr == "c"]
    assert k.value == "*symbol not id*"


def test_shared_structure_and_cycles_are_copied_once() -> None:
    agent, out = run(SHARED, 1, item=True)
    assert out == "copy D1 C4\n"
    # print --depth 3 D1 in the kernel
    assert agent.print("D1", 3) == (
        "(D1 ^name foo ^x 1 ^x 2 ^x 3 ^y C4 ^z C4)\n  (C4 ^back D1 ^t |a b| ^w 2.500000)\n"
    )


def test_a_state_copy_has_its_links_but_not_type_superstate_or_proposals() -> None:
    agent, _ = run(SUPPORT, 2)
    # print D2 in the kernel, after O1 was selected and applied
    assert words(agent.print("D2", 1)) == words(
        "(D2 ^epmem E2 ^io I4 ^operator O2 ^orig B2 ^reward-link R6\n       ^smem L2)\n"
    )


def test_copies_take_the_firing_support() -> None:
    """copy-selected fires as an o-assertion: its copy stays when O1 is gone."""
    agent, _ = run(SUPPORT, 3)
    # print D2 and print s1 in the kernel
    assert words(agent.print("D2", 1)) == words(
        "(D2 ^epmem E2 ^io I4 ^operator O2 ^orig B2 ^reward-link R6\n       ^smem L2)\n"
    )
    assert agent.print("S1", 1) == (
        "(S1 ^done yes ^epmem E1 ^io I1 ^late D3 ^ocopy D1 ^orig B1 ^reward-link R1\n"
        "       ^selcopy D2 ^smem L1 ^superstate nil ^type state)\n"
    )


def test_i_supported_copies_retract_with_their_rule() -> None:
    agent, out = run(RETRACT, 10)
    assert out == "seen D1 2\ngone\n" "\nSystem halted.\nInterrupt received.This Agent halted."
    assert not [w for w in agent.wmes() if w.id.name == "D1"]


# ------------------------------------------------------------- against the kernel

_INTERNAL = re.compile(r"^\s*(\(\d+: .*\))\s*$")


def _kernel_memory(kernel, text: str, decisions: int, item: bool) -> tuple[str, list[str]]:
    with kernel.KernelAgent() as ka:
        for rule in text.strip().split("\nsp "):
            ka.cmd(rule if rule.startswith("sp ") else "sp " + rule)
        if item:
            ka.add_inputs([("item", (("n", 3),))])
        ka.cmd("watch 0")
        ka.take_log()
        ka.cmd(f"run {decisions}")
        written = ka.take_log()
        lines = ka.cmd("print --internal --depth 50 s1").splitlines()
    return written, sorted(m.group(1) for line in lines if (m := _INTERNAL.match(line)))


@pytest.mark.parametrize(
    ("text", "decisions", "item"),
    [(SHARED, 1, True), (SUPPORT, 1, False), (SUPPORT, 2, False), (SUPPORT, 6, False),
     (RETRACT, 10, False)],
)  # fmt: skip
def test_copies_agree_with_the_kernel(kernel, text: str, decisions: int, item: bool) -> None:
    """Same WMEs, timetags and identifier names (the top state's structure: the kernel's
    ``print s1`` does not reach substates), same output."""
    written, theirs = _kernel_memory(kernel, text, decisions, item)
    agent, out = run(text, decisions, item)
    assert "Error" not in written
    assert out == written
    reached = set(theirs)
    ours = sorted(trace_wme(w).strip() for w in agent.wmes())
    assert [w for w in ours if w in reached] == theirs
    assert sum(1 for _ in agent.wmes()) >= len(theirs)


def test_differential_run_agrees(kernel, tmp_path: Path) -> None:
    path = tmp_path / "deep_copy.soar"
    path.write_text(SHARED)
    theirs, ours = kernel.run_kernel(path, decisions=3), kernel.run_ours(path, decisions=3)
    assert ours.output == theirs.output
    assert ours.wm == theirs.wm
    assert (ours.production_firings, ours.wm_size) == (theirs.production_firings, theirs.wm_size)
